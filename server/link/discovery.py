"""Finding the virtual hubs running on this computer, by name.

A virtual hub (`python -m openbricks_sim.virtual_hub --pty`) lives in `<data dir>/virtual-hubs/<name>/`.
While it runs it holds an exclusive lock on `hub.lock` there (with its pid in the file), and once up
it writes `endpoint.json`: its pid, the pty its REPL is served on and the path of its control socket,
which answers `{"op": "status"}`. The socket is `control.sock` in the folder unless that path is too
long for a Unix socket (a deep data dir), when it lives in a temp folder: the record says where.

A folder whose lock is free belongs to a hub that has stopped (or crashed: the kernel drops a dead
process's lock), so it is ignored; so is a record whose pid is not the lock holder's (left by a killed
hub while a new one is still starting), and a hub serving its REPL over stdio (no pty), which others
cannot reach. A hub that predates the record is still found through `control.sock` in its folder.
"""

from __future__ import annotations

import fcntl
import json
import socket
from dataclasses import dataclass
from pathlib import Path

from openbricks_server.paths import virtual_hubs_dir
from openbricks_sim.virtual_hub.endpoint import CONTROL_SOCKET, LOCK_FILE
from openbricks_sim.virtual_hub.endpoint import FILE_NAME as ENDPOINT_FILE

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


def _lock_pid(lock_path: Path) -> int | None:
    try:
        return int(lock_path.read_text().split()[0])
    except (OSError, ValueError, IndexError):
        return None


def _control_socket(folder: Path) -> Path | None:
    """Where the hub in `folder` serves its control socket, or None while it cannot be trusted."""
    try:
        record = json.loads((folder / ENDPOINT_FILE).read_text())
    except FileNotFoundError:
        return folder / CONTROL_SOCKET  # a hub from before endpoint records
    except (OSError, ValueError):
        return None  # being replaced right now: the next look finds it whole
    if not isinstance(record, dict) or not record.get("control"):
        return None
    if record.get("pid") != _lock_pid(folder / LOCK_FILE):
        return None  # left by a hub that was killed; its successor has not written its own yet
    return Path(record["control"])


def virtual_hubs() -> list[VirtualHub]:
    """The live, reachable virtual hubs, by name."""
    root = virtual_hubs_dir()
    if not root.is_dir():
        return []
    found = []
    for folder in sorted(root.iterdir()):
        if not folder.is_dir() or not _held(folder / LOCK_FILE):
            continue
        socket_path = _control_socket(folder)
        if socket_path is None:
            continue
        try:
            status = control(socket_path, {"op": "status"})
        except (OSError, ValueError):
            continue  # starting up or shutting down: not reachable right now
        if status.get("ok") and status.get("pty"):
            found.append(
                VirtualHub(
                    str(status.get("name", folder.name)),
                    folder,
                    str(status["pty"]),
                    bool(status.get("running")),
                    socket_path,
                )
            )
    return found


def find_virtual_hub(name: str) -> VirtualHub | None:
    return next((hub for hub in virtual_hubs() if hub.name == name), None)
