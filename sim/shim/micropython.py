"""MicroPython's `micropython` module for a program running in the simulator."""

_clock = [None]


def bind(clock):
    _clock[0] = clock


def const(value):
    return value


def native(fn):
    return fn


def viper(fn):
    return fn


def schedule(fn, arg):
    """Run fn(arg) "soon", as the ESP32 port does: at the next moment simulated time moves on."""
    clock = _clock[0]
    if clock is None:
        fn(arg)
        return
    clock.schedule(lambda: fn(arg), 0)


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


def kbd_intr(char):
    pass


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
