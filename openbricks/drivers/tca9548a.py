"""TI TCA9548A 8-channel I2C switch, so several same-address sensors share one bus.

The TCS34725 has one fixed address (0x29); the mux fans the bus out to eight
isolated channels, one sensor each. `mux[n]` is a drop-in for `machine.I2C`
that selects channel n before each transaction, so every driver constructs
against it unchanged.

Protocol (datasheet section 8.3): the mux has a single control register,
written and read as a plain one-byte transfer at its own address; bit n
connects channel n. Several bits may be set at once; 0 disconnects all.
"""

from micropython import const

_DEFAULT_ADDR = const(0x70)
_CHANNELS = const(8)
_ENODEV = const(19)


class TCA9548A:
    """8-channel I2C multiplexer for same-address sensors.

    `mux[n]` returns an I2C-compatible handle for channel n (0-7); `address`
    is 0x70-0x77 depending on the A0/A1/A2 straps.
    """

    def __init__(self, i2c, address=_DEFAULT_ADDR):
        if not 0x70 <= address <= 0x77:
            raise ValueError("TCA9548A address must be 0x70..0x77 (set by A0/A1/A2), got 0x%02X" % address)
        self._i2c = i2c
        self._address = address
        self._mask = None  # what we last wrote; None = unknown, write before the next transfer
        self._channels = [None] * _CHANNELS
        try:
            self._write_mask(0)
        except OSError as e:
            raise OSError(
                _ENODEV,
                "no TCA9548A answers at I2C address 0x%02X (%s): check SDA/SCL/power, and that the "
                "A0/A1/A2 straps match address=" % (address, e),
            ) from None

    def __getitem__(self, channel):
        if not isinstance(channel, int) or not 0 <= channel < _CHANNELS:
            raise IndexError("TCA9548A channels are 0..7, got %r" % (channel,))
        handle = self._channels[channel]
        if handle is None:
            handle = _Channel(self, channel)
            self._channels[channel] = handle
        return handle

    def __len__(self):
        return _CHANNELS

    def select(self, channel):
        """Enable exactly `channel` (0..7), disabling the rest."""
        if not isinstance(channel, int) or not 0 <= channel < _CHANNELS:
            raise ValueError("TCA9548A channels are 0..7, got %r" % (channel,))
        self._write_mask(1 << channel)

    def disable(self):
        """Disconnect every channel (control byte 0x00)."""
        self._write_mask(0)

    def selected(self):
        """The control byte as the mux reports it: bit n set = channel n connected."""
        return self._i2c.readfrom(self._address, 1)[0]

    def _write_mask(self, mask):
        self._mask = None
        self._i2c.writeto(self._address, bytes((mask,)))
        self._mask = mask

    def _run(self, channel, operation, *args):
        """Select `channel` (skipped when already selected: it costs a bus transaction every time)
        and run one upstream I2C operation.

        The skip trusts our record of the mux state; a mux that browned out alone comes back with
        every channel off and would make that record a lie, so a failed transfer re-selects and
        retries once before the error reaches the driver.
        """
        mask = 1 << channel
        if self._mask != mask:
            self._write_mask(mask)
        try:
            return operation(*args)
        except OSError:
            self._write_mask(mask)
            return operation(*args)

    def __repr__(self):
        return "TCA9548A(address=0x%02X)" % self._address


class _Channel:
    """One downstream channel, duck-typed as `machine.I2C` for the drivers behind it."""

    def __init__(self, mux, channel):
        self._mux = mux
        self.channel = channel

    def scan(self):
        """Addresses that answer on this channel (the mux's own address is on every channel and left out)."""
        found = self._mux._run(self.channel, self._mux._i2c.scan)
        return [a for a in found if a != self._mux._address]

    def writeto(self, addr, buf, stop=True):
        return self._mux._run(self.channel, self._mux._i2c.writeto, addr, buf, stop)

    def writevto(self, addr, vector, stop=True):
        return self._mux._run(self.channel, self._mux._i2c.writevto, addr, vector, stop)

    def readfrom(self, addr, nbytes, stop=True):
        return self._mux._run(self.channel, self._mux._i2c.readfrom, addr, nbytes, stop)

    def readfrom_into(self, addr, buf, stop=True):
        return self._mux._run(self.channel, self._mux._i2c.readfrom_into, addr, buf, stop)

    def writeto_mem(self, addr, memaddr, buf, addrsize=8):
        return self._mux._run(self.channel, self._mux._i2c.writeto_mem, addr, memaddr, buf, addrsize)

    def readfrom_mem(self, addr, memaddr, nbytes, addrsize=8):
        return self._mux._run(self.channel, self._mux._i2c.readfrom_mem, addr, memaddr, nbytes, addrsize)

    def readfrom_mem_into(self, addr, memaddr, buf, addrsize=8):
        return self._mux._run(self.channel, self._mux._i2c.readfrom_mem_into, addr, memaddr, buf, addrsize)

    def __repr__(self):
        return "%r[%d]" % (self._mux, self.channel)
