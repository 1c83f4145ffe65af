"""The I2C side every register-mapped chip model shares.

A transaction writes the register address (one byte, or two high byte first
for chips with 16-bit maps), then reads or writes data bytes from there on,
the address advancing by one per byte. Bus adapters call the four methods a
machine.I2C needs from a device: `write(data)`, `read(nbytes)`,
`write_mem(reg, data, addrsize)` and `read_mem(reg, nbytes, addrsize)`.
Models compute a register's value when it is read, so nothing is evaluated
that the program never asks for.
"""

EIO = 5


def physics_clock_us(data):
    """A clock for device models: the simulated time of `data` (mujoco.MjData) in microseconds."""
    return lambda: int(round(data.time * 1_000_000))


class RegisterDevice:
    ADDRESS_BYTES = 1

    def __init__(self):
        self.pointer = 0

    # -- what a chip model defines --------------------------------------------------------------

    def read_register(self, reg: int) -> int:
        raise NotImplementedError

    def write_register(self, reg: int, value: int) -> None:
        raise NotImplementedError

    def next_register(self, reg: int) -> int:
        return (reg + 1) & (0xFF if self.ADDRESS_BYTES == 1 else 0xFFFF)

    def select(self, address_bytes: bytes) -> int:
        """The register a transaction's address bytes point at."""
        reg = 0
        for b in address_bytes:
            reg = (reg << 8) | b
        return reg

    # -- the bus side ---------------------------------------------------------------------------

    def write(self, data) -> None:
        n = self.ADDRESS_BYTES
        if len(data) < n:
            raise OSError(EIO, f"{type(self).__name__}: a write needs {n} register address byte(s)")
        self.pointer = self.select(bytes(data[:n]))
        for value in data[n:]:
            self.write_register(self.pointer, value)
            self.pointer = self.next_register(self.pointer)

    def read(self, nbytes: int) -> bytes:
        out = bytearray(nbytes)
        for i in range(nbytes):
            out[i] = self.read_register(self.pointer) & 0xFF
            self.pointer = self.next_register(self.pointer)
        return bytes(out)

    def write_mem(self, reg: int, data, addrsize: int = 8) -> None:
        self.write(reg.to_bytes(addrsize // 8, "big") + bytes(data))

    def read_mem(self, reg: int, nbytes: int, addrsize: int = 8) -> bytes:
        self.write(reg.to_bytes(addrsize // 8, "big"))
        return self.read(nbytes)
