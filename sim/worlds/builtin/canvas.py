"""A printed mat drawn by code, for the built-in mats' images: an RGB raster addressed in millimetres.

The raster is laid out the way MuJoCo maps a 2D texture onto a plane with
texrepeat 1 1: row 0 is the mat's far edge (+y), column 0 its left edge
(-x), so the array reads like the mat seen from above. The origin of the
millimetre frame is the mat centre, +x right, +y toward the far edge, the
same frame as the world's, so a shape drawn at (x_mm, y_mm) lies under a
robot standing at (x_mm, y_mm).

Edges are anti-aliased from the exact signed distance to each shape, so a
line's edge sits where it was drawn to a fraction of a texel; a sensor that
interpolates between texels then sees the edge move smoothly instead of in
whole-texel steps. Every primitive touches only its own bounding box.
"""

import numpy as np

from ...world_file import PALETTE

# Print colours (sRGB) chosen to read as their names under the colour sensor model: the palette a
# world file's colour names mean.
WHITE = PALETTE["white"]
BLACK = PALETTE["black"]
RED = PALETTE["red"]
GREEN = PALETTE["green"]
BLUE = PALETTE["blue"]
YELLOW = PALETTE["yellow"]
GREY = PALETTE["grey"]


class MatCanvas:
    """An RGB mat of `width_mm` x `height_mm` at `px_per_mm` texels per millimetre."""

    def __init__(self, width_mm: float, height_mm: float, px_per_mm: float = 1.0, background=WHITE):
        if width_mm <= 0 or height_mm <= 0 or px_per_mm <= 0:
            raise ValueError(
                f"a mat needs positive size and resolution, got {width_mm} x {height_mm} mm "
                f"at {px_per_mm} px/mm"
            )
        self.width_mm = float(width_mm)
        self.height_mm = float(height_mm)
        self.px_per_mm = float(px_per_mm)
        self.width_px = max(1, round(width_mm * px_per_mm))
        self.height_px = max(1, round(height_mm * px_per_mm))
        self.pixels = np.empty((self.height_px, self.width_px, 3), dtype=np.uint8)
        self.pixels[:] = background

    # -- frames ----------------------------------------------------------------------------------

    def _window(self, x0_mm, y0_mm, x1_mm, y1_mm, margin_mm):
        """Texel index ranges covering a mm box (plus margin), clipped to the mat; None if off it."""
        s = self.px_per_mm
        c0 = int(np.floor((min(x0_mm, x1_mm) - margin_mm + self.width_mm / 2) * s))
        c1 = int(np.ceil((max(x0_mm, x1_mm) + margin_mm + self.width_mm / 2) * s))
        r0 = int(np.floor((self.height_mm / 2 - max(y0_mm, y1_mm) - margin_mm) * s))
        r1 = int(np.ceil((self.height_mm / 2 - min(y0_mm, y1_mm) + margin_mm) * s))
        c0, c1 = max(c0, 0), min(c1, self.width_px)
        r0, r1 = max(r0, 0), min(r1, self.height_px)
        if c0 >= c1 or r0 >= r1:
            return None
        return r0, r1, c0, c1

    def _centres_mm(self, window):
        """World millimetre coordinates of the texel centres inside a window, as (x, y) grids."""
        r0, r1, c0, c1 = window
        s = self.px_per_mm
        x = (np.arange(c0, c1) + 0.5) / s - self.width_mm / 2
        y = self.height_mm / 2 - (np.arange(r0, r1) + 0.5) / s
        return np.meshgrid(x, y)

    def _coverage(self, signed_distance_mm):
        """Fraction of a texel inside a shape, from the signed distance of its centre (negative inside)."""
        return np.clip(0.5 - signed_distance_mm * self.px_per_mm, 0.0, 1.0)

    def _blend(self, window, alpha, rgb):
        r0, r1, c0, c1 = window
        region = self.pixels[r0:r1, c0:c1]
        touched = alpha > 0.0  # a thin line's bounding box is mostly empty: blend only what it covers
        old = region[touched].astype(np.float32)
        a = alpha[touched][:, None].astype(np.float32)
        region[touched] = np.rint(old + (np.asarray(rgb, dtype=np.float32) - old) * a).astype(np.uint8)

    # -- shapes ----------------------------------------------------------------------------------

    def fill_rect(self, x0_mm, y0_mm, x1_mm, y1_mm, rgb):
        """An axis-aligned rectangle between two opposite corners."""
        window = self._window(x0_mm, y0_mm, x1_mm, y1_mm, 1.0 / self.px_per_mm)
        if window is None:
            return
        x, y = self._centres_mm(window)
        cx, cy = (x0_mm + x1_mm) / 2, (y0_mm + y1_mm) / 2
        hx, hy = abs(x1_mm - x0_mm) / 2, abs(y1_mm - y0_mm) / 2
        qx, qy = np.abs(x - cx) - hx, np.abs(y - cy) - hy
        outside = np.hypot(np.maximum(qx, 0), np.maximum(qy, 0))
        inside = np.minimum(np.maximum(qx, qy), 0)
        self._blend(window, self._coverage(outside + inside), rgb)

    def fill_disc(self, cx_mm, cy_mm, radius_mm, rgb):
        window = self._window(
            cx_mm - radius_mm, cy_mm - radius_mm, cx_mm + radius_mm, cy_mm + radius_mm, 1.0 / self.px_per_mm
        )
        if window is None:
            return
        x, y = self._centres_mm(window)
        self._blend(window, self._coverage(np.hypot(x - cx_mm, y - cy_mm) - radius_mm), rgb)

    def stroke_rect(self, x0_mm, y0_mm, x1_mm, y1_mm, width_mm, rgb):
        """A rectangle's outline, `width_mm` wide, centred on the rectangle's edges."""
        corners = [(x0_mm, y0_mm), (x1_mm, y0_mm), (x1_mm, y1_mm), (x0_mm, y1_mm), (x0_mm, y0_mm)]
        self.stroke_path(corners, width_mm, rgb)

    def stroke_path(self, points_mm, width_mm, rgb):
        """A polyline of `width_mm` with round joins and ends (a printed line's centreline)."""
        points = np.asarray(points_mm, dtype=np.float64)
        if points.ndim != 2 or points.shape[1] != 2 or len(points) < 2:
            raise ValueError("stroke_path needs two or more (x_mm, y_mm) points")
        half = width_mm / 2
        lo, hi = points.min(axis=0), points.max(axis=0)
        window = self._window(lo[0], lo[1], hi[0], hi[1], half + 1.0 / self.px_per_mm)
        if window is None:
            return
        r0, _, c0, _ = window
        alpha = np.zeros((window[1] - r0, window[3] - c0), dtype=np.float32)
        for a, b in zip(points[:-1], points[1:], strict=True):
            seg = self._window(
                min(a[0], b[0]),
                min(a[1], b[1]),
                max(a[0], b[0]),
                max(a[1], b[1]),
                half + 1.0 / self.px_per_mm,
            )
            if seg is None:
                continue
            x, y = self._centres_mm(seg)
            d = _distance_to_segment(x, y, a, b) - half
            rows = slice(seg[0] - r0, seg[1] - r0)
            cols = slice(seg[2] - c0, seg[3] - c0)
            np.maximum(alpha[rows, cols], self._coverage(d), out=alpha[rows, cols])
        self._blend(window, alpha, rgb)


def _distance_to_segment(x, y, a, b):
    """Distance from grid points to the segment a-b (mm)."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    length2 = dx * dx + dy * dy
    if length2 == 0.0:
        return np.hypot(x - a[0], y - a[1])
    t = np.clip(((x - a[0]) * dx + (y - a[1]) * dy) / length2, 0.0, 1.0)
    return np.hypot(x - (a[0] + t * dx), y - (a[1] + t * dy))
