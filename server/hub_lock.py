"""A per-hub lock so two host processes never interleave their traffic on one hub.

A hub runs one raw-REPL conversation at a time: a second `openbricks run` that connected while the first
was streaming would interrupt its program and mix both outputs. Every command that talks to a hub (and
the daemon, which takes the same lock while it owns a hub's link) holds ``hub_lock(name)`` for the whole
conversation. The lock is an OS file lock, released by the kernel if its holder dies, so a crashed
command never leaves a hub locked.
"""

from __future__ import annotations

import re
from contextlib import contextmanager

from openbricks_server.errors import CliError
from openbricks_server.paths import locks_dir

_UNSAFE = re.compile(r"[^A-Za-z0-9._-]")


class HubBusyError(CliError):
    """Another process holds the hub's lock."""


def lock_path(hub_name: str):
    """The lock file of `hub_name`; names that differ only in characters unsafe for files stay apart."""
    safe = _UNSAFE.sub(lambda m: f"%{ord(m.group()):02x}", hub_name)
    return locks_dir() / f"{safe}.lock"


@contextmanager
def hub_lock(hub_name: str, wait_s: float = 0.0):
    """Hold `hub_name`'s lock for the block; raise HubBusyError if it is not free within `wait_s`."""
    from filelock import FileLock, Timeout

    lock = FileLock(lock_path(hub_name), thread_local=False)
    try:
        lock.acquire(timeout=wait_s)
    except Timeout:
        raise HubBusyError(
            f"hub {hub_name!r} is busy: another openbricks command (or the console) is talking to it; "
            "wait for it to finish, or stop it, then retry"
        ) from None
    try:
        yield
    finally:
        lock.release()
