"""A centreline built from straights and arcs, the way a robot would drive it.

Headings are clockwise from +x and a positive arc angle turns right, the same
conventions as DriveBase.turn() and curve(), so a track reads like the
program that follows it. The same path prints the line on the mat and scores
a run (how far along it the robot got).
"""

import math

import numpy as np


class Path:
    """A pen that starts at (x_mm, y_mm) facing heading_deg and records where it goes."""

    def __init__(self, x_mm: float, y_mm: float, heading_deg: float = 0.0):
        self.x_mm = float(x_mm)
        self.y_mm = float(y_mm)
        self.heading_deg = float(heading_deg)
        self._points = [(self.x_mm, self.y_mm)]
        self.length_mm = 0.0

    def straight(self, length_mm: float, step_mm: float = 5.0) -> "Path":
        h = -math.radians(self.heading_deg)  # clockwise heading -> counter-clockwise math angle
        n = max(1, math.ceil(abs(length_mm) / step_mm))
        x0, y0 = self.x_mm, self.y_mm
        for i in range(1, n + 1):
            s = length_mm * i / n
            self._points.append((x0 + s * math.cos(h), y0 + s * math.sin(h)))
        self.x_mm, self.y_mm = self._points[-1]
        self.length_mm += abs(length_mm)
        return self

    def arc(self, radius_mm: float, angle_deg: float, step_mm: float = 5.0) -> "Path":
        """Turn `angle_deg` (positive = right, clockwise) along a circle of `radius_mm`."""
        if radius_mm <= 0:
            raise ValueError(f"arc radius must be positive, got {radius_mm} mm")
        h = -math.radians(self.heading_deg)
        side = -1.0 if angle_deg > 0 else 1.0  # the centre lies to the right for a right turn
        cx = self.x_mm + side * radius_mm * -math.sin(h)
        cy = self.y_mm + side * radius_mm * math.cos(h)
        start = math.atan2(self.y_mm - cy, self.x_mm - cx)
        sweep = -math.radians(angle_deg)  # clockwise on the mat is a negative math angle
        n = max(1, math.ceil(abs(sweep) * radius_mm / step_mm))
        for i in range(1, n + 1):
            a = start + sweep * i / n
            self._points.append((cx + radius_mm * math.cos(a), cy + radius_mm * math.sin(a)))
        self.x_mm, self.y_mm = self._points[-1]
        self.heading_deg += angle_deg
        self.length_mm += abs(math.radians(angle_deg)) * radius_mm
        return self

    def points(self) -> np.ndarray:
        """The centreline as an (N, 2) array of mm points."""
        return np.array(self._points)

    def progress(self, x_mm: float, y_mm: float) -> tuple[float, float]:
        """(distance along the path to the point nearest (x_mm, y_mm), distance from the path) in mm."""
        p = self.points()
        a, b = p[:-1], p[1:]
        ab = b - a
        length2 = np.maximum((ab * ab).sum(axis=1), 1e-12)
        t = np.clip(((x_mm - a[:, 0]) * ab[:, 0] + (y_mm - a[:, 1]) * ab[:, 1]) / length2, 0.0, 1.0)
        nearest = a + ab * t[:, None]
        offsets = np.hypot(nearest[:, 0] - x_mm, nearest[:, 1] - y_mm)
        i = int(np.argmin(offsets))
        seg_lengths = np.sqrt(length2)
        along = float(seg_lengths[:i].sum() + t[i] * seg_lengths[i])
        return along, float(offsets[i])
