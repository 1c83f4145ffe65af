"""The hub's NVS (hub name, BLE state, provenance, sensor calibration) kept in a file on the host.

The simulator's `esp32.NVS` works on a dict {namespace: {key: int | bytes}} and publishes a
namespace by assigning it on commit(); this dict writes itself to disk on that assignment, so a
committed value survives the virtual hub's restart as it survives a reset on a real hub. The file
is replaced atomically: a crash mid-write leaves the previous commit.
"""

import base64
import json
import os
import tempfile

_FORMAT = 1


def _encode(value):
    if isinstance(value, int):
        return {"i32": value}
    return {"blob": base64.b64encode(bytes(value)).decode("ascii")}


def _decode(item):
    if "i32" in item:
        return int(item["i32"])
    return base64.b64decode(item["blob"])


class PersistentNVS(dict):
    """{namespace: {key: value}} that saves itself to `path` whenever a namespace is committed."""

    def __init__(self, path):
        super().__init__()
        self.path = os.fspath(path)
        try:
            with open(self.path, encoding="utf-8") as f:
                stored = json.load(f)
        except FileNotFoundError:
            stored = {}
        except (OSError, ValueError) as exc:
            raise ValueError(
                f"the virtual hub's NVS file {self.path} is unreadable ({exc}); "
                "move it aside to start with an empty NVS"
            ) from None
        for namespace, items in stored.get("namespaces", {}).items():
            super().__setitem__(namespace, {key: _decode(item) for key, item in items.items()})

    def __setitem__(self, namespace, values):
        super().__setitem__(namespace, dict(values))
        self.save()

    def save(self):
        data = {
            "format": _FORMAT,
            "namespaces": {ns: {k: _encode(v) for k, v in items.items()} for ns, items in self.items()},
        }
        directory = os.path.dirname(self.path) or "."
        fd, tmp = tempfile.mkstemp(prefix=".nvs-", dir=directory)
        try:
            with os.fdopen(fd, "w", encoding="utf-8") as f:
                json.dump(data, f, indent=1, sort_keys=True)
            os.replace(tmp, self.path)
        except BaseException:
            try:
                os.remove(tmp)
            except OSError:
                pass
            raise

    def set_blob(self, namespace, key, value):
        """Write and commit one blob (what `openbricks flash --name` does on a real hub)."""
        items = dict(self.get(namespace, {}))
        items[key] = bytes(value)
        self[namespace] = items
