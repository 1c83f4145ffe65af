"""The simulated hub's outside world: what the shim's `machine` classes talk to.

Everything a program can touch through `machine` ends here: bus devices,
analog and digital inputs, pulse widths, PWM and pin outputs. Device models
(the serial-bus servos, and the sensors in sim/sensors/) register on a
`SimBoard`; the registration points mirror the test fakes' so a model works
in both places:

  board.attach_uart(uart_id, dev)        dev.handle(data: bytes) -> reply bytes
  board.attach_i2c(bus, address, dev)    dev.read(n), dev.write(data),
                                         dev.read_mem(reg, n, addrsize), dev.write_mem(reg, data, addrsize)
                                         bus: a hardware I2C id (0, 1), or ("soft", scl_pin, sda_pin)
  board.attach_spi(cs_pin, dev)          dev.transfer(data: bytes) -> bytes, while cs_pin is driven low
  board.set_analog(pin, source)          raw 12-bit reading: an int, or a callable() -> int
  board.set_input(pin, source)           level seen by an input Pin: 0/1, or a callable() -> 0/1
  board.set_pulse(pin, source)           what time_pulse_us(pin, level) measures: us, or callable(level) -> us
  board.set_encoder(pin_a, source)       a PCNT Encoder on phase_a=pin_a counts callable() -> edges
                                         (without one, it decodes the levels set_input drives on its lines)
  board.watch_output(pin, callback)      callback(pin_id, level_or_duty) when the program drives the pin

Callables are read when the program reads, so a sensor model computes its
value from the physics at that instant and costs nothing in between.

Bus transfers take simulated time, as on the hub (wire time at the bus's
baud rate/clock), so a program polling a sensor in a tight loop still lets
the robot move.
"""


class SimBoard:
    """The devices and signals around one simulated hub."""

    def __init__(self, clock, before_first_use=None):
        """before_first_use(): called once, when the program first reaches the board through `machine`
        (the simulation builds its physics then)."""
        self.clock = clock
        self.before_first_use = before_first_use
        self.uart_devices = {}  # uart id -> device
        self.i2c_devices = {}  # bus key -> {address: device}
        self.spi_devices = {}  # cs pin -> device
        self.analog = {}  # pin -> int or callable
        self.inputs = {}  # pin -> 0/1 or callable
        self.pulses = {}  # pin -> us or callable(level)
        self.encoder_sources = {}  # phase_a pin -> callable() -> edges
        self.output_watchers = {}  # pin -> [callback]
        self.pins = {}  # pin -> the last machine.Pin constructed on it
        self.pwms = {}  # pin -> the last machine.PWM constructed on it
        self.uarts = {}  # uart id -> the last machine.UART constructed for it
        self.pcnt_units = {}  # PCNT unit -> the machine.Encoder counting on it until its deinit()
        self.hardware_timers = {}  # timer id -> the clock handle every machine.Timer(id) shares
        self.bitstreams = []  # (pin, timing, bytes) the program sent (LED strips), last 64
        self.reset_requested = False

    # --- registration (device models) ------------------------------------------------------

    def attach_uart(self, uart_id, device):
        self.uart_devices[uart_id] = device

    def attach_i2c(self, bus, address, device):
        self.i2c_devices.setdefault(bus, {})[address] = device

    def attach_spi(self, cs_pin, device):
        self.spi_devices[cs_pin] = device

    def set_analog(self, pin, source):
        self.analog[pin] = source

    def set_input(self, pin, source):
        """Drive an input from outside; a constant level change fires the pin's IRQ like an edge
        would, and is counted by a PCNT unit whose A or B line it is."""
        listener = self.pins.get(pin)
        old = listener.value() if listener is not None else None
        self.inputs[pin] = source
        if listener is not None and not listener._is_output():
            new = listener.value()
            if new != old:
                listener._edge(new)
        for unit in self.pcnt_units.values():
            if pin == unit._phase_a or pin == unit._phase_b:
                unit._line_changed()

    def set_pulse(self, pin, source):
        self.pulses[pin] = source

    def set_encoder(self, pin_a, source):
        self.encoder_sources[pin_a] = source

    def watch_output(self, pin, callback):
        self.output_watchers.setdefault(pin, []).append(callback)

    # --- reading (the machine shim) ----------------------------------------------------------

    def input_level(self, pin, default=0):
        source = self.inputs.get(pin, default)
        return 1 if (source() if callable(source) else source) else 0

    def analog_raw(self, pin):
        source = self.analog.get(pin, 0)
        value = source() if callable(source) else source
        return max(0, min(4095, int(value)))

    def pulse_us(self, pin, level):
        source = self.pulses.get(pin)
        if source is None:
            return None
        return int(source(level) if callable(source) else source)

    def encoder_edges(self, pin_a):
        source = self.encoder_sources.get(pin_a)
        return None if source is None else int(source())

    def uart_reply_delay_us(self, wire_us):
        """How long after a request is written its reply can be read: the request and the reply
        crossing the wire (`wire_us` at the UART's baud rate) and the device's turnaround (a
        serial-bus servo answers about 30 us after the request's last byte)."""
        return wire_us + 30

    def i2c_bus(self, key):
        return self.i2c_devices.get(key, {})

    def spi_selected(self):
        """The SPI device whose chip-select pin is driven low right now, or None."""
        for cs, device in self.spi_devices.items():
            pin = self.pins.get(cs)
            if pin is not None and pin._is_output() and pin._out == 0:
                return device
        return None

    def output_changed(self, pin, value):
        for callback in self.output_watchers.get(pin, ()):
            callback(pin, value)

    def record_bitstream(self, pin, timing, data):
        self.bitstreams.append((pin, tuple(timing), bytes(data)))
        del self.bitstreams[:-64]
