"""The hub's flash filesystem on a host directory, as MicroPython's `os` and `open` show it.

    fs = HubFS("/home/me/.local/share/openbricks/virtual-hubs/RobotA/flash")
    os_module = fs.os_module()            # ilistdir, stat tuples, remove, rename, ... (MicroPython's)
    with fs.open("/program.py", "w") as f: ...

Hub paths are absolute from the hub's root ("/program.py", "/openbricks_logs/slot_0.log") or
relative to the hub's working directory; they never reach outside the root, whatever `..` or links
they contain. Errors are MicroPython's: a plain OSError whose args are (errno, "ENOENT"), which a
host such as mpremote recognises by the errno name in the traceback.

The flash has a capacity (a real hub's VFS partition is a couple of megabytes): a write past it
fails with ENOSPC, and statvfs() reports the space as the hub would.
"""

import errno
import io
import os
import stat
from collections import namedtuple

BLOCK_BYTES = 4096  # littlefs block size on the ESP32 ports
DEFAULT_CAPACITY_BYTES = 2 * 1024 * 1024
S_IFDIR = 0x4000  # MicroPython's ilistdir/stat type codes (no permission bits on littlefs)
S_IFREG = 0x8000
NAME_MAX = 255

UnameResult = namedtuple("uname_result", ("sysname", "nodename", "release", "version", "machine"))


def hub_error(code, detail=None):
    """OSError as MicroPython raises it: args (errno, "ENAME"), printed `[Errno 2] ENOENT`."""
    name = errno.errorcode.get(code, str(code))
    return OSError(code, name if detail is None else f"{name}: {detail}")


def _as_hub_error(exc):
    return hub_error(exc.errno if exc.errno is not None else errno.EIO)


class HubFS:
    """The flash of one hub, rooted at the host directory `root` (created if missing)."""

    def __init__(self, root, capacity_bytes=DEFAULT_CAPACITY_BYTES, uname=None):
        os.makedirs(root, exist_ok=True)
        self.root = os.path.realpath(root)
        self.capacity_bytes = int(capacity_bytes)
        self.cwd = "/"
        self._uname = uname or UnameResult("esp32", "esp32", "1.27.0", "openbricks virtual hub", "ESP32S3")
        self._used_estimate = None  # bytes in use, an upper bound between exact recounts

    def __repr__(self):
        return "<VfsLfs2>"  # how `vfs.mount()` (and so `mpremote df`) names the ESP32 port's flash

    # -- paths ---------------------------------------------------------------------------------

    def hub_path(self, path):
        """`path` as a normalised absolute hub path ("/a/b"); `..` stops at the root."""
        if isinstance(path, bytes):
            path = path.decode()
        if not isinstance(path, str):
            raise TypeError(f"a hub path is a str, not {type(path).__name__}")
        if "\x00" in path:
            raise hub_error(errno.EINVAL)
        joined = path if path.startswith("/") else self.cwd.rstrip("/") + "/" + path
        parts = []
        for part in joined.split("/"):
            if part in ("", "."):
                continue
            if part == "..":
                if parts:
                    parts.pop()
                continue
            parts.append(part)
        return "/" + "/".join(parts)

    def host_path(self, path):
        """The host file behind hub path `path`; EACCES if a link would lead outside the flash."""
        hub = self.hub_path(path)
        host = os.path.join(self.root, hub.lstrip("/")) if hub != "/" else self.root
        real = os.path.realpath(host)
        if real != self.root and not real.startswith(self.root + os.sep):
            raise hub_error(errno.EACCES, "outside the hub's flash")
        return host

    def to_hub_path(self, host_path):
        """The hub path of host file `host_path`, or None if it is not on this flash."""
        real = os.path.realpath(host_path)
        if real == self.root:
            return "/"
        if real.startswith(self.root + os.sep):
            return "/" + os.path.relpath(real, self.root).replace(os.sep, "/")
        return None

    # -- space ---------------------------------------------------------------------------------

    def used_bytes(self):
        """Flash in use: every file rounded up to whole blocks, plus a block per directory."""
        used = BLOCK_BYTES
        for top, dirs, files in os.walk(self.root):
            used += BLOCK_BYTES * len(dirs)
            for name in files:
                try:
                    size = os.lstat(os.path.join(top, name)).st_size
                except OSError:
                    continue
                used += -(-size // BLOCK_BYTES) * BLOCK_BYTES
        self._used_estimate = used
        return used

    def _reserve(self, nbytes):
        """Account for `nbytes` about to be written; ENOSPC when the flash cannot hold them."""
        if self._used_estimate is None or self._used_estimate + nbytes > self.capacity_bytes:
            self.used_bytes()  # the estimate only grows: recount exactly before refusing
            if self._used_estimate + nbytes > self.capacity_bytes:
                raise hub_error(errno.ENOSPC)
        self._used_estimate += nbytes

    # -- files ---------------------------------------------------------------------------------

    def open(self, path, mode="r", buffering=-1, encoding=None, errors=None, newline=None, closefd=True):
        """MicroPython's open(): text is UTF-8 and newlines are not translated."""
        if (
            not isinstance(mode, str)
            or not set(mode) <= set("rwaxbt+")
            or len(set(mode)) != len(mode)
            or sum(mode.count(c) for c in "rwax") != 1
        ):
            raise ValueError(f"invalid mode {mode!r}")
        host = self.host_path(path)
        raw_mode = mode.replace("b", "").replace("t", "")
        try:
            raw = _FlashFile(self, host, raw_mode)
        except OSError as exc:
            raise _as_hub_error(exc) from None
        if buffering == 0 and "b" in mode:
            return raw
        if "+" in raw_mode:
            buffered = io.BufferedRandom(raw)
        elif raw_mode[0] == "r":
            buffered = io.BufferedReader(raw)
        else:
            buffered = io.BufferedWriter(raw)
        if "b" in mode:
            return buffered
        return io.TextIOWrapper(buffered, encoding=encoding or "utf-8", errors=errors, newline="")

    # -- os --------------------------------------------------------------------------------------

    def os_module(self):
        """A module object with MicroPython's `os` API on this flash."""
        import types

        module = types.ModuleType("os", "MicroPython's os on the virtual hub's flash.")
        for name in (
            "ilistdir",
            "listdir",
            "stat",
            "statvfs",
            "remove",
            "unlink",
            "rename",
            "mkdir",
            "rmdir",
            "getcwd",
            "chdir",
            "uname",
            "sync",
            "urandom",
        ):
            setattr(module, name, getattr(self, name))
        module.sep = "/"
        return module

    def ilistdir(self, path="."):
        host = self.host_path(path)
        try:
            names = sorted(os.listdir(host))
        except OSError as exc:
            raise _as_hub_error(exc) from None
        return iter([self._entry(host, name) for name in names])

    @staticmethod
    def _entry(host_dir, name):
        try:
            info = os.lstat(os.path.join(host_dir, name))
        except OSError:
            return (name, S_IFREG, 0, 0)
        if stat.S_ISDIR(info.st_mode):
            return (name, S_IFDIR, 0, 0)
        return (name, S_IFREG, 0, info.st_size)

    def listdir(self, path="."):
        return [entry[0] for entry in self.ilistdir(path)]

    def stat(self, path):
        try:
            info = os.stat(self.host_path(path))
        except OSError as exc:
            raise _as_hub_error(exc) from None
        kind = S_IFDIR if stat.S_ISDIR(info.st_mode) else S_IFREG
        size = 0 if kind == S_IFDIR else info.st_size
        mtime = int(info.st_mtime)
        return (kind, 0, 0, 0, 0, 0, size, mtime, mtime, mtime)

    def statvfs(self, path="/"):
        self.stat(path)
        blocks = self.capacity_bytes // BLOCK_BYTES
        free = max(0, blocks - self.used_bytes() // BLOCK_BYTES)
        return (BLOCK_BYTES, BLOCK_BYTES, blocks, free, free, 0, 0, 0, 0, NAME_MAX)

    def _mutate(self, action, *paths):
        try:
            action(*[self.host_path(p) for p in paths])
        except OSError as exc:
            raise _as_hub_error(exc) from None

    def remove(self, path):
        host = self.host_path(path)
        if os.path.isdir(host):
            raise hub_error(errno.EISDIR)
        self._mutate(os.remove, path)

    unlink = remove

    def rename(self, old, new):
        if self.hub_path(old) == "/" or self.hub_path(new) == "/":
            raise hub_error(errno.EINVAL)
        self._mutate(os.rename, old, new)

    def mkdir(self, path):
        self._mutate(os.mkdir, path)
        self._used_estimate = None

    def rmdir(self, path):
        if self.hub_path(path) == "/":
            raise hub_error(errno.EBUSY)
        self._mutate(os.rmdir, path)

    def getcwd(self):
        return self.cwd

    def chdir(self, path):
        target = self.hub_path(path)
        if not os.path.isdir(self.host_path(target)):
            raise hub_error(errno.ENOENT if not os.path.exists(self.host_path(target)) else errno.ENOTDIR)
        self.cwd = target

    def uname(self):
        return self._uname

    def sync(self):
        pass  # every write reaches the host file when the hub's file object flushes it

    @staticmethod
    def urandom(n):
        return os.urandom(n)


class _FlashFile(io.FileIO):
    """A host file whose writes are charged to the flash's capacity."""

    def __init__(self, fs, host_path, mode):
        if os.path.isdir(host_path):
            raise OSError(errno.EISDIR, "is a directory")
        super().__init__(host_path, mode)
        self._fs = fs

    def write(self, data):
        self._fs._reserve(len(data))
        return super().write(data)
