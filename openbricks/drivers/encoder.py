"""Quadrature encoders: counts of A/B edges (x4 decoding), read by the motor drivers.

Two ways to count, one interface (`count()`, `reset(count)`, `close()`); `make_encoder()` picks the
peripheral when the runtime has it and the interrupt decoder otherwise:

- QuadratureEncoder decodes in a pin-change interrupt. Fine for Hall
  encoders behind a gearbox (a JGB37-520 at 300 RPM is ~6.6 k edges/s), but
  Pin.irq tops out around 5-10 kHz of edges: the ESP32 port has no hard pin
  interrupts, it queues every handler on the MicroPython scheduler, so a
  burst the queue cannot hold skips states (counted in `missed`).
- PCNTEncoder lets the ESP32's pulse-counter peripheral count, with its glitch
  filter, for high-resolution GMR encoders (MG370) whose edge rate no
  interrupt handler could keep up with. One PCNT unit per encoder (ESP32 has
  8, ESP32-S3 has 4). On the firmware the counter is the native PCNTEncoder
  (`_openbricks_native`, the encoder core in C): the hard tick reads the unit
  every millisecond and unwraps its 16-bit counter, whatever Python is doing.
  Elsewhere it is machine.Encoder (the simulator's). The default wherever
  either exists: it costs no CPU per edge and misses none, and the simulator
  counts encoders this way too (it has no per-edge pin interrupts).

Both count up for A leading B, so a motor keeps its direction whichever counts.
"""

from openbricks import _native, pins
from openbricks.drivers import claim_pins, release_pins

# Count change for (previous AB state << 2 | new AB state), AB = (A << 1) | B. Forward is
# A leading B: 00 -> 10 -> 11 -> 01. Both bits changing at once means an edge was missed: 0.
_STEP = (0, -1, 1, 0, 1, 0, 0, -1, -1, 0, 0, 1, 0, 1, -1, 0)
_MISSED = (3, 6, 9, 12)  # transitions where both channels changed

# PCNT filter: the manual counts it in 80 MHz APB cycles (1023 ~ 12.8 us); machine.Encoder takes ns.
_NS_PER_APB_CYCLE = 12.5
# PCNT units (machine.Encoder ids) per chip; off-chip (simulator, tests) nothing bounds them.
_PCNT_UNITS = {pins.ESP32: 8, pins.ESP32S3: 4}


def make_encoder(pin_a, pin_b, invert=False, name="encoder", unit=None, filter=1023, counts_per_rev=4):
    """The encoder counter this runtime does best: a PCNT unit, else the pin-interrupt decoder.

    `unit` is the PCNT unit to count on; None takes the lowest free one, and when every unit of the
    chip is taken the encoder counts in a pin interrupt instead. A runtime without machine.Encoder
    (a MicroPython port other than the ESP32's) always counts in a pin interrupt. `counts_per_rev`
    (edges per output turn) lets the native counter report degrees too.
    """
    import machine

    if _hub_counter() is not None or getattr(machine, "Encoder", None) is not None:
        if unit is None:
            unit = free_pcnt_unit()
        if unit is not None:
            return PCNTEncoder(
                pin_a,
                pin_b,
                unit=unit,
                filter=filter,
                invert=invert,
                name=name,
                counts_per_rev=counts_per_rev,
            )
    return QuadratureEncoder(pin_a, pin_b, invert=invert, name=name)


def _hub_counter():
    """The firmware's native PCNTEncoder when this build counts pins with it (the ESP32 image), else None."""
    counter = _native.get("PCNTEncoder")
    return counter if counter is not None and counter.HARDWARE else None


def free_pcnt_unit():
    """The lowest PCNT unit no live encoder counts on, or None when the chip has none left."""
    limit = _PCNT_UNITS.get(pins.chip())
    unit = 0
    while limit is None or unit < limit:
        holder = PCNTEncoder._units.get(unit)
        if holder is None or not holder._live():
            return unit
        unit += 1
    return None


class QuadratureEncoder:
    """x4 decoding of an A/B encoder in a (scheduled) pin interrupt.

    The handler reads both lines when it runs, not at the edge, so a late
    handler still counts the right way as long as the lines moved at most one
    state since the last one.
    """

    def __init__(self, pin_a, pin_b, invert=False, name="encoder"):
        from machine import Pin

        self._pins = (pin_a, pin_b)
        claim_pins(self, ((pin_a, name + " A", False), (pin_b, name + " B", False)))
        self._sign = -1 if invert else 1
        self._a = Pin(pin_a, Pin.IN, Pin.PULL_UP)
        self._b = Pin(pin_b, Pin.IN, Pin.PULL_UP)
        self._state = (self._a.value() << 1) | self._b.value()
        self._count = 0
        self.missed = 0  # transitions that skipped a state: edges came faster than the interrupt
        trigger = Pin.IRQ_RISING | Pin.IRQ_FALLING
        self._a.irq(self._edge, trigger)
        self._b.irq(self._edge, trigger)

    def _edge(self, _pin):
        state = (self._a.value() << 1) | self._b.value()
        transition = (self._state << 2) | state
        self._count += _STEP[transition]
        if transition in _MISSED:
            self.missed += 1
        self._state = state

    def count(self):
        return self._count * self._sign

    def native_counter(self):
        """None: this encoder is counted in Python (a pin interrupt)."""
        return None

    def reset(self, count=0):
        self._count = count * self._sign

    def close(self):
        self._a.irq(None)
        self._b.irq(None)
        release_pins(self, self._pins)


class PCNTEncoder:
    """x4 counting of an A/B encoder by a PCNT unit: the firmware's native counter, else machine.Encoder."""

    _units = {}  # unit -> the encoder counting on it

    def __init__(self, pin_a, pin_b, unit=0, filter=1023, invert=False, name="encoder", counts_per_rev=4):
        from machine import Pin

        PCNTEncoder._close_leftovers()
        holder = PCNTEncoder._units.get(unit)
        if holder is not None:
            raise ValueError(
                "PCNT unit %d already counts the encoder on GPIO %d/%d; give each motor its own "
                "pcnt_unit (ESP32: 0-7, ESP32-S3: 0-3)" % (unit, holder._pins[0], holder._pins[1])
            )
        if not 0 <= filter <= 1023:
            raise ValueError("pcnt_filter=%r: the PCNT glitch filter takes 0..1023 APB cycles" % (filter,))
        self._pins = (pin_a, pin_b)
        claim_pins(self, ((pin_a, name + " A", False), (pin_b, name + " B", False)))
        self._sign = -1 if invert else 1
        try:
            native = _hub_counter()
            if native is not None:
                # The core applies the direction itself, and the hard tick keeps it counting.
                # The core counts whole edges per turn; a calibrated fractional figure only moves its
                # angle(), which the motors do not use (they scale count() themselves).
                self._native = native(
                    max(1, int(counts_per_rev + 0.5)),
                    invert=invert,
                    pin_a=pin_a,
                    pin_b=pin_b,
                    unit=unit,
                    filter=filter,
                )
                self._sign = 1
            else:
                from machine import Encoder

                self._native = None
                self._encoder = Encoder(
                    unit,
                    Pin(pin_a, Pin.IN),
                    Pin(pin_b, Pin.IN),
                    phases=4,
                    filter_ns=int(filter * _NS_PER_APB_CYCLE),
                )
        except Exception:
            release_pins(self, self._pins)
            raise
        self.unit = unit
        PCNTEncoder._units[unit] = self

    def _live(self):
        owner = pins.owner_of(self._pins[0])
        return owner is not None and owner[1] is self

    @staticmethod
    def _close_leftovers():
        """Forget the encoders of a finished program (the launcher already took their pins back). A
        native counter still holds a hardware unit and a hard-tick slot: those are given back here."""
        for unit, holder in list(PCNTEncoder._units.items()):
            if not holder._live():
                if holder._native is not None:
                    holder._native.close()
                del PCNTEncoder._units[unit]

    def native_counter(self):
        """The firmware's encoder core counting this unit (read in C by the hard tick), or None."""
        return self._native

    def count(self):
        if self._native is not None:
            return self._native.count()
        return self._encoder.value() * self._sign

    def reset(self, count=0):
        if self._native is not None:
            self._native.reset(count)
        else:
            self._encoder.value(count * self._sign)

    def close(self):
        if self._native is not None:
            self._native.close()
        else:
            self._encoder.deinit()
        release_pins(self, self._pins)
        if PCNTEncoder._units.get(self.unit) is self:
            del PCNTEncoder._units[self.unit]
