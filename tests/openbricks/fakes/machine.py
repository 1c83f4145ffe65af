"""`machine` for the runtime's tests: the simulator's model (sim/shim/machine.py) on a test board.

Pins, ADC, PWM, the I2C and SPI buses, the timers, the RTC and the chip-level functions are the
simulator's, bound to `board`, a SimBoard the test sets up and reads back. Buses carry bytes to
device models that tests attach (I2C chips with register maps, an SPI IMU), so drivers are
exercised through their real wire protocol. The PCNT Encoder (counting the A/B lines a test
drives edge by edge) and the UART (a fake ST3215 answers at once, and every write is logged)
are still this module's own.
"""

from . import bounded, clock
from .hardware import board as _sim_board
from .hardware import machine as _model
from .hardware import mptime

# The simulator's definitions, as they are.
Pin = _model.Pin
Signal = _model.Signal
ADC = _model.ADC
PWM = _model.PWM
I2C = _model.I2C
SoftI2C = _model.SoftI2C
SPI = _model.SPI
SoftSPI = _model.SoftSPI
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
        self.uarts = {}  # uart id -> the last UART object constructed for it
        self.encoders = {}  # PCNT unit -> the Encoder counting on it; tests move its .count

    def set_input(self, pin_id, level):
        """Drive an input pin from outside: fires the pin's IRQ on a matching edge, and counts on
        an Encoder whose A or B line it is."""
        old = self.input_level(pin_id, 1)
        _sim_board.SimBoard.set_input(self, pin_id, 1 if level else 0)
        if old != self.input_level(pin_id):
            for encoder in self.encoders.values():
                if pin_id in (encoder.phase_a, encoder.phase_b):
                    encoder._line_changed()


board = _Board()


def _pin_id(pin):
    return _model._pin_id(pin)


def _input_level(pin_id):
    pin = board.pins.get(pin_id)
    return pin.value() if pin is not None else board.input_level(pin_id)


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


class UART(_model.UART):
    """The simulator's UART, but the device model's reply is there at once (no wire time), so the
    C serial-bus engine polling it on the tick sees it; every write is logged in `written`."""

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
