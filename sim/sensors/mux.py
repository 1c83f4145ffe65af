"""TI TCA9548A I2C switch: eight downstream channels behind one control register.

The mux answers at its own address (0x70..0x77) with a one-byte control
register, written and read as a plain transfer; bit n connects channel n's
devices to the upstream bus. A bus adapter asks `downstream(address)` for
the device that answers at an address through the connected channels: none
when no connected channel has one, and a collision (every transfer fails,
as two chips driving SDA at once would) when two connected channels do.
"""

from .registers import EIO

ADDRESS = 0x70
CHANNELS = 8


class TCA9548AModel:
    def __init__(self, address: int = ADDRESS):
        self.address = address
        self.control = 0
        self.channels: list[dict[int, object]] = [{} for _ in range(CHANNELS)]

    def attach(self, channel: int, address: int, device) -> None:
        if not 0 <= channel < CHANNELS:
            raise ValueError(f"TCA9548A channels are 0..7, got {channel}")
        self.channels[channel][address] = device

    def downstream(self, address: int):
        found = [
            self.channels[ch][address]
            for ch in range(CHANNELS)
            if self.control & (1 << ch) and address in self.channels[ch]
        ]
        if not found:
            return None
        if len(found) > 1:
            return _Collision(address)
        return found[0]

    def addresses(self) -> list[int]:
        """Every downstream address reachable through the connected channels (for a bus scan)."""
        return sorted({a for ch in range(CHANNELS) if self.control & (1 << ch) for a in self.channels[ch]})

    # -- the mux's own transfers ------------------------------------------------------------------

    def write(self, data) -> None:
        if data:
            self.control = data[-1]

    def read(self, nbytes: int) -> bytes:
        return bytes([self.control]) * nbytes

    def write_mem(self, reg: int, data, addrsize: int = 8) -> None:
        self.write(bytes([reg & 0xFF]) + bytes(data))

    def read_mem(self, reg: int, nbytes: int, addrsize: int = 8) -> bytes:
        self.write(bytes([reg & 0xFF]))
        return self.read(nbytes)


class _Collision:
    """Two same-address chips on connected channels: no transfer gets through intact."""

    def __init__(self, address):
        self.address = address

    def _fail(self, *_args):
        raise OSError(EIO, f"two devices answer at 0x{self.address:02X} on the connected TCA9548A channels")

    write = read = write_mem = read_mem = _fail
