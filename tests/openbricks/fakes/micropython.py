"""A fake `micropython` module for CPython: the few helpers the runtime calls."""

_scheduled = []


def reset():
    del _scheduled[:]


def const(value):
    return value


def schedule(fn, arg):
    # The ESP32 port runs scheduled callbacks between bytecodes soon after; run them now.
    fn(arg)


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
