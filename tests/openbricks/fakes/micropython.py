"""A fake `micropython` module for CPython: the few helpers the runtime calls."""

import sys

from . import clock

# MICROPY_SCHEDULER_DEPTH on the ESP32 port: callbacks pending at once before schedule() refuses.
SCHEDULER_DEPTH = 8

_scheduled = []  # (fn, arg) waiting for the VM's next pending check


def reset():
    """A soft reset drops whatever was still queued."""
    del _scheduled[:]


def run_pending():
    """Run what is queued, oldest first, as the VM does between bytecodes.

    A callback that raises is printed and dropped, as the port's scheduler does; a callback that
    schedules another leaves it for the next pending check, so a self-rescheduling callback cannot
    starve the program.
    """
    batch = _scheduled[:]
    del _scheduled[:]
    for fn, arg in batch:
        try:
            fn(arg)
        except Exception as exc:  # noqa: BLE001 - printed and dropped, as on the hub
            sys.print_exception(exc)


def const(value):
    return value


def schedule(fn, arg):
    """Queue fn(arg) to run later: at the next virtual-clock advance (a sleep, a wait), never inside
    this call, as on the hub, where it runs between bytecodes after the caller returns."""
    if len(_scheduled) >= SCHEDULER_DEPTH:
        raise RuntimeError("schedule queue full")
    _scheduled.append((fn, arg))


clock.set_pending_runner(run_pending)


def alloc_emergency_exception_buf(size):
    pass


def mem_info(verbose=None):
    pass


def opt_level(level=None):
    return 0 if level is None else None


def native(fn):
    return fn


def viper(fn):
    return fn


class RingIO:
    """micropython.RingIO (MicroPython 1.23+): a fixed byte ring, as the C type behaves.

    RingIO(n) holds n bytes; RingIO(buffer) uses the buffer and holds len(buffer) - 1. write() stores
    what fits and returns that count; reads on an empty ring return b"" / 0.
    """

    def __init__(self, size_or_buffer):
        if isinstance(size_or_buffer, int):
            self._capacity = size_or_buffer
        else:
            self._capacity = len(size_or_buffer) - 1
        self._data = bytearray()

    def any(self):
        return len(self._data)

    def write(self, buf):
        room = self._capacity - len(self._data)
        chunk = bytes(buf[:room])
        self._data.extend(chunk)
        return len(chunk)

    def read(self, nbytes=-1):
        if nbytes is None or nbytes < 0:
            nbytes = len(self._data)
        out = bytes(self._data[:nbytes])
        del self._data[: len(out)]
        return out

    def readinto(self, buf, nbytes=-1):
        if nbytes is None or nbytes < 0 or nbytes > len(buf):
            nbytes = len(buf)
        out = self.read(nbytes)
        buf[: len(out)] = out
        return len(out)

    def readline(self, nbytes=-1):
        end = self._data.find(b"\n")
        n = len(self._data) if end < 0 else end + 1
        if nbytes is not None and 0 <= nbytes < n:
            n = nbytes
        return self.read(n)

    def close(self):
        pass
