"""The furniture every world shares: the floor, a printed mat, border walls.

The mat is a plane geom carrying the canvas as its texture (texrepeat 1 1, so
one texel per canvas pixel). A plane collides as an infinite surface, so the
robot drives on the same contact model on and off the mat; its size only
bounds what is drawn and what a downward ray hits. Beyond the mat a ray falls
through to a visual-only floor a little below, which is how a sensor that
leaves the mat sees bare floor instead of mat texture.
"""

import mujoco

MM = 0.001
MAT_GEOM_PREFIX = "mat"
FLOOR_GEOM = "floor"
FLOOR_RGB = (0.55, 0.55, 0.57)
WALL_RGBA = (0.72, 0.58, 0.40, 1.0)  # plywood


def add_floor(spec: mujoco.MjSpec, half_size_m: float = 5.0) -> None:
    """A grey floor, seen and ray-hit but never touched: the mat plane carries all contacts."""
    spec.worldbody.add_geom(
        name=FLOOR_GEOM,
        type=mujoco.mjtGeom.mjGEOM_PLANE,
        size=[half_size_m, half_size_m, 0.1],
        pos=[0.0, 0.0, -0.0005],
        rgba=[*FLOOR_RGB, 1.0],
        contype=0,
        conaffinity=0,
    )


def add_mat(spec: mujoco.MjSpec, canvas, name: str = MAT_GEOM_PREFIX, x_mm=0.0, y_mm=0.0):
    """Lay `canvas` (an RGB raster: pixels, width_px/height_px, width_mm/height_mm, as from_file's
    MatRaster) flat with its centre at (x_mm, y_mm); returns the geom."""
    texture = spec.add_texture(
        name=f"{name}_texture",
        type=mujoco.mjtTexture.mjTEXTURE_2D,
        width=canvas.width_px,
        height=canvas.height_px,
        nchannel=3,
    )
    texture.data = canvas.pixels.tobytes()
    material = spec.add_material(name=f"{name}_material", texrepeat=[1.0, 1.0], texuniform=False)
    material.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = texture.name
    return spec.worldbody.add_geom(
        name=name,
        type=mujoco.mjtGeom.mjGEOM_PLANE,
        size=[canvas.width_mm / 2 * MM, canvas.height_mm / 2 * MM, 0.05],
        pos=[x_mm * MM, y_mm * MM, 0.0],
        material=material.name,
    )


def add_border(
    spec: mujoco.MjSpec, inner_width_mm, inner_height_mm, height_mm=70.0, thickness_mm=20.0, name="wall"
):
    """Four walls whose inner faces enclose a centred inner_width_mm x inner_height_mm rectangle."""
    hw, hh = inner_width_mm / 2, inner_height_mm / 2
    t = thickness_mm / 2
    walls = {
        f"{name}_north": (0.0, hh + t, hw + 2 * t, t),
        f"{name}_south": (0.0, -hh - t, hw + 2 * t, t),
        f"{name}_east": (hw + t, 0.0, t, hh),
        f"{name}_west": (-hw - t, 0.0, t, hh),
    }
    for wall_name, (x, y, sx, sy) in walls.items():
        add_wall(spec, wall_name, x, y, 2 * sx, 2 * sy, height_mm)


def add_wall(spec: mujoco.MjSpec, name, x_mm, y_mm, length_x_mm, length_y_mm, height_mm=70.0, rgba=WALL_RGBA):
    """A static box standing on the mat, centred at (x_mm, y_mm)."""
    spec.worldbody.add_geom(
        name=name,
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[length_x_mm / 2 * MM, length_y_mm / 2 * MM, height_mm / 2 * MM],
        pos=[x_mm * MM, y_mm * MM, height_mm / 2 * MM],
        rgba=list(rgba),
    )
