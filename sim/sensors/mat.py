"""What lies under a downward-looking sensor: the mat texture (or a prop, or bare floor) and how far
away it is, averaged over the sensor's footprint.

A ray from the sensor straight down finds the surface (the robot's own geoms
are excluded). On a textured plane the hit point is taken into the geom's
frame and turned into texture coordinates the way MuJoCo maps a 2D texture
onto a plane (texrepeat over the plane's extent, or per metre with
texuniform; row 0 at the far +y edge), then a disc of sample points around it
is bilinearly interpolated and averaged, all as NumPy array operations over
every sensor of a group at once. Any other surface reads its material or geom
colour; a ray that hits nothing within range reads black (no light returns).

Colours come out as linear reflectance 0..1 per channel: texels are sRGB, so
they pass through the sRGB decoding curve first (a printed black reflects a
few percent, not the 9 % its code value suggests).
"""

import math

import mujoco
import numpy as np

from ..chassis import ROBOT_BODY

_SRGB_TO_LINEAR = np.array(
    [c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4 for c in np.arange(256) / 255.0],
    dtype=np.float32,
)


def srgb_to_linear(rgb_255) -> np.ndarray:
    """Linear reflectance of 8-bit sRGB values (any shape)."""
    return _SRGB_TO_LINEAR[np.asarray(rgb_255, dtype=np.uint8)]


def footprint_offsets_mm(radius_mm: float) -> np.ndarray:
    """Seven sample points weighting a disc of radius_mm about evenly: the centre and a hexagon at 0.7 r,
    (K, 2) mm. Texels are anti-aliased and interpolated, so a few samples give a smooth average."""
    if radius_mm <= 0:
        return np.zeros((1, 2))
    points = [(0.0, 0.0)]
    for k in range(6):
        a = 2 * math.pi * k / 6
        points.append((radius_mm * 0.7 * math.cos(a), radius_mm * 0.7 * math.sin(a)))
    return np.array(points)


class _TexturedPlane:
    """Texture lookup on one textured plane geom: a view into model.tex_data, no copy."""

    def __init__(self, model: mujoco.MjModel, geom_id: int, tex_id: int, material_id: int):
        h, w, n = (
            int(model.tex_height[tex_id]),
            int(model.tex_width[tex_id]),
            int(model.tex_nchannel[tex_id]),
        )
        start = int(model.tex_adr[tex_id])
        self._flat = model.tex_data[start : start + h * w * n].reshape(h * w, n)[:, :3]
        self.width, self.height = w, h
        half = np.array(model.geom_size[geom_id][:2], dtype=np.float64)
        repeat = np.array(model.mat_texrepeat[material_id], dtype=np.float64)
        uniform = bool(model.mat_texuniform[material_id])
        # Geom-local xy (m) -> continuous texel coordinates (column, row from the top edge), as one
        # multiply-add: uv = xy * repeat (per metre) or (xy / size + 1/2) * repeat (over the plane),
        # then column = u * W - 1/2, row = (1 - v) * H - 1/2 (texel centres at half-integers).
        size = np.array([w, -h], dtype=np.float64)
        per_metre = repeat if uniform else repeat / (2.0 * half)
        self._gain = per_metre * size
        self._offset = (np.zeros(2) if uniform else 0.5 * repeat) * size + np.array([-0.5, h - 0.5])
        self._wraps = uniform or bool(np.any(repeat != 1.0))
        self._period = np.array([w, h], dtype=np.float64)
        self._last = np.array([w - 1, h - 1])

    def reflectance(self, local_xy_m: np.ndarray) -> np.ndarray:
        """Linear RGB at geom-local points (..., 2) metres, bilinearly interpolated."""
        f = local_xy_m * self._gain + self._offset
        if self._wraps:
            f %= self._period
        i0 = np.floor(f)
        t = f - i0
        i0 = np.clip(i0.astype(np.intp), 0, self._last)
        i1 = np.minimum(i0 + 1, self._last)
        row0 = i0[..., 1] * self.width
        row1 = i1[..., 1] * self.width
        corners = _SRGB_TO_LINEAR[
            self._flat[np.stack((row0 + i0[..., 0], row0 + i1[..., 0], row1 + i0[..., 0], row1 + i1[..., 0]))]
        ]
        tx, ty = t[..., :1], t[..., 1:]
        top = corners[0] + (corners[1] - corners[0]) * tx
        bottom = corners[2] + (corners[3] - corners[2]) * tx
        return top + (bottom - top) * ty


class GroundProbe:
    """Looks straight down from points on the robot and reports colour and range.

    `max_range_mm` bounds the ray: anything farther reads as no surface at all.
    """

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, max_range_mm: float = 200.0):
        self.model = model
        self.data = data
        self.max_range_m = max_range_mm / 1000.0
        self.robot_body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, ROBOT_BODY)
        self._planes: dict[int, _TexturedPlane | None] = {}
        self._geom_id = np.zeros(1, dtype=np.int32)

    def _plane(self, geom_id: int) -> "_TexturedPlane | None":
        if geom_id not in self._planes:
            self._planes[geom_id] = None
            m = self.model
            material = int(m.geom_matid[geom_id])
            if m.geom_type[geom_id] == mujoco.mjtGeom.mjGEOM_PLANE and material >= 0:
                tex = int(m.mat_texid[material][mujoco.mjtTextureRole.mjTEXROLE_RGB])
                if tex >= 0 and m.tex_type[tex] == mujoco.mjtTexture.mjTEXTURE_2D:
                    self._planes[geom_id] = _TexturedPlane(m, geom_id, tex, material)
        return self._planes[geom_id]

    def _plain_colour(self, geom_id: int) -> np.ndarray:
        m = self.model
        material = int(m.geom_matid[geom_id])
        rgba = m.mat_rgba[material] if material >= 0 else m.geom_rgba[geom_id]
        return srgb_to_linear(np.rint(np.clip(rgba[:3], 0, 1) * 255))

    def cast_down(self, origin_m: np.ndarray, down: np.ndarray) -> tuple[int, float]:
        """(geom id, distance m) of the first surface below origin, or (-1, inf)."""
        distance = mujoco.mj_ray(
            self.model, self.data, origin_m, down, None, 1, self.robot_body, self._geom_id
        )
        if distance < 0 or distance > self.max_range_m:
            return -1, math.inf
        return int(self._geom_id[0]), distance

    def look(self, site_id: int, spots_m: np.ndarray):
        """Reflectance under each spot of a downward-looking sensor, and the range to the surface.

        One ray from the site along its -z axis finds the surface. `spots_m` (G, K, 2) holds, per
        spot, K sample points in the sensor's own frame (x forward, y left, metres): a sensor's
        footprint, or for a reflectance bar each element's footprint at its position. They are
        carried onto the surface around the hit point and looked up in one vectorised pass.
        Returns ((G, 3) linear reflectance, range in mm, or inf when no surface is within range,
        which reads black).
        """
        data = self.data
        groups = spots_m.shape[0]
        axes = data.site_xmat[site_id].reshape(3, 3)
        down = -axes[:, 2]
        geom, distance = self.cast_down(data.site_xpos[site_id], down)
        if geom < 0:
            return np.zeros((groups, 3)), math.inf
        plane = self._plane(geom)
        if plane is None:
            return np.tile(self._plain_colour(geom), (groups, 1)), distance * 1000.0
        rotation = data.geom_xmat[geom].reshape(3, 3)
        hit = data.site_xpos[site_id] + down * distance
        centre = ((hit - data.geom_xpos[geom]) @ rotation)[:2]
        onto_plane = (axes[:, :2].T @ rotation)[:, :2]  # sensor xy -> geom-local xy
        local = spots_m @ onto_plane + centre
        return plane.reflectance(local).mean(axis=1), distance * 1000.0


def spot_pattern_m(centres_mm, footprint_mm: np.ndarray) -> np.ndarray:
    """(G, K, 2) sample points in a sensor's frame (metres): a footprint around each spot centre
    given in mm (x forward, y left)."""
    centres = np.asarray(centres_mm, dtype=np.float64).reshape(-1, 1, 2)
    return (centres + footprint_mm[None, :, :]) / 1000.0
