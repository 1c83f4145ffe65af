"""Finding the virtual hubs running on this computer, by name.

A virtual hub (`python -m openbricks_sim.virtual_hub --pty`) lives in `<data dir>/virtual-hubs/<name>/`
and, while it runs, holds an exclusive lock on `hub.lock` there and answers `{"op": "status"}` on
`control.sock` with its name and the pty its REPL is served on. A folder whose lock is free belongs to
a hub that has stopped (or crashed: the kernel drops a dead process's lock), so it is ignored, and a
hub serving its REPL over stdio (no pty) is not reachable by others and is ignored too.
"""

from __future__ import annotations

import fcntl
import json
import socket
from dataclasses import dataclass
from pathlib import Path

from openbricks_server.paths import virtual_hubs_dir

LOCK_FILE = "hub.lock"  # openbricks_sim.virtual_hub.hub.LOCK_FILE
CONTROL_SOCKET = "control.sock"  # openbricks_sim.virtual_hub.control.SOCKET_NAME
STATUS_TIMEOUT_S = 5.0  # a hub still booting answers late; a dead one does not hold its lock


@dataclass(frozen=True)
class VirtualHub:
    name: str
    directory: Path
    pty: str
    running: bool  # a program is running on it
    control_socket: Path


def _held(lock_path: Path) -> bool:
    """True while a live process holds the hub's lock."""
    try:
        with open(lock_path, "rb") as handle:
            try:
                fcntl.flock(handle, fcntl.LOCK_SH | fcntl.LOCK_NB)
            except BlockingIOError:
                return True
            fcntl.flock(handle, fcntl.LOCK_UN)
            return False
    except OSError:
        return False


def control(socket_path: Path, request: dict, timeout_s: float = STATUS_TIMEOUT_S) -> dict:
    """One request on a virtual hub's control socket (click, press, release, status)."""
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as conn:
        conn.settimeout(timeout_s)
        conn.connect(str(socket_path))
        conn.sendall(json.dumps(request).encode() + b"\n")
        reply = b""
        while not reply.endswith(b"\n"):
            chunk = conn.recv(4096)
            if not chunk:
                break
            reply += chunk
    return json.loads(reply)


def virtual_hubs() -> list[VirtualHub]:
    """The live, reachable virtual hubs, by name."""
    root = virtual_hubs_dir()
    if not root.is_dir():
        return []
    found = []
    for folder in sorted(root.iterdir()):
        if not folder.is_dir() or not _held(folder / LOCK_FILE):
            continue
        try:
            status = control(folder / CONTROL_SOCKET, {"op": "status"})
        except (OSError, ValueError):
            continue  # starting up or shutting down: not reachable right now
        if status.get("ok") and status.get("pty"):
            found.append(
                VirtualHub(
                    str(status.get("name", folder.name)),
                    folder,
                    str(status["pty"]),
                    bool(status.get("running")),
                    folder / CONTROL_SOCKET,
                )
            )
    return found


def find_virtual_hub(name: str) -> VirtualHub | None:
    return next((hub for hub in virtual_hubs() if hub.name == name), None)
