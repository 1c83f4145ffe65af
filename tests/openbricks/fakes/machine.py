"""`machine` for the runtime's tests: the simulator's model (sim/shim/machine.py) on a test board.

Every class is the simulator's, bound to `board`, a SimBoard the test sets up and reads back.
Buses carry bytes to device models that tests attach (I2C chips with register maps, an SPI IMU,
servos on a UART), so drivers are exercised through their real wire protocol; PCNT units count
the A/B lines a test drives edge by edge, or the edges a shaft model reports.
"""

from . import clock
from .hardware import board as _sim_board
from .hardware import machine as _model

# The simulator's definitions, as they are.
Pin = _model.Pin
Signal = _model.Signal
ADC = _model.ADC
PWM = _model.PWM
I2C = _model.I2C
SoftI2C = _model.SoftI2C
SPI = _model.SPI
UART = _model.UART
Encoder = _model.Encoder
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
    """Everything outside the chip, as the test sets it up and reads it back: a fresh simulator's
    board on the test's clock for every test."""

    def __init__(self):
        self.reset()

    def reset(self):
        _sim_board.SimBoard.__init__(self, clock.current())
        _model.bind(self)

    def uart_reply_delay_us(self, wire_us):
        """A test's serial device answers at once: the C serial-bus engine, which on the host keeps
        the wire's clock itself over a Python UART, reads the reply on the tick that asked for it."""
        return 0


board = _Board()
