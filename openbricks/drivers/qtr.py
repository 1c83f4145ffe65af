"""Pololu QTR / QTRX analog reflectance arrays: line position, edges and markers.

Each element is an IR emitter/phototransistor pair a few millimetres above
the mat; its output rises over a dark line. Raw readings depend on mounting
height, mat and light, so every element is calibrated to its own mat (0) and
line (1000) extremes by sweeping the array across the line; reading before
that raises, because an uncalibrated centroid is a plausible-looking wrong
number.

Coordinates are millimetres in the array's frame, 0 at its centre unless
`positions_mm` says otherwise, positive to the RIGHT. One `read()` takes a
coherent snapshot (`QTRReading`) from which a control tick derives every
view it needs: centroid, edges, fork clusters, the edge-follower error.
"""

import json
import time

from machine import ADC, Pin
from micropython import const

from openbricks import pins

DEFAULT_CALIBRATION_PATH = "/qtr.cal"
_CALIBRATION_FORMAT = "openbricks-qtr-1"
_FULL_SCALE = const(1000)
# An element whose sweep moved its ADC less than this (in read_u16 counts, ~1 % of 3.1 V) never
# saw the line: scaling that span to 0..1000 would turn noise into full-range jumps.
_MIN_SPAN = const(655)
_ENOENT = const(2)
_CALIBRATE_HINT = "sweep it across the line while calibrate() runs, or load_calibration() recorded by "
_CALIBRATE_SCRIPT = "examples/qtr_calibrate.py"


class QTRElement:
    """One calibrated element of a reading: `value` 0 (mat) .. 1000 (line).

    Deliberately not an int subclass: MicroPython cannot reflect-compare an
    int against one, so `max()` over readings would raise on the hub while
    passing on a desktop. Numeric code uses `.value`.
    """

    def __init__(self, value, threshold):
        self.value = value
        self._threshold = threshold

    def dark(self):
        """True when this element is over the line."""
        return self.value > self._threshold

    def white(self):
        """True when this element is over the mat."""
        return self.value <= self._threshold

    def ambient(self):
        """Reflected brightness 0 (black) .. 100 (white): the Pybricks scale, inverted from `value`."""
        return (_FULL_SCALE - self.value) // 10

    def __repr__(self):
        return "QTRElement(%d)" % self.value


class QTRReading:
    """One snapshot of the whole array: a list of QTRElement left to right, plus every
    aggregate view of exactly this sample (position, edges, clusters, edge_error, ...)."""

    def __init__(self, elements, array):
        self.elements = elements
        self._array = array

    def __len__(self):
        return len(self.elements)

    def __getitem__(self, index):
        return self.elements[index]

    def __iter__(self):
        return iter(self.elements)

    def values(self):
        """The plain 0..1000 ints, left to right."""
        return [e.value for e in self.elements]

    def max(self):
        """The highest calibrated value in this snapshot (the element most over the line): the
        follower's off-mat phantom gate, since lifted off the mat nothing reads high."""
        return max(self.values())

    def dark_count(self):
        """How many elements of this snapshot are over the line (see QTRArray.dark_count())."""
        return self._array.dark_count(self)

    def all_dark(self):
        """Every element over the line (a crossing or the stop bar is under the array)."""
        return self._array.dark_count(self) == len(self.elements)

    def position(self):
        """Line centre in mm of this snapshot, positive = right of centre; None when no line is seen."""
        return self._array.position(self)

    def left_edge_position(self):
        """The line's LEFT edge in mm in this snapshot; None when nothing is dark."""
        return self._array.left_edge_position(self)

    def right_edge_position(self):
        """The line's RIGHT edge in mm in this snapshot; None when nothing is dark."""
        return self._array.right_edge_position(self)

    def edge_error(self):
        """Steering error -50 .. +50 of this snapshot for the set_mode() discipline (+ = steer right)."""
        return self._array.edge_error(self)

    def leftmost_position(self):
        """Centre (mm) of the leftmost dark cluster of this snapshot (the left fork), or None."""
        return self._array.leftmost_position(self)

    def rightmost_position(self):
        """Centre (mm) of the rightmost dark cluster of this snapshot (the right fork), or None."""
        return self._array.rightmost_position(self)

    def __repr__(self):
        return "QTRReading(%r)" % self.values()


class QTRArray:
    """Analog QTR/QTRX array on ESP32 ADC pins, listed LEFT to RIGHT as mounted.

    `pitch_mm` is the spacing of the wired channels (elements centred on the
    array) unless `positions_mm` gives each element's true coordinate, e.g.
    for a skip pattern. `ctrl` is the optional emitter-enable GPIO (driven
    high: emitters on). `dark_threshold` is the calibrated value above which
    an element counts as over the line.
    """

    #: Where set_mode("left") holds the line's LEFT edge, in mm from the array's centre.
    LEFT_SETPOINT_MM = 0.0
    #: Where set_mode("right") holds the line's RIGHT edge, in mm from the array's centre.
    RIGHT_SETPOINT_MM = 0.0
    #: The manual's spelling of LEFT_SETPOINT_MM (the same value).
    LEFT_SETPPOINT_MM = 0.0
    #: The manual's spelling of RIGHT_SETPOINT_MM (the same value).
    RIGHT_SETPPOINT_MM = 0.0

    def __init__(self, pins, pitch_mm=4.0, ctrl=None, dark_threshold=300, positions_mm=None):
        pin_list = tuple(pins)
        if not pin_list:
            raise ValueError("QTRArray needs at least one ADC pin")
        if len(set(pin_list)) != len(pin_list):
            raise ValueError("QTRArray pins must be distinct, got %r" % (pin_list,))
        if not 0 <= dark_threshold < _FULL_SCALE:
            raise ValueError("dark_threshold is a calibrated value 0..999, got %r" % (dark_threshold,))
        if not pitch_mm > 0:
            raise ValueError("pitch_mm must be positive, got %r" % (pitch_mm,))
        n = len(pin_list)
        if positions_mm is None:
            positions_mm = [(i - (n - 1) / 2) * pitch_mm for i in range(n)]
        positions_mm = tuple(float(x) for x in positions_mm)
        if len(positions_mm) != n:
            raise ValueError("positions_mm has %d entries for %d pins" % (len(positions_mm), n))
        for i in range(1, n):
            if positions_mm[i] <= positions_mm[i - 1]:
                raise ValueError("positions_mm must increase left to right, got %r" % (positions_mm,))
        self._pins = pin_list
        self._positions = positions_mm
        self._pitch = pitch_mm
        self._threshold = dark_threshold
        self._adcs = []
        for pin in pin_list:
            _claim(pin, "QTR analog input", self, output=False)
            self._adcs.append(ADC(Pin(pin), atten=ADC.ATTN_11DB))
        self._ctrl = None
        if ctrl is not None:
            _claim(ctrl, "QTR emitter control (CTRL)", self)
            self._ctrl = Pin(ctrl, Pin.OUT, value=1)
        self._lo = None  # per-element raw extremes once calibration has begun
        self._hi = None
        self._mode = None
        self._setpoint = None  # (index, fraction) where edge_error samples the array
        self._last_side = 0

    # -- geometry ------------------------------------------------------------------------------

    @property
    def pins(self):
        return self._pins

    @property
    def positions_mm(self):
        return self._positions

    # -- raw samples and calibration -----------------------------------------------------------

    def raw(self):
        """Uncalibrated ADC readings (read_u16 counts), left to right."""
        return [adc.read_u16() for adc in self._adcs]

    def calibrate(self, duration_ms=3000, poll_ms=5):
        """Learn each element's mat/line extremes while the array is swept across the line.

        Extends any earlier calibration instead of replacing it, so repeated calls refine.
        """
        n = len(self._adcs)
        if self._lo is None:
            self._lo = [65535] * n
            self._hi = [0] * n
        lo, hi = self._lo, self._hi
        start = time.ticks_ms()
        while True:
            for i, value in enumerate(self.raw()):
                if value < lo[i]:
                    lo[i] = value
                if value > hi[i]:
                    hi[i] = value
            if time.ticks_diff(time.ticks_ms(), start) >= duration_ms:
                break
            time.sleep_ms(poll_ms)

    def calibration(self):
        """Per-element (min, max) raw extremes, or None before any calibration; a narrow span
        next to wide neighbours points at a mounting or wiring problem on that element."""
        if self._lo is None:
            return None
        return [(self._lo[i], self._hi[i]) for i in range(len(self._lo))]

    def calibrated(self):
        """True when every element has seen both mat and line."""
        return self._lo is not None and not self._narrow_elements()

    def _narrow_elements(self):
        return [i for i in range(len(self._lo)) if self._hi[i] - self._lo[i] < _MIN_SPAN]

    def _require_calibration(self):
        if self._lo is None:
            raise RuntimeError(
                "%s is not calibrated: %s%s (saved to %s)"
                % (self._describe(), _CALIBRATE_HINT, _CALIBRATE_SCRIPT, DEFAULT_CALIBRATION_PATH)
            )
        narrow = self._narrow_elements()
        if narrow:
            raise RuntimeError(
                "%s calibration is incomplete: element(s) %s (GPIO %s) never saw both mat and line; "
                "%s%s"
                % (
                    self._describe(),
                    narrow,
                    ", ".join(str(self._pins[i]) for i in narrow),
                    _CALIBRATE_HINT,
                    _CALIBRATE_SCRIPT,
                )
            )

    def save_calibration(self, path=DEFAULT_CALIBRATION_PATH):
        """Persist the calibration, with the wiring it belongs to, so one sweep serves later runs."""
        self._require_calibration()
        record = {"format": _CALIBRATION_FORMAT, "pins": list(self._pins), "min": self._lo, "max": self._hi}
        with open(path, "w") as f:
            f.write(json.dumps(record))

    def load_calibration(self, path=DEFAULT_CALIBRATION_PATH):
        """Load a calibration written by save_calibration(); refuses one recorded for other wiring.

        Calibration depends on height and mat: resweep after remounting the array or changing mats.
        """
        try:
            with open(path) as f:
                text = f.read()
        except OSError:
            raise OSError(
                _ENOENT,
                "no QTR calibration at %s: run %s on this robot (it sweeps the array and saves it there)"
                % (path, _CALIBRATE_SCRIPT),
            ) from None
        lo, hi, wired = _parse_calibration(text, len(self._pins), path)
        if tuple(wired) != self._pins:
            raise ValueError(
                "QTR calibration %s was recorded for GPIO %s, but this %s is wired to GPIO %s: a "
                "calibration is per element, so it would mis-scale every reading; recalibrate this "
                "wiring with %s" % (path, tuple(wired), type(self).__name__, self._pins, _CALIBRATE_SCRIPT)
            )
        self._lo = lo
        self._hi = hi

    # -- reading -------------------------------------------------------------------------------

    def read(self):
        """One calibrated snapshot: a QTRReading of QTRElement, left to right."""
        self._require_calibration()
        lo, hi, threshold = self._lo, self._hi, self._threshold
        elements = []
        for i, raw in enumerate(self.raw()):
            value = (raw - lo[i]) * _FULL_SCALE // (hi[i] - lo[i])
            elements.append(QTRElement(min(_FULL_SCALE, max(0, value)), threshold))
        reading = QTRReading(elements, self)
        centre = self.position(reading)
        if centre is not None and centre != 0:
            self._last_side = 1 if centre > 0 else -1
        return reading

    def _values(self, readings):
        if readings is None:
            readings = self.read()
        if isinstance(readings, QTRReading):
            return readings.values()
        return [r.value if isinstance(r, QTRElement) else r for r in readings]

    def dark_count(self, readings=None):
        """How many elements are over the line (a full-width bar darkens most, a branch stub one side)."""
        threshold = self._threshold
        return sum(1 for v in self._values(readings) if v > threshold)

    def position(self, readings=None):
        """Line centre in mm, positive = line RIGHT of centre; None when no element sees the line.

        A value-weighted centroid over every element, so partly covered elements at the line's
        sides add sub-pitch resolution. At a fork it lands between the two lines: steer on
        leftmost_position()/rightmost_position() there.
        """
        values = self._values(readings)
        if not any(v > self._threshold for v in values):
            return None
        return _centroid(values, self._positions, 0, len(values))

    def left_edge_position(self, readings=None):
        """The line's LEFT edge in mm: where the calibrated value crosses dark_threshold between the
        last mat element and the leftmost dark one; None when nothing is dark.

        With the leftmost element itself dark the true edge is off the array; the estimate then
        saturates half a gap beyond it, keeping the error's sign and size instead of vanishing.
        """
        values = self._values(readings)
        first = _first_dark(values, self._threshold)
        if first is None:
            return None
        x = self._positions
        if first == 0:
            return x[0] - self._half_gap(0, 1)
        return _crossing(values, x, first - 1, first, self._threshold)

    def right_edge_position(self, readings=None):
        """Mirror of left_edge_position(): the line's RIGHT edge in mm, saturating half a gap
        beyond a dark rightmost element; None when nothing is dark."""
        values = self._values(readings)
        last = _last_dark(values, self._threshold)
        if last is None:
            return None
        x = self._positions
        n = len(values)
        if last == n - 1:
            return x[n - 1] + self._half_gap(n - 1, n - 2)
        return _crossing(values, x, last, last + 1, self._threshold)

    def leftmost_position(self, readings=None):
        """Centre (mm) of the LEFTMOST contiguous dark cluster, or None: at a fork, the left line's
        own centre, where the global centroid would steer into the gap."""
        values = self._values(readings)
        first = _first_dark(values, self._threshold)
        if first is None:
            return None
        end = first
        while end < len(values) and values[end] > self._threshold:
            end += 1
        return _centroid(values, self._positions, first, end)

    def rightmost_position(self, readings=None):
        """Centre (mm) of the RIGHTMOST contiguous dark cluster, or None: the right fork."""
        values = self._values(readings)
        last = _last_dark(values, self._threshold)
        if last is None:
            return None
        begin = last
        while begin > 0 and values[begin - 1] > self._threshold:
            begin -= 1
        return _centroid(values, self._positions, begin, last + 1)

    def last_side(self):
        """+1 if the line was last seen right of centre, -1 left, 0 never off-centre: which way
        to search after losing the line."""
        return self._last_side

    # -- edge following ------------------------------------------------------------------------

    def set_mode(self, mode):
        """Select the edge discipline: "left" holds the line's LEFT edge at LEFT_SETPOINT_MM,
        "right" the RIGHT edge at RIGHT_SETPOINT_MM. Takes effect on the next edge_error();
        call again any time to switch mid-run."""
        if mode == "left":
            setpoint = self.LEFT_SETPOINT_MM
        elif mode == "right":
            setpoint = self.RIGHT_SETPOINT_MM
        else:
            raise ValueError('QTR mode must be "left" or "right", got %r' % (mode,))
        x = self._positions
        if not x[0] <= setpoint <= x[-1]:
            raise ValueError(
                "%s setpoint %.1f mm is outside this array's window (%.1f .. %.1f mm): set %s_SETPOINT_MM "
                "to a position the elements cover" % (mode, setpoint, x[0], x[-1], mode.upper())
            )
        index = 0
        while index < len(x) - 1 and x[index + 1] <= setpoint:
            index += 1
        fraction = 0.0 if index == len(x) - 1 else (setpoint - x[index]) / (x[index + 1] - x[index])
        self._setpoint = (index, fraction)
        self._mode = mode

    def mode(self):
        """The selected discipline ("left"/"right"), or None before set_mode()."""
        return self._mode

    def edge_error(self, readings=None):
        """Signed steering error -50 .. +50 for the set_mode() discipline: the ambient (0 black ..
        100 white) at the setpoint element referenced to 50. Zero when that element straddles the
        edge; positive = steer right, in both modes (left: mat under the element means the line
        is to the right; right: mat means the line is to the left, so the sign flips)."""
        if self._mode is None:
            raise RuntimeError(
                'edge_error() follows an edge chosen by set_mode("left") or set_mode("right"); call it first'
            )
        values = self._values(readings)
        index, fraction = self._setpoint
        value = values[index]
        if fraction:
            value += int((values[index + 1] - value) * fraction)
        ambient = (_FULL_SCALE - value) // 10
        return ambient - 50 if self._mode == "left" else 50 - ambient

    def emitters(self, on):
        """Switch the IR emitters through CTRL (no-op when CTRL is tied high)."""
        if self._ctrl is not None:
            self._ctrl.value(1 if on else 0)

    # -- helpers -------------------------------------------------------------------------------

    def _half_gap(self, end, neighbour):
        if len(self._positions) < 2:
            return self._pitch / 2
        return abs(self._positions[end] - self._positions[neighbour]) / 2

    def _describe(self):
        return "%s on GPIO %s" % (type(self).__name__, ", ".join(str(p) for p in self._pins))

    def __repr__(self):
        return "%s(pins=%r)" % (type(self).__name__, self._pins)


class QTRChannel(QTRArray):
    """One reflectance element with the array's calibrate/read contract: a detector (branch or
    marker flag) kept out of the steering array, so a marker never yanks the centroid."""

    def __init__(self, pin, dark_threshold=300):
        QTRArray.__init__(self, (pin,), dark_threshold=dark_threshold)

    def value(self):
        """Calibrated reading, 0 (mat) .. 1000 (marker/line)."""
        return self.read()[0].value

    def dark(self):
        """True when the element is over a marker/line."""
        return self.read()[0].dark()

    def white(self):
        """True when the element is over the mat."""
        return self.read()[0].white()


class QTRLineSensor(QTRArray):
    """The standard line-follow window: ten channels of a QTRX-HD-15A (4 mm pitch) in a skip
    pattern on GPIO 1..10, geometry and both edge setpoints built in.

    Channels 1, 3, 4, 5, 7, 9, 11, 12, 13, 15 left to right: a 56 mm window at gaps of
    8/4/4/8/8/8/4/4/8 mm. "left" holds the line's LEFT edge under channel 4 (-16 mm), "right" the
    RIGHT edge under channel 12 (+16 mm). The pattern is a palindrome, so turning the board round
    only swaps channel labels. Other wiring: use QTRArray with your own pins and positions.
    """

    #: The QTRX-HD-15A channels wired, left to right.
    CHANNELS = (1, 3, 4, 5, 7, 9, 11, 12, 13, 15)
    #: The ADC GPIOs they are wired to, left to right.
    PINS = (1, 2, 3, 4, 5, 6, 7, 8, 9, 10)
    #: Each element's position in mm from the window's centre, left to right.
    POSITIONS_MM = (-28.0, -20.0, -16.0, -12.0, -4.0, 4.0, 12.0, 16.0, 20.0, 28.0)
    #: set_mode("left") holds the LEFT edge under channel 4: -16 mm.
    LEFT_SETPOINT_MM = POSITIONS_MM[CHANNELS.index(4)]
    #: set_mode("right") holds the RIGHT edge under channel 12: +16 mm.
    RIGHT_SETPOINT_MM = POSITIONS_MM[CHANNELS.index(12)]
    #: The manual's spelling of LEFT_SETPOINT_MM.
    LEFT_SETPPOINT_MM = LEFT_SETPOINT_MM
    #: The manual's spelling of RIGHT_SETPOINT_MM.
    RIGHT_SETPPOINT_MM = RIGHT_SETPOINT_MM

    def __init__(self, dark_threshold=300):
        QTRArray.__init__(
            self, self.PINS, pitch_mm=4.0, dark_threshold=dark_threshold, positions_mm=self.POSITIONS_MM
        )


def _claim(pin, role, owner, output=True):
    # Module-level on purpose: inside QTRArray.__init__ the name `pins` is the caller's pin tuple.
    pins.claim(pin, role, owner=owner, output=output)


def _first_dark(values, threshold):
    for i in range(len(values)):
        if values[i] > threshold:
            return i
    return None


def _last_dark(values, threshold):
    for i in range(len(values) - 1, -1, -1):
        if values[i] > threshold:
            return i
    return None


def _centroid(values, positions, begin, end):
    total = 0
    moment = 0.0
    for i in range(begin, end):
        total += values[i]
        moment += values[i] * positions[i]
    return moment / total if total else None


def _crossing(values, positions, a, b, threshold):
    # Linear interpolation of where the value passes the threshold between elements a and b.
    va, vb = values[a], values[b]
    if va == vb:
        return (positions[a] + positions[b]) / 2
    return positions[a] + (threshold - va) * (positions[b] - positions[a]) / (vb - va)


def _parse_calibration(text, n, path):
    def corrupt(why):
        return ValueError(
            "QTR calibration %s is corrupt (%s): re-run %s to record a fresh one"
            % (path, why, _CALIBRATE_SCRIPT)
        )

    try:
        record = json.loads(text)
    except ValueError:
        raise corrupt("not JSON") from None
    if not isinstance(record, dict) or record.get("format") != _CALIBRATION_FORMAT:
        raise corrupt("not an openbricks QTR calibration")
    lo, hi, wired = record.get("min"), record.get("max"), record.get("pins")
    for name, field in (("min", lo), ("max", hi), ("pins", wired)):
        if not isinstance(field, list) or not all(isinstance(v, int) for v in field):
            raise corrupt("%s is not a list of integers" % name)
    if len(lo) != len(wired) or len(hi) != len(wired):
        raise corrupt("%d pins but %d/%d extremes" % (len(wired), len(lo), len(hi)))
    if len(wired) == n:
        for i in range(n):
            if lo[i] > hi[i]:
                raise corrupt("element %d has min > max" % i)
    return lo, hi, wired
