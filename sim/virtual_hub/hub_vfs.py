"""MicroPython's VFS on a virtual hub: the flash at "/", and filesystems hub code mounts beside it.

    files = HubVFS(flash)                       # flash: the HubFS at "/"
    files.mount(RemoteFS(...), "/remote")       # os.mount(), as `mpremote mount DIR` does it
    files.open("/remote/helper.py", "rb")       # the mounted object's open("/helper.py", "rb")
    files.mount()                               # [(flash, "/"), (RemoteFS, "/remote")]: `vfs.mount()`

A mounted object speaks MicroPython's VFS protocol (open, ilistdir, stat, statvfs, remove, rename,
mkdir, rmdir, chdir, getcwd, mount, umount) with paths inside it ("/helper.py"); this module
strips the mount point, as MicroPython's extmod/vfs.c does. `os`, `open`, `io.open`, imports and
`vfs` of hub code all go through it, so `mpremote df` and `mpremote mount` work as on a hub.

A soft reset unmounts everything but the flash (MicroPython re-initialises its VFS on soft reset).
"""

import errno
import types

from .hub_fs import hub_error


class HubVFS:
    """The mount table of one hub, with the flash (a HubFS) at the root."""

    def __init__(self, flash):
        self.flash = flash
        self._mounts = {}  # mount point ("/remote") -> mounted object

    # -- the table -------------------------------------------------------------------------------

    def mount(self, fs=None, mount_point=None, *, readonly=False, mkfs=False):
        """vfs.mount(fs, "/dir"); with no arguments, the list of (fs, mount point)."""
        if fs is None and mount_point is None:
            return [(self.flash, "/")] + [(obj, point) for point, obj in sorted(self._mounts.items())]
        point = self.flash.hub_path(mount_point)
        if point == "/" or point in self._mounts:
            raise hub_error(errno.EPERM)
        if hasattr(fs, "mount"):
            fs.mount(readonly, mkfs)
        self._mounts[point] = fs
        return None

    def umount(self, target):
        """vfs.umount("/dir") or vfs.umount(fs)."""
        if isinstance(target, str | bytes):
            point = self.flash.hub_path(target)
        else:
            point = next((p for p, obj in self._mounts.items() if obj is target), None)
        fs = self._mounts.pop(point, None) if point is not None else None
        if fs is None:
            raise hub_error(errno.EINVAL)
        if hasattr(fs, "umount"):
            fs.umount()
        if self.flash.cwd == point or self.flash.cwd.startswith(point + "/"):
            self.flash.cwd = "/"

    def reset(self):
        """A soft reset: every mount but the flash goes, without calling into hub code."""
        self._mounts.clear()

    def _resolve(self, path):
        """(mounted object, path inside it) for a hub path, or (None, hub path) on the flash."""
        hub = self.flash.hub_path(path)
        for point in sorted(self._mounts, key=len, reverse=True):
            if hub == point or hub.startswith(point + "/"):
                return self._mounts[point], hub[len(point) :] or "/"
        return None, hub

    # -- what hub code calls -----------------------------------------------------------------------

    def open(self, path, mode="r", *args, **kwargs):
        fs, inner = self._resolve(path)
        if fs is None:
            return self.flash.open(inner, mode, *args, **kwargs)
        return fs.open(inner, mode)

    def ilistdir(self, path="."):
        fs, inner = self._resolve(path)
        return iter(self.flash.ilistdir(inner) if fs is None else fs.ilistdir(inner))

    def listdir(self, path="."):
        return [entry[0] for entry in self.ilistdir(path)]

    def stat(self, path):
        fs, inner = self._resolve(path)
        if fs is None:
            return self.flash.stat(inner)
        if inner == "/" and not hasattr(fs, "stat"):
            return (0x4000, 0, 0, 0, 0, 0, 0, 0, 0, 0)
        return fs.stat(inner)

    def statvfs(self, path="/"):
        fs, inner = self._resolve(path)
        return self.flash.statvfs(inner) if fs is None else fs.statvfs(inner)

    def _call(self, name, path, *more):
        fs, inner = self._resolve(path)
        if fs is None:
            return getattr(self.flash, name)(inner, *more)
        return getattr(fs, name)(inner, *more)

    def remove(self, path):
        return self._call("remove", path)

    def mkdir(self, path):
        return self._call("mkdir", path)

    def rmdir(self, path):
        return self._call("rmdir", path)

    def rename(self, old, new):
        fs_old, inner_old = self._resolve(old)
        fs_new, inner_new = self._resolve(new)
        if fs_old is not fs_new:
            raise hub_error(errno.EXDEV)
        if fs_old is None:
            return self.flash.rename(inner_old, inner_new)
        return fs_old.rename(inner_old, inner_new)

    def chdir(self, path):
        fs, inner = self._resolve(path)
        if fs is None:
            return self.flash.chdir(inner)
        if hasattr(fs, "chdir"):
            fs.chdir(inner)
        self.flash.cwd = self.flash.hub_path(path)
        return None

    def getcwd(self):
        return self.flash.cwd

    def is_file(self, path):
        """Whether `path` is a file (imports look for modules with this)."""
        try:
            return not self.stat(path)[0] & 0x4000
        except (OSError, AttributeError, TypeError):
            return False

    # -- modules -----------------------------------------------------------------------------------

    def os_module(self):
        """MicroPython's `os` over this table: the flash's os, with every path call routed."""
        module = self.flash.os_module()
        for name in ("ilistdir", "listdir", "stat", "statvfs", "remove", "rename", "mkdir", "rmdir"):
            setattr(module, name, getattr(self, name))
        module.unlink = self.remove
        module.chdir = self.chdir
        module.getcwd = self.getcwd
        module.mount = self.mount
        module.umount = self.umount
        return module

    def vfs_module(self):
        """MicroPython's `vfs`: mount() (the table when called bare) and umount()."""
        module = types.ModuleType("vfs", "MicroPython's vfs on the virtual hub.")
        module.mount = self.mount
        module.umount = self.umount
        return module
