"""`machine` for a hub program running in the simulator (MicroPython 1.27, ESP32 port surface).

Installed as `sys.modules["machine"]` in the process that runs the program
(see sim.shim.install). Every class talks to the SimBoard bound with bind():
buses reach device models, inputs read sensor models, outputs notify
watchers, and Timer callbacks run on the simulated clock. Transfers take the
simulated time they take on the wire.
"""

import sys

from . import mptime

_board = [None]  # the SimBoard of the running program


def bind(board):
    """Point this module at `board` (None unbinds)."""
    _board[0] = board


def _sim():
    board = _board[0]
    if board is None:
        raise RuntimeError("the simulator's machine module is not bound to a simulated hub")
    if getattr(board, "before_first_use", None) is not None:
        board.before_first_use()  # the simulation builds its physics at the first hardware use
    return board


def _pin_id(pin):
    # Any Pin-like object names its pin (a test's pins too); a number is the pin itself.
    return pin.id() if hasattr(pin, "id") else pin


class Pin:
    IN = 1
    OUT = 3
    OPEN_DRAIN = 7
    PULL_UP = 1
    PULL_DOWN = 2
    PULL_HOLD = 4
    IRQ_RISING = 1
    IRQ_FALLING = 2
    WAKE_LOW = 4
    WAKE_HIGH = 5
    DRIVE_0 = 0
    DRIVE_1 = 1
    DRIVE_2 = 2
    DRIVE_3 = 3

    def __init__(self, id, mode=-1, pull=-1, value=None, **kwargs):
        self._id = id
        self._mode = Pin.IN
        self._pull = None
        self._out = 0
        self._handler = None
        self._trigger = 0
        _sim().pins[id] = self
        self.init(mode, pull, value)

    def init(self, mode=-1, pull=-1, value=None, **kwargs):
        if mode != -1 and mode is not None:
            self._mode = mode
        if pull != -1:
            self._pull = pull
        if value is not None:
            self._drive(value)

    def id(self):
        return self._id

    def _is_output(self):
        return self._mode in (Pin.OUT, Pin.OPEN_DRAIN)

    def _drive(self, level):
        level = 1 if level else 0
        changed = level != self._out
        self._out = level
        if changed and self._is_output():
            _sim().output_changed(self._id, level)

    def value(self, v=None):
        if v is not None:
            self._drive(v)
            return None
        if self._is_output():
            return self._out
        return _sim().input_level(self._id, 1 if self._pull == Pin.PULL_UP else 0)

    def __call__(self, v=None):
        return self.value(v)

    def on(self):
        self._drive(1)

    def off(self):
        self._drive(0)

    def irq(self, handler=None, trigger=IRQ_FALLING | IRQ_RISING, wake=None):
        # The ESP32 port's signature: no `hard=` (pin handlers are always scheduled), so a program
        # passing one gets the TypeError it would get on the hub.
        self._handler = handler
        self._trigger = trigger

    def _edge(self, level):
        wanted = Pin.IRQ_RISING if level else Pin.IRQ_FALLING
        if self._handler is not None and self._trigger & wanted:
            self._handler(self)

    def __repr__(self):
        return f"Pin({self._id})"


class Signal:
    def __init__(self, pin, invert=False):
        self._pin = pin if isinstance(pin, Pin) else Pin(pin)
        self._invert = bool(invert)

    def value(self, v=None):
        if v is None:
            return self._pin.value() ^ self._invert
        self._pin.value((1 if v else 0) ^ self._invert)
        return None

    def on(self):
        self.value(1)

    def off(self):
        self.value(0)

    def __call__(self, v=None):
        return self.value(v)


class ADC:
    ATTN_0DB = 0
    ATTN_2_5DB = 1
    ATTN_6DB = 2
    ATTN_11DB = 3
    WIDTH_9BIT = 0
    WIDTH_10BIT = 1
    WIDTH_11BIT = 2
    WIDTH_12BIT = 3

    def __init__(self, pin, atten=ATTN_11DB, **kwargs):
        self._pin = _pin_id(pin)
        self._atten = atten

    def init(self, atten=None, **kwargs):
        if atten is not None:
            self._atten = atten

    def atten(self, value):
        self._atten = value

    def width(self, value):
        pass

    def read(self):
        return _sim().analog_raw(self._pin)

    def read_u16(self):
        raw = self.read()
        return (raw << 4) | (raw >> 8)

    def read_uv(self):
        return self.read() * 3_100_000 // 4095


class PWM:
    def __init__(self, pin, freq=5000, duty=None, duty_u16=None, duty_ns=None, **kwargs):
        self._pin = _pin_id(pin)
        self._freq = freq or 5000
        self._duty_u16 = 0
        _sim().pwms[self._pin] = self
        self.init(freq=freq, duty=duty, duty_u16=duty_u16, duty_ns=duty_ns)

    def init(self, freq=None, duty=None, duty_u16=None, duty_ns=None, **kwargs):
        if freq:
            self._freq = freq
        if duty is not None:
            self._set(int(duty) * 65535 // 1023)
        if duty_u16 is not None:
            self._set(duty_u16)
        if duty_ns is not None:
            self._set(int(duty_ns) * self._freq * 65535 // 1_000_000_000)

    def _set(self, duty_u16):
        duty_u16 = max(0, min(65535, int(duty_u16)))
        if duty_u16 != self._duty_u16:
            self._duty_u16 = duty_u16
            _sim().output_changed(self._pin, duty_u16 / 65535)

    def freq(self, f=None):
        if f is None:
            return self._freq
        self._freq = f
        return None

    def duty(self, d=None):
        if d is None:
            return self._duty_u16 * 1023 // 65535
        self._set(int(d) * 65535 // 1023)
        return None

    def duty_u16(self, d=None):
        if d is None:
            return self._duty_u16
        self._set(d)
        return None

    def duty_ns(self, d=None):
        if d is None:
            return self._duty_u16 * 1_000_000_000 // (65535 * self._freq)
        self._set(int(d) * self._freq * 65535 // 1_000_000_000)
        return None

    def deinit(self):
        self._set(0)


# Count change per (previous AB << 2 | new AB), AB = A << 1 | B; +1 for A leading B, as the ESP32
# port's machine.Encoder counts; 0 where both lines changed at once.
_QUADRATURE_STEP = (0, -1, 1, 0, 1, 0, 0, -1, -1, 0, 0, 1, 0, 1, -1, 0)


class Encoder:
    """ESP32 PCNT quadrature counter: unit `id` counts the edges of its A/B lines, every edge with
    phases=4, one per cycle with phases=1.

    A model that reports the edges on phase_a (board.set_encoder: the simulator's wheels, whose
    lines toggle too fast to be worth driving one by one) is counted as it reports them; otherwise
    the unit decodes the levels driven onto its lines (board.set_input) edge by edge, as the
    peripheral does. The unit is the board's (board.pcnt_units) until deinit() frees it.
    """

    def __init__(self, id, phase_a=None, phase_b=None, **kwargs):
        self._id = id
        self._phase_a = self._phase_b = None
        self.init(phase_a, phase_b, **kwargs)

    def init(self, phase_a=None, phase_b=None, filter_ns=0, phases=1, **kwargs):
        if phase_a is not None:
            self._phase_a = _pin_id(phase_a)
        if phase_b is not None:
            self._phase_b = _pin_id(phase_b)
        self._filter_ns = filter_ns
        self._phases = phases
        self._lines = self._line_levels()
        self._decoded = 0  # edges decoded from the lines since init()
        self._offset = self._edges()
        _sim().pcnt_units[self._id] = self

    def _line_levels(self):
        board = _sim()
        levels = 0
        for pin_id in (self._phase_a, self._phase_b):
            pin = board.pins.get(pin_id)
            levels = levels << 1 | (pin.value() if pin is not None else board.input_level(pin_id))
        return levels

    def _line_changed(self):
        lines = self._line_levels()
        self._decoded += _QUADRATURE_STEP[(self._lines << 2) | lines]
        self._lines = lines

    def _edges(self):
        edges = _sim().encoder_edges(self._phase_a)
        return (self._decoded if edges is None else edges) * self._phases // 4

    def value(self, value=None):
        current = self._edges() - self._offset
        if value is not None:
            self._offset = self._edges() - int(value)
        return current

    def deinit(self):
        units = _sim().pcnt_units
        if units.get(self._id) is self:
            del units[self._id]


# The ESP32-S3's four general-purpose timers; the port has no virtual (id -1) timers.
HARDWARE_TIMER_COUNT = 4


class Timer:
    """A hardware timer. Timer(id) names one of the chip's timers, so every Timer built for the
    same id drives one alarm: a second init() replaces the first one's callback, as on the hub."""

    ONE_SHOT = 0
    PERIODIC = 1

    def __init__(self, id, **kwargs):
        if not isinstance(id, int) or not 0 <= id < HARDWARE_TIMER_COUNT:
            raise ValueError(
                f"Timer({id!r}) doesn't exist: the ESP32 has hardware timers 0..{HARDWARE_TIMER_COUNT - 1}"
                " and no virtual timers"
            )
        self._id = id
        if kwargs:
            self.init(**kwargs)

    def init(self, mode=PERIODIC, period=-1, freq=-1, callback=None):
        if freq is not None and freq > 0:
            period_us = 1_000_000 // freq
        else:
            period_us = int(period) * 1000
        if period_us <= 0:
            raise ValueError("Timer: give period= (ms) or freq= (Hz)")
        self.deinit()
        board = _sim()

        def fire():
            if mode == Timer.ONE_SHOT:
                board.hardware_timers.pop(self._id, None)
            if callback is None:
                return
            try:
                callback(self)
            except Exception as exc:  # noqa: BLE001 - the hub prints a failing callback and carries on
                # The port runs timer callbacks from its scheduler, which prints what they raise;
                # the program that was sleeping never sees it and the timer keeps firing.
                sys.print_exception(exc)

        board.hardware_timers[self._id] = board.clock.schedule(
            fire, period_us, period_us if mode == Timer.PERIODIC else 0
        )

    def deinit(self):
        handle = _sim().hardware_timers.pop(self._id, None)
        if handle is not None:
            handle.cancel()

    def value(self):
        return 0

    def __repr__(self):
        return f"Timer({self._id})"


class WDT:
    def __init__(self, id=0, timeout=5000):
        self.timeout = timeout

    def feed(self):
        pass


class RTC:
    def __init__(self, id=0):
        pass

    def datetime(self, dt=None):
        clock = _sim().clock
        if dt is None:
            epoch_us = clock.epoch_us()
            t = mptime.gmtime(epoch_us // 1_000_000)
            return (t[0], t[1], t[2], t[6], t[3], t[4], t[5], epoch_us % 1_000_000)
        year, month, day, _weekday, hours, minutes, seconds, subseconds = dt
        secs = mptime.mktime((year, month, day, hours, minutes, seconds, 0, 0))
        clock.set_epoch_ms(secs * 1000 + subseconds // 1000)
        return None

    def init(self, dt):
        self.datetime(dt)


class UART:
    """A UART whose far end is a device model; a reply can be read once the board says it has
    come back over the wire (board.uart_reply_delay_us)."""

    INV_TX = 1
    INV_RX = 2
    RTS = 1
    CTS = 2

    def __init__(self, id, baudrate=115200, **kwargs):
        self._id = id
        self._rx = bytearray()
        self._rx_ready_us = 0
        self._deinited = False
        self.init(baudrate, **kwargs)
        _sim().uarts[id] = self

    def init(self, baudrate=115200, bits=8, parity=None, stop=1, tx=None, rx=None, timeout=0, **kwargs):
        self._baud = int(baudrate) or 115200
        self._tx_pin = _pin_id(tx)
        self._rx_pin = _pin_id(rx)
        self._timeout_ms = timeout
        self._deinited = False

    def deinit(self):
        self._deinited = True

    def _check(self):
        if self._deinited:
            raise OSError(f"UART{self._id} is deinitialised")

    def _wire_us(self, nbytes):
        return nbytes * 10 * 1_000_000 // self._baud

    def write(self, data):
        self._check()
        data = bytes(data)
        board = _sim()
        device = board.uart_devices.get(self._id)
        now = board.clock.now_us()
        if device is not None:
            reply = device.handle(data)
            if reply:
                self._rx.extend(reply)
                self._rx_ready_us = now + board.uart_reply_delay_us(self._wire_us(len(data) + len(reply)))
        return len(data)

    def any(self):
        self._check()
        if self._rx and _sim().clock.now_us() >= self._rx_ready_us:
            return len(self._rx)
        return 0

    def read(self, n=None):
        waiting = self.any()
        if not waiting:
            if self._timeout_ms:
                clock = _sim().clock
                clock.advance_us(self._timeout_ms * 1000)
                waiting = self.any()
            if not waiting:
                return None
        n = waiting if n is None else min(n, waiting)
        out = bytes(self._rx[:n])
        self._rx = self._rx[n:]  # MicroPython bytearrays do not support slice deletion
        return out

    def readinto(self, buf, nbytes=None):
        data = self.read(len(buf) if nbytes is None else nbytes)
        if not data:
            return None
        buf[: len(data)] = data
        return len(data)

    def readline(self):
        waiting = self.any()
        if not waiting:
            return None
        end = self._rx.find(b"\n")
        return self.read(waiting if end < 0 else end + 1)

    def flush(self):
        pass

    def txdone(self):
        return True

    def sendbreak(self):
        pass


class I2C:
    """Hardware I2C: devices attached to the board under this bus id. SoftI2C keys by its pins."""

    def __init__(self, id=0, scl=None, sda=None, freq=400_000, timeout=50_000, **kwargs):
        self._key = id
        self._freq = freq or 400_000

    def init(self, scl=None, sda=None, freq=None, **kwargs):
        if freq:
            self._freq = freq

    def _devices(self):
        return _sim().i2c_bus(self._key)

    def _device(self, addr):
        device = self._devices().get(addr)
        self._charge(1)
        if device is None:
            raise OSError(19)  # ENODEV: nothing acknowledged the address, as the ESP32 port reports it
        return device

    def _charge(self, nbytes):
        _sim().clock.charge_cpu_us(nbytes * 9 * 1_000_000 // self._freq)

    def scan(self):
        self._charge(128)
        return sorted(self._devices())

    def writeto(self, addr, buf, stop=True):
        self._device(addr).write(bytes(buf))
        self._charge(len(buf))
        return len(buf)

    def readfrom(self, addr, nbytes, stop=True):
        data = bytes(self._device(addr).read(nbytes))
        self._charge(nbytes)
        return data

    def readfrom_into(self, addr, buf, stop=True):
        data = self.readfrom(addr, len(buf))
        buf[: len(data)] = data

    def writevto(self, addr, vector, stop=True):
        return self.writeto(addr, b"".join(bytes(b) for b in vector), stop)

    def writeto_mem(self, addr, memaddr, buf, addrsize=8):
        self._device(addr).write_mem(memaddr, bytes(buf), addrsize)
        self._charge(len(buf) + addrsize // 8)

    def readfrom_mem(self, addr, memaddr, nbytes, addrsize=8):
        data = bytes(self._device(addr).read_mem(memaddr, nbytes, addrsize))
        self._charge(nbytes + addrsize // 8 + 1)
        return data

    def readfrom_mem_into(self, addr, memaddr, buf, addrsize=8):
        data = self.readfrom_mem(addr, memaddr, len(buf), addrsize)
        buf[: len(data)] = data


class SoftI2C(I2C):
    def __init__(self, scl, sda, freq=400_000, timeout=50_000, **kwargs):
        I2C.__init__(self, ("soft", _pin_id(scl), _pin_id(sda)), freq=freq)


class SPI:
    MSB = 0
    LSB = 1
    CONTROLLER = 0

    def __init__(self, id=1, baudrate=1_000_000, polarity=0, phase=0, **kwargs):
        self._id = id
        self._baud = baudrate or 1_000_000

    def init(self, baudrate=None, **kwargs):
        if baudrate:
            self._baud = baudrate

    def _transfer(self, data):
        board = _sim()
        board.clock.charge_cpu_us(len(data) * 8 * 1_000_000 // self._baud)
        device = board.spi_selected()
        if device is None:
            return b"\xff" * len(data)  # nothing drives MISO: the pull-up reads all ones
        return bytes(device.transfer(bytes(data)))

    def write(self, buf):
        self._transfer(buf)

    def write_readinto(self, write_buf, read_buf):
        read_buf[:] = self._transfer(write_buf)[: len(read_buf)]

    def readinto(self, buf, write=0x00):
        buf[:] = self._transfer(bytes([write]) * len(buf))

    def read(self, nbytes, write=0x00):
        return self._transfer(bytes([write]) * nbytes)

    def deinit(self):
        pass


class SoftSPI(SPI):
    def __init__(self, baudrate=500_000, polarity=0, phase=0, sck=None, mosi=None, miso=None, **kwargs):
        SPI.__init__(self, -1, baudrate)


def time_pulse_us(pin, pulse_level, timeout_us=1_000_000):
    """The echo width the board's model reports for pin, after waiting that long. On a timeout
    (no model, or a width past timeout_us) it waits timeout_us and returns -1; a model may also
    report the port's own timeouts, -1 (pulse too long) or -2 (it never started)."""
    board = _sim()
    width = board.pulse_us(_pin_id(pin), pulse_level)
    if width is None or width < 0 or width > timeout_us:
        board.clock.advance_us(timeout_us)
        return width if width is not None and width in (-1, -2) else -1
    board.clock.advance_us(width)
    return width


def bitstream(pin, encoding, timing, data):
    board = _sim()
    board.record_bitstream(_pin_id(pin), timing, data)
    board.clock.charge_cpu_us(len(data) * 8 * (timing[0] + timing[1]) // 1000 if len(timing) > 1 else 0)


def freq(hz=None):
    return 240_000_000 if hz is None else None


def unique_id():
    return b"\x5e\x1a\x0b\x00\x00\x01"


def reset():
    """A hard reset ends the simulated program (the run's result says so)."""
    _sim().reset_requested = True
    raise SystemExit("machine.reset()")


def soft_reset():
    reset()


def idle():
    _sim().clock.advance_us(100)


def lightsleep(time_ms=None):
    _sim().clock.advance_us(int(time_ms or 0) * 1000)


def deepsleep(time_ms=None):
    reset()


def disable_irq():
    return 0


def enable_irq(state=0):
    pass


def reset_cause():
    return PWRON_RESET


PWRON_RESET = 1
HARD_RESET = 2
WDT_RESET = 3
DEEPSLEEP_RESET = 4
SOFT_RESET = 5
