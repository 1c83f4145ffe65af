"""One warm fork server per user and installation, shared by every `openbricks sim run`.

A run's child pays a few tenths of a second before the program's first touch of the robot can go on:
importing numpy and MuJoCo, which no trimming removes. A fork server (fork_server.py) pays that once.
`sim run` asks the published one, if there is one, to fork its contained child; if there is none it
forks its own child as before and, once its run is over, starts one in the background for the runs
after it. The server ends after IDLE_S without a request, or when its socket is taken away.

- Where: a datagram socket in `sim/` of openbricks' runtime folder (`$XDG_RUNTIME_DIR/openbricks`,
  else `openbricks-UID` in the temporary folder), a folder of the user's own with no access for anyone
  else; otherwise there are no warm runs.
- Which: the socket's name is a fingerprint of the interpreter, its import path and the newest source
  file of the three packages and the native extensions, so an upgrade or an edited checkout never
  gets a server with the old code in it: it gets a new server.
- What the child gets: the requesting command's working folder and environment, its standard streams
  and result pipe, and the same fence as any child (limits.contain, the hub's imports), its own doing.

OPENBRICKS_SIM_WARM=0 turns it off: every run starts cold, and none starts a server.
"""

from __future__ import annotations

import os
import socket
import stat
import subprocess
import sys
import time
import zlib

from .fork_server import ForkServerClient, serve, warm_up

IDLE_S = 600.0  # a server nobody asked for this long ends
DISABLE_ENV = "OPENBRICKS_SIM_WARM"
RUNTIME_DIR_ENV = "OPENBRICKS_RUNTIME_DIR"  # the console's too (openbricks_server.paths)
_SOCKET_PATH_MAX = 100  # sockaddr_un's path is 108 bytes on Linux, 104 on macOS
_SOURCE_PACKAGES = ("openbricks", "openbricks_sim", "openbricks_server")
_NATIVE_MODULES = ("openbricks_native", "openbricks_mjcontrol", "openbricks_pycost")
_SKIPPED_FOLDERS = {"__pycache__", "static", "node_modules"}


def enabled() -> bool:
    return os.environ.get(DISABLE_ENV, "1") != "0" and hasattr(os, "fork")


def socket_path() -> str | None:
    """This installation's server socket for this user, or None where warm runs cannot be had safely."""
    folder = _private_folder()
    if folder is None:
        return None
    path = os.path.join(folder, f"sim-{_fingerprint()}.sock")
    return path if len(path) <= _SOCKET_PATH_MAX else None


def connect() -> ForkServerClient | None:
    """A client of the published server, or None (none is running, warm runs are off or unsafe here)."""
    if not enabled():
        return None
    path = socket_path()
    if path is None:
        return None
    control = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    try:
        control.connect(path)
    except OSError:  # no server (or a stale socket of one that ended): this run starts cold
        control.close()
        return None
    return ForkServerClient(control, dict(os.environ), os.getcwd())


def start_in_background() -> None:
    """Start this installation's server for the runs to come (a no-op if one is starting or running)."""
    if not enabled():
        return
    path = socket_path()
    if path is None:
        return
    subprocess.Popen(
        [sys.executable, "-P", "-m", "openbricks_sim.fork_server", "--publish", path],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        cwd="/",  # never keeps a folder of the user's busy
        start_new_session=True,  # no terminal's Ctrl-C or hang-up reaches it
    )


def publish_and_serve(path: str) -> int:
    """The server's side: warm up, put the socket at `path` in one step, serve until idle or replaced."""
    import fcntl

    lock = open(path + ".lock", "a+", encoding="utf-8")  # noqa: SIM115 - held for the server's life
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:  # another server of this installation is starting or running
        return 0
    lock.truncate(0)
    lock.write(f"{os.getpid()}\n")  # who holds it, for whoever wants to stop it
    lock.flush()
    warm_up()
    control = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    staging = f"{path}.{os.getpid()}"
    control.bind(staging)
    os.chmod(staging, 0o600)
    os.replace(staging, path)  # clients find a ready server or none, never one still importing
    inode = os.stat(path).st_ino
    last_busy = [time.monotonic()]

    def published(busy: bool) -> bool:
        now = time.monotonic()
        if busy:
            last_busy[0] = now
        try:
            ours = os.stat(path).st_ino == inode
        except OSError:
            return False
        if ours and now - last_busy[0] >= IDLE_S:
            os.unlink(path)  # no new client from here on; serve() takes what was already sent
            return False
        return ours

    try:
        return serve(control.detach(), published)
    finally:
        try:
            if os.stat(path).st_ino == inode:
                os.unlink(path)
        except OSError:
            pass


def server_pid(path: str) -> int | None:
    """The pid of the server publishing at `path` (from its lock file), if one does."""
    try:
        with open(path + ".lock", encoding="utf-8") as f:
            return int(f.read().strip() or 0) or None
    except (OSError, ValueError):
        return None


def _private_folder() -> str | None:
    """`sim/` in openbricks' runtime folder (OPENBRICKS_RUNTIME_DIR, else $XDG_RUNTIME_DIR/openbricks as
    the console has it, else openbricks-UID in the temporary folder), made ours alone; None if it
    cannot be. Computed here rather than by platformdirs, whose import would cost every run more
    than a warm start saves a short one."""
    root = os.environ.get(RUNTIME_DIR_ENV)
    if not root:
        xdg = os.environ.get("XDG_RUNTIME_DIR", "").strip()
        if xdg:
            root = os.path.join(xdg, "openbricks")
        else:
            root = os.path.join(os.environ.get("TMPDIR") or "/tmp", f"openbricks-{os.getuid()}")
    folder = os.path.join(root, "sim")
    try:
        os.makedirs(root, exist_ok=True)
        os.mkdir(folder, 0o700)
    except FileExistsError:
        pass
    except OSError:
        return None
    # Not ours alone (the folder, or the one holding it, which could swap it): another user could
    # hand our runs a server of theirs.
    outer, inner = os.lstat(root), os.lstat(folder)
    if not (stat.S_ISDIR(outer.st_mode) and stat.S_ISDIR(inner.st_mode)):
        return None
    if outer.st_uid != os.getuid() or inner.st_uid != os.getuid() or inner.st_mode & 0o077:
        return None
    return folder


def _fingerprint() -> str:
    """Names the code a server would run: the interpreter, the import path, the newest source file."""
    import importlib.util

    newest = 0
    for name in _SOURCE_PACKAGES:
        spec = importlib.util.find_spec(name)
        if spec is not None and spec.submodule_search_locations:
            for folder in spec.submodule_search_locations:
                newest = max(newest, _newest_py_ns(folder))
    for name in _NATIVE_MODULES:
        spec = importlib.util.find_spec(name)
        if spec is not None and spec.origin:
            newest = max(newest, os.stat(spec.origin).st_mtime_ns)
    text = "\0".join([sys.executable, sys.version, *sys.path, str(newest)]).encode("utf-8", "surrogatepass")
    return f"{zlib.crc32(text):08x}{zlib.adler32(text):08x}"


def _newest_py_ns(folder: str) -> int:
    newest = 0
    with os.scandir(folder) as entries:
        for entry in entries:
            if entry.is_dir(follow_symlinks=False):
                if entry.name not in _SKIPPED_FOLDERS:
                    newest = max(newest, _newest_py_ns(entry.path))
            elif entry.name.endswith(".py"):
                newest = max(newest, entry.stat().st_mtime_ns)
    return newest
