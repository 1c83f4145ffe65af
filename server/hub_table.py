"""What `openbricks list` prints, the same whether the CLI scanned itself or asked the console.

As text: one aligned row per hub. With --json: one JSON array of objects with stable keys, for scripts
(docs/cli.md lists them): `name`, `kind` ("virtual", "hub": offers the REPL service, "ble": another
Bluetooth device), `address` (a virtual hub's pty or console id, a Bluetooth address) and `status`
("idle", "running a program", a signal strength such as "-61 dBm", ...).
"""

from __future__ import annotations

import json
import sys
from typing import NamedTuple


class HubRow(NamedTuple):
    name: str
    kind: str
    address: str
    status: str


def print_hubs(rows: list[HubRow], as_json: bool, none_found: str) -> None:
    """The rows on stdout; with none, `none_found` on stderr (and `[]` on stdout for --json)."""
    if as_json:
        print(json.dumps([row._asdict() for row in rows]))
    if not rows:
        print(none_found, file=sys.stderr)
        return
    if as_json:
        return
    widths = [max(len(row[i]) for row in rows) for i in range(3)]
    for row in rows:
        print(f"{row.name:<{widths[0]}}  {row.kind:<{widths[1]}}  {row.address:<{widths[2]}}  {row.status}")
