"""The running console's address and a local operator token, in a file only this user can read.

`openbricks console` writes it once it serves and removes it when it stops; the CLI reads it to go through
the daemon (which owns the hub links) instead of opening links of its own. Import-light on purpose: the
CLI reads it on every command.
"""

from __future__ import annotations

import json
import os
from dataclasses import asdict, dataclass
from pathlib import Path

FILENAME = "console.json"


@dataclass(frozen=True)
class RuntimeInfo:
    url: str  # base URL, e.g. http://127.0.0.1:8765
    token: str  # an operator token valid while this daemon runs
    pid: int
    data_dir: str

    @property
    def sign_in_url(self) -> str:
        return f"{self.url}/?token={self.token}"


def path() -> Path:
    from openbricks_server import paths

    return paths.runtime_dir() / FILENAME


def write(info: RuntimeInfo) -> Path:
    """Write atomically with mode 0600 (the folder 0700): the token is an operator's key."""
    target = path()
    target.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
    temporary = target.with_name(f".{FILENAME}.{os.getpid()}")
    fd = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w") as handle:
        json.dump(asdict(info), handle)
    os.chmod(temporary, 0o600)
    os.replace(temporary, target)
    return target


def read() -> RuntimeInfo | None:
    """The running console, or None (no file, an unreadable one, or one left by a process that is gone)."""
    try:
        data = json.loads(path().read_text())
        info = RuntimeInfo(
            url=str(data["url"]),
            token=str(data["token"]),
            pid=int(data["pid"]),
            data_dir=str(data["data_dir"]),
        )
    except (OSError, ValueError, KeyError, TypeError):
        return None
    return info if _alive(info.pid) else None


def remove(pid: int) -> None:
    """Remove the file if it is `pid`'s (a second console's file is left alone)."""
    try:
        data = json.loads(path().read_text())
        if int(data.get("pid", -1)) == pid:
            path().unlink()
    except (OSError, ValueError, TypeError, AttributeError):
        pass


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True
