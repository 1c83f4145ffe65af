"""MicroPython's `deflate` module for code on a virtual hub, on the host's zlib.

The hub firmware has `deflate` (the host compresses staged programs with it), so a virtual hub
offers the same API: `DeflateIO(stream, format=AUTO, wbits=0, close=False)` decompresses what it
reads from `stream` and compresses what is written to it, in the RAW, ZLIB or GZIP container.
"""

import zlib

AUTO = 0
RAW = 1
ZLIB = 2
GZIP = 3

_READ_CHUNK = 256
_DEFAULT_WBITS = 15


def _zlib_wbits(format, wbits, decompress):
    bits = wbits or _DEFAULT_WBITS
    if not 5 <= bits <= 15:
        raise ValueError("wbits must be 5..15 (or 0 for the default)")
    if format == RAW:
        return -bits
    if format == ZLIB:
        return bits
    if format == GZIP:
        return 16 + bits
    if format == AUTO and decompress:
        return 32 + bits  # a zlib or gzip header, whichever the data has
    raise ValueError("format must be RAW, ZLIB or GZIP (AUTO only when reading)")


class DeflateIO:
    """A stream that inflates on read and deflates on write, over `stream`."""

    def __init__(self, stream, format=AUTO, wbits=0, close=False):
        if format not in (AUTO, RAW, ZLIB, GZIP):
            raise ValueError("format must be deflate.AUTO, RAW, ZLIB or GZIP")
        self._stream = stream
        self._format = format
        self._wbits = wbits
        self._close_stream = close
        self._inflater = None
        self._deflater = None
        self._pending = b""
        self._eof = False
        self._closed = False

    def _check(self):
        if self._closed:
            raise OSError(9, "EBADF")  # MicroPython's error for a closed stream

    def readinto(self, buf):
        self._check()
        if self._inflater is None:
            self._inflater = zlib.decompressobj(_zlib_wbits(self._format, self._wbits, True))
        while not self._pending and not self._eof:
            chunk = self._stream.read(_READ_CHUNK)
            if not chunk:
                self._pending = self._inflater.flush()
                self._eof = True
            else:
                try:
                    self._pending = self._inflater.decompress(chunk)
                except zlib.error:
                    raise OSError(22, "EINVAL") from None  # corrupt data, as the hub reports it
                if self._inflater.eof:
                    self._eof = True
        n = min(len(buf), len(self._pending))
        buf[:n] = self._pending[:n]
        self._pending = self._pending[n:]
        return n

    def read(self, n=-1):
        parts = []
        while n is None or n < 0 or sum(len(p) for p in parts) < n:
            want = _READ_CHUNK if n is None or n < 0 else n - sum(len(p) for p in parts)
            buf = bytearray(want)
            got = self.readinto(buf)
            if not got:
                break
            parts.append(bytes(buf[:got]))
        return b"".join(parts)

    def readline(self):
        line = bytearray()
        byte = bytearray(1)
        while self.readinto(byte):
            line += byte
            if byte == b"\n":
                break
        return bytes(line)

    def write(self, data):
        self._check()
        if self._deflater is None:
            fmt = ZLIB if self._format == AUTO else self._format
            self._deflater = zlib.compressobj(wbits=_zlib_wbits(fmt, self._wbits, False))
        out = self._deflater.compress(bytes(data))
        if out:
            self._stream.write(out)
        return len(data)

    def close(self):
        if self._closed:
            return
        if self._deflater is not None:
            self._stream.write(self._deflater.flush())
        self._closed = True
        if self._close_stream:
            self._stream.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False
