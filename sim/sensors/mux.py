"""TI TCA9548A I2C switch: eight downstream channels behind one control register.

The mux answers at its own address (0x70..0x77) with a one-byte control
register, written and read as a plain transfer; bit n connects channel n's
devices to the upstream bus. Connecting really puts them on the upstream
bus's address map (the dict a bus adapter looks devices up in), so a driver
reaches a sensor only while its channel is connected; two connected devices
at one address (two channels, or a channel and a chip wired straight to the
bus) collide, and every transfer to that address fails as two chips driving
SDA at once would. Disconnecting restores whatever the bus had before.
"""

from .registers import EIO

ADDRESS = 0x70
CHANNELS = 8


class TCA9548AModel:
    def __init__(self, upstream: dict, address: int = ADDRESS):
        """`upstream` is the bus's {address: device} map; the mux adds itself to it."""
        self.address = address
        self.control = 0
        self.channels: list[dict[int, object]] = [{} for _ in range(CHANNELS)]
        self._bus = upstream
        self._overlay: dict[int, tuple[object, object]] = {}  # address -> (what we put, what it hid)
        upstream[address] = self

    def attach(self, channel: int, address: int, device) -> None:
        if not 0 <= channel < CHANNELS:
            raise ValueError(f"TCA9548A channels are 0..7, got {channel}")
        self.channels[channel][address] = device
        self._reconnect()

    def _reconnect(self) -> None:
        bus = self._bus
        for address, (ours, hidden) in self._overlay.items():
            if bus.get(address) is ours:
                if hidden is None:
                    del bus[address]
                else:
                    bus[address] = hidden
        self._overlay = {}
        connected: dict[int, list] = {}
        for ch in range(CHANNELS):
            if self.control & (1 << ch):
                for address, device in self.channels[ch].items():
                    connected.setdefault(address, []).append(device)
        for address, devices in connected.items():
            hidden = bus.get(address)
            if hidden is not None:
                devices.append(hidden)
            ours = devices[0] if len(devices) == 1 else _Collision(address)
            self._overlay[address] = (ours, hidden)
            bus[address] = ours

    # -- the mux's own transfers ------------------------------------------------------------------

    def write(self, data) -> None:
        if data:
            self.control = data[-1]
            self._reconnect()

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
        raise OSError(
            EIO, f"two devices answer at 0x{self.address:02X} through the connected TCA9548A channels"
        )

    write = read = write_mem = read_mem = _fail
