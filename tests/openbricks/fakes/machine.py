"""`machine` for the runtime's tests: the simulator's model (sim/shim/machine.py) on a test board.

The timers, the RTC, bitstream, time_pulse_us and the chip-level functions are the simulator's,
bound to `board`, a SimBoard the test sets up and reads back. The pins, ADC, PWM, encoders and
the UART / I2C / SPI buses are still this module's own: buses carry bytes to device models that
tests attach (a fake ST3215 that answers SCS packets from a register file, I2C chips with
register maps), so drivers are exercised through their real wire protocol.
"""

from . import bounded, clock
from .hardware import board as _sim_board
from .hardware import machine as _model
from .hardware import mptime

# The simulator's definitions, as they are.
HARDWARE_TIMER_COUNT = _model.HARDWARE_TIMER_COUNT
Timer = _model.Timer
RTC = _model.RTC
WDT = _model.WDT
bitstream = _model.bitstream
time_pulse_us = _model.time_pulse_us
freq = _model.freq
unique_id = _model.unique_id
reset = _model.reset
soft_reset = _model.soft_reset
idle = _model.idle
lightsleep = _model.lightsleep
deepsleep = _model.deepsleep
disable_irq = _model.disable_irq
enable_irq = _model.enable_irq
reset_cause = _model.reset_cause
PWRON_RESET = _model.PWRON_RESET
HARD_RESET = _model.HARD_RESET
WDT_RESET = _model.WDT_RESET
DEEPSLEEP_RESET = _model.DEEPSLEEP_RESET
SOFT_RESET = _model.SOFT_RESET


class _Board(_sim_board.SimBoard):
    """Everything outside the chip, as the test sets it up and reads it back: the simulator's board
    (pulses, bitstreams, hardware timers, a reset asked for) and this module's registries."""

    def __init__(self):
        self.reset()

    def reset(self):
        _sim_board.SimBoard.__init__(self, clock.current())
        _model.bind(self)
        self.input_levels = {}  # pin id -> 0/1 seen by Pin.value() on inputs
        self.pwms = {}  # pin id -> the last PWM object constructed for it
        self.uarts = {}  # uart id -> the last UART object constructed for it
        self.encoders = {}  # PCNT unit -> the Encoder counting on it; tests move its .count

    def set_input(self, pin_id, level):
        """Drive an input pin from outside; fires the pin's IRQ on a matching edge."""
        old = self.input_levels.get(pin_id, 1)
        self.input_levels[pin_id] = 1 if level else 0
        pin = self.pins.get(pin_id)
        if pin is not None and pin._irq_handler is not None and old != self.input_levels[pin_id]:
            rising = self.input_levels[pin_id] == 1
            if (rising and pin._irq_trigger & Pin.IRQ_RISING) or (
                not rising and pin._irq_trigger & Pin.IRQ_FALLING
            ):
                pin._irq_handler(pin)
        if old != self.input_levels[pin_id]:
            for encoder in self.encoders.values():
                if pin_id in (encoder.phase_a, encoder.phase_b):
                    encoder._line_changed()


board = _Board()


def _pin_id(pin):
    return pin.id() if isinstance(pin, Pin) else pin


def _input_level(pin_id):
    pin = board.pins.get(pin_id)
    return pin.value() if pin is not None else board.input_levels.get(pin_id, 0)


class Pin:
    IN = 1
    OUT = 3
    OPEN_DRAIN = 7
    PULL_UP = 1
    PULL_DOWN = 2
    IRQ_RISING = 1
    IRQ_FALLING = 2

    def __init__(self, id, mode=-1, pull=-1, value=None):
        self._id = id
        self._mode = mode
        self._pull = pull
        self._out = 0
        self._irq_handler = None
        self._irq_trigger = 0
        if value is not None:
            self._out = 1 if value else 0
        board.pins[id] = self

    def init(self, mode=-1, pull=-1, value=None):
        if mode != -1:
            self._mode = mode
        if pull != -1:
            self._pull = pull
        if value is not None:
            self._out = 1 if value else 0

    def id(self):
        return self._id

    def value(self, v=None):
        if v is None:
            if self._mode == Pin.OUT:
                return self._out
            default = 1 if self._pull == Pin.PULL_UP else 0
            return board.input_levels.get(self._id, default)
        self._out = 1 if v else 0
        return None

    def __call__(self, v=None):
        return self.value(v)

    def on(self):
        self._out = 1

    def off(self):
        self._out = 0

    def irq(self, handler=None, trigger=3, wake=None):
        # The ESP32 port's signature: it has no `hard=` (every pin handler is scheduled), and a
        # driver passing one gets a TypeError on the hub.
        self._irq_handler = handler
        self._irq_trigger = trigger

    def __repr__(self):
        return "Pin(%s)" % self._id


class ADC:
    ATTN_0DB = 0
    ATTN_2_5DB = 1
    ATTN_6DB = 2
    ATTN_11DB = 3
    WIDTH_9BIT = 0
    WIDTH_10BIT = 1
    WIDTH_11BIT = 2
    WIDTH_12BIT = 3

    def __init__(self, pin, atten=None):
        self._pin = _pin_id(pin)
        self._atten = atten

    def atten(self, value):
        self._atten = value

    def width(self, value):
        pass

    def read(self):
        return board.analog.get(self._pin, 0)

    def read_u16(self):
        return (self.read() << 4) | (self.read() >> 8)


class PWM:
    def __init__(self, pin, freq=None, duty=None, duty_u16=None):
        self._pin = _pin_id(pin)
        self._freq = freq or 5000
        self._duty_u16 = 0
        if duty is not None:
            self._duty_u16 = int(duty) * 65535 // 1023
        if duty_u16 is not None:
            self._duty_u16 = int(duty_u16)
        self.deinited = False
        board.pwms[self._pin] = self

    def freq(self, f=None):
        if f is None:
            return self._freq
        self._freq = f
        return None

    def duty(self, d=None):
        if d is None:
            return self._duty_u16 * 1023 // 65535
        self._duty_u16 = int(d) * 65535 // 1023
        return None

    def duty_u16(self, d=None):
        if d is None:
            return self._duty_u16
        self._duty_u16 = max(0, min(65535, int(d)))
        return None

    def deinit(self):
        self.deinited = True


# Count change per (previous AB << 2 | new AB), AB = A << 1 | B; +1 for A leading B, as the ESP32
# port's machine.Encoder counts; 0 where both lines changed at once.
_QUADRATURE_STEP = (0, -1, 1, 0, 1, 0, 0, -1, -1, 0, 0, 1, 0, 1, -1, 0)


class Encoder:
    """PCNT quadrature counter (ESP32 machine.Encoder); `count` is what the hardware has counted.

    Tests move `count` directly, or drive the A/B lines with board.set_input (as
    fakes.dc_motor.QuadratureLines does), which the unit counts like the peripheral: every edge
    with phases=4, one per cycle with phases=1.
    """

    def __init__(self, id, phase_a=None, phase_b=None, **kwargs):
        self._id = id
        self.init(phase_a, phase_b, **kwargs)
        board.encoders[id] = self

    def init(self, phase_a=None, phase_b=None, filter_ns=0, phases=1):
        self.phase_a = _pin_id(phase_a)
        self.phase_b = _pin_id(phase_b)
        self.filter_ns = filter_ns
        self.phases = phases
        self.count = 0
        self.deinited = False
        self._lines = self._line_levels()
        self._edges = 0

    def _line_levels(self):
        return (_input_level(self.phase_a) << 1) | _input_level(self.phase_b)

    def _line_changed(self):
        lines = self._line_levels()
        step = _QUADRATURE_STEP[(self._lines << 2) | lines]
        self._lines = lines
        if step and not self.deinited:
            before = self._edges * self.phases // 4
            self._edges += step
            self.count += self._edges * self.phases // 4 - before

    def value(self, value=None):
        current = self.count
        if value is not None:
            self.count = int(value)
        return current

    def deinit(self):
        self.deinited = True


class UART:
    def __init__(self, id, baudrate=115200, **kwargs):
        self._id = id
        self._rx = bytearray()
        self.written = []
        self.deinited = False
        self.init(baudrate, **kwargs)
        board.uarts[id] = self

    def init(self, baudrate=115200, bits=8, parity=None, stop=1, tx=None, rx=None, timeout=0, **kwargs):
        self.baudrate = baudrate
        self.tx = _pin_id(tx)
        self.rx = _pin_id(rx)
        self.timeout = timeout
        self.deinited = False

    def deinit(self):
        self.deinited = True

    def write(self, data):
        if self.deinited:
            raise OSError("UART%d is deinitialised" % self._id)
        data = bytes(data)
        bounded.append(self.written, data)
        device = board.uart_devices.get(self._id)
        if device is not None:
            reply = device.handle(data)
            if reply:
                self._rx.extend(reply)
        return len(data)

    def any(self):
        return len(self._rx)

    def read(self, n=None):
        if not self._rx:
            if self.timeout:
                mptime.sleep_ms(self.timeout)
            return None
        if n is None or n > len(self._rx):
            n = len(self._rx)
        out = bytes(self._rx[:n])
        self._rx = self._rx[n:]  # MicroPython bytearrays do not support slice deletion
        return out

    def readinto(self, buf, n=None):
        data = self.read(len(buf) if n is None else n)
        if not data:
            return None
        buf[: len(data)] = data
        return len(data)

    def flush(self):
        pass

    def txdone(self):
        return True


class I2C:
    def __init__(self, id=0, scl=None, sda=None, freq=400_000, **kwargs):
        self._id = id
        self.scl = _pin_id(scl)
        self.sda = _pin_id(sda)
        self.freq = freq

    def _device(self, addr):
        device = board.i2c_devices.get(self._id, {}).get(addr)
        if device is None:
            raise OSError(19)  # ENODEV: no ACK at that address, as the ESP32 port reports it
        return device

    def scan(self):
        return sorted(board.i2c_devices.get(self._id, {}))

    def writeto(self, addr, buf, stop=True):
        self._device(addr).write(bytes(buf))
        return len(buf)

    def readfrom(self, addr, nbytes, stop=True):
        return bytes(self._device(addr).read(nbytes))

    def readfrom_into(self, addr, buf, stop=True):
        data = self.readfrom(addr, len(buf))
        buf[: len(data)] = data

    def writeto_mem(self, addr, memaddr, buf, addrsize=8):
        self._device(addr).write_mem(memaddr, bytes(buf), addrsize)

    def readfrom_mem(self, addr, memaddr, nbytes, addrsize=8):
        return bytes(self._device(addr).read_mem(memaddr, nbytes, addrsize))

    def readfrom_mem_into(self, addr, memaddr, buf, addrsize=8):
        data = self.readfrom_mem(addr, memaddr, len(buf), addrsize)
        buf[: len(data)] = data


SoftI2C = I2C


class SPI:
    MSB = 0
    LSB = 1

    def __init__(self, id=1, baudrate=1_000_000, polarity=0, phase=0, sck=None, mosi=None, miso=None, **kw):
        self._id = id
        self.baudrate = baudrate
        self.polarity = polarity
        self.phase = phase
        self.sck = _pin_id(sck)
        self.mosi = _pin_id(mosi)
        self.miso = _pin_id(miso)

    def init(self, **kwargs):
        for key, value in kwargs.items():
            setattr(self, key, value)

    def _selected(self):
        # The device whose chip-select pin is driven low right now.
        for cs_id, device in board.spi_devices.items():
            pin = board.pins.get(cs_id)
            if pin is not None and pin._mode == Pin.OUT and pin._out == 0:
                return device
        return None

    def write_readinto(self, write_buf, read_buf):
        device = self._selected()
        reply = device.transfer(bytes(write_buf)) if device is not None else b"\xff" * len(write_buf)
        read_buf[: len(reply)] = reply

    def write(self, buf):
        device = self._selected()
        if device is not None:
            device.transfer(bytes(buf))

    def readinto(self, buf, write=0x00):
        out = bytearray(len(buf))
        self.write_readinto(bytes([write]) * len(buf), out)
        buf[:] = out

    def read(self, nbytes, write=0x00):
        buf = bytearray(nbytes)
        self.readinto(buf, write)
        return bytes(buf)

    def deinit(self):
        pass


SoftSPI = SPI
