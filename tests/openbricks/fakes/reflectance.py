"""Dark lines on a light mat under an analog QTR/QTRX reflectance array.

Each element is an IR emitter/phototransistor pair with a small footprint on
the mat; its output voltage rises with how much of that footprint is dark
(the raw ADC reading goes from `white_raw` over bare mat to `black_raw` fully
over a line). Positions are millimetres in the array's frame, positive to the
right. The model writes the readings into `machine.board.analog`, and
`sweep()` moves the lines with the virtual clock, the way a person slides
the robot across the line while `calibrate()` runs.
"""

from . import clock, machine


class LineMat:
    def __init__(self, pins_to_x_mm, white_raw=300, black_raw=3500, footprint_mm=4.0, bias=None):
        self.pins_to_x_mm = dict(pins_to_x_mm)
        self.white_raw = white_raw
        self.black_raw = black_raw
        self.footprint_mm = footprint_mm
        self.bias = dict(bias or {})  # pin -> raw offset (a pull-up on a strapping pin, say)
        self.lines = []  # (left edge mm, width mm)
        self._timer = None
        self.update()

    def place(self, *lines):
        """Put lines at (left_edge_mm, width_mm) each; no argument = bare mat."""
        self.lines = [tuple(line) for line in lines]
        self.update()

    def place_line(self, center_mm, width_mm=20.0):
        self.place((center_mm - width_mm / 2, width_mm))

    def coverage(self, x_mm):
        half = self.footprint_mm / 2
        lo, hi = x_mm - half, x_mm + half
        dark = 0.0
        for left, width in self.lines:
            dark += max(0.0, min(hi, left + width) - max(lo, left))
        return min(1.0, dark / self.footprint_mm)

    def update(self):
        for pin, x in self.pins_to_x_mm.items():
            raw = self.white_raw + (self.black_raw - self.white_raw) * self.coverage(x)
            machine.board.analog[pin] = max(0, min(4095, int(raw + self.bias.get(pin, 0))))

    def sweep(self, from_center_mm, to_center_mm, duration_ms, width_mm=20.0, step_ms=5):
        """Slide one line from `from_center_mm` to `to_center_mm` over `duration_ms` of virtual time."""
        state = {"t_ms": 0}
        self.place_line(from_center_mm, width_mm)

        def step():
            state["t_ms"] += step_ms
            f = min(1.0, state["t_ms"] / duration_ms)
            self.place_line(from_center_mm + (to_center_mm - from_center_mm) * f, width_mm)
            if f >= 1.0:
                self._sweep.cancel()

        self._sweep = clock.every_ms(step_ms, step)
