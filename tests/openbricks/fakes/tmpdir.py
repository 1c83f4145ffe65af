"""Scratch directories for tests that write files (run logs, staged programs), on CPython and MicroPython."""

import os

_counter = [0]


def _exists(path):
    try:
        os.stat(path)
        return True
    except OSError:
        return False


def make(prefix="ob"):
    """A fresh empty directory under /tmp (or the working directory where /tmp does not exist)."""
    base = "/tmp" if _exists("/tmp") else "."
    while True:
        _counter[0] += 1
        path = "%s/%s-%d-%d" % (base, prefix, os.getpid() if hasattr(os, "getpid") else 0, _counter[0])
        if not _exists(path):
            os.mkdir(path)
            return path


def remove(path):
    """Delete `path` and everything under it."""
    for entry in os.listdir(path):
        child = path + "/" + entry
        if os.stat(child)[0] & 0x4000:  # S_IFDIR
            remove(child)
        else:
            os.remove(child)
    os.rmdir(path)


class scratch:
    """`with tmpdir.scratch() as directory:` a fresh directory, removed with its contents on the way out."""

    def __init__(self, prefix="ob"):
        self.prefix = prefix
        self.path = None

    def __enter__(self):
        self.path = make(self.prefix)
        return self.path

    def __exit__(self, exc_type, exc, tb):
        remove(self.path)
        return False
