"""MicroPython's `deflate` module for CPython, decompression side (what the runtime uses), over zlib."""

import zlib

AUTO = 0
RAW = 1
ZLIB = 2
GZIP = 3

_WBITS = {AUTO: 47, RAW: -15, ZLIB: 15, GZIP: 31}


class DeflateIO:
    def __init__(self, stream, format=AUTO, wbits=0, close=False):
        self._stream = stream
        self._inflater = zlib.decompressobj(_WBITS[format])
        self._out = b""
        self._eof = False

    def readinto(self, buf):
        while len(self._out) < len(buf) and not self._eof:
            chunk = self._stream.read(256)
            try:
                if chunk:
                    self._out += self._inflater.decompress(chunk)
                else:
                    self._out += self._inflater.flush()
                    self._eof = True
            except zlib.error as exc:
                raise OSError(22, "corrupt deflate stream: %s" % exc) from None
        n = min(len(buf), len(self._out))
        buf[:n] = self._out[:n]
        self._out = self._out[n:]
        return n

    def read(self, n=-1):
        chunks = []
        buf = bytearray(512 if n < 0 else n)
        while True:
            got = self.readinto(buf)
            if not got:
                break
            chunks.append(bytes(buf[:got]))
            if n >= 0:
                break
        return b"".join(chunks)
