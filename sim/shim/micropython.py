"""MicroPython's `micropython` module for a program running in the simulator."""

import sys

_clock = [None]


def bind(clock):
    _clock[0] = clock
    del _queued[:]  # a new hub starts with an empty queue


def const(value):
    return value


def native(fn):
    return fn


def viper(fn):
    return fn


# MICROPY_SCHEDULER_DEPTH on the ESP32 port: callbacks pending at once before schedule() refuses.
SCHEDULER_DEPTH = 8

_queued = []  # clock handles of scheduled callbacks; a handle is cancelled once run or soft-reset away


def schedule(fn, arg):
    """Queue fn(arg) to run "soon", as the ESP32 port does: at the next moment simulated time moves
    on, never inside this call. A full queue refuses, and a callback that raises is printed and
    dropped, as the port's scheduler does."""
    _queued[:] = [handle for handle in _queued if not handle.cancelled]
    if len(_queued) >= SCHEDULER_DEPTH:
        raise RuntimeError("schedule queue full")
    clock = _clock[0]
    if clock is None:
        raise RuntimeError("micropython.schedule needs the simulated clock: bind() it first")

    def run():
        try:
            fn(arg)
        except Exception as exc:  # noqa: BLE001 - printed and dropped, as on the hub
            sys.print_exception(exc)

    _queued.append(clock.schedule(run, 0))


def alloc_emergency_exception_buf(size):
    pass


def opt_level(level=None):
    return 0 if level is None else None


def mem_info(verbose=None):
    print("stack: 0 out of 15360\nGC: simulated (no MicroPython heap)")


def qstr_info(verbose=None):
    pass


def stack_use():
    return 0


def heap_lock():
    return 0


def heap_unlock():
    return 0


_kbd_intr_handler = [None]


def bind_kbd_intr(handler):
    """Who honours kbd_intr(): a virtual hub's link (None: nothing reads a console, as in a sim run)."""
    _kbd_intr_handler[0] = handler


def kbd_intr(char):
    """micropython.kbd_intr(chr): the byte that interrupts running code, -1 for none (mpremote's
    mount turns Ctrl-C off while binary data flows)."""
    if _kbd_intr_handler[0] is not None:
        _kbd_intr_handler[0](char)


class RingIO:
    """micropython.RingIO: a fixed-size byte ring. RingIO(n) holds n bytes; RingIO(buffer) holds len - 1."""

    def __init__(self, size_or_buffer):
        self._capacity = size_or_buffer if isinstance(size_or_buffer, int) else len(size_or_buffer) - 1
        self._data = bytearray()

    def any(self):
        return len(self._data)

    def write(self, buf):
        chunk = bytes(buf[: self._capacity - len(self._data)])
        self._data += chunk
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
