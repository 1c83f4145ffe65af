"""The simulated world as viser scene nodes: built once from the MjModel, then moved frame by frame.

mjviser does the mirroring: every geom of the model becomes a mesh (primitives, meshes with their
UV textures, height fields), bodies that share a shape are drawn as one batched node, and each frame
moves only the bodies that can move. It draws every plane as viser's infinite grid, though, and our
mats are planes whose printed canvas is the whole point of a line-following or colour world; so
each textured plane is drawn again here as a textured quad in place of its grid. The plain floor
keeps a grid, which reads well as "the floor", minus the white sheet that would veil the mat.
"""

from __future__ import annotations

import zlib

import mujoco
import numpy as np
import trimesh
import trimesh.visual
import trimesh.visual.material
from mjviser import ViserMujocoScene
from PIL import Image

# Printed mats lie on the contact plane; the floor is drawn 0.5 mm below it. This lift keeps the two
# from flickering into each other at a distance (depth precision) and is far below what a wheel
# resting on the mat would show.
_MAT_LIFT_M = 0.0003
# Free space around what the camera frames first, and the least it frames (a lone robot).
_FRAME_MARGIN_M = 0.15
_MIN_FRAME_SPAN_M = 0.8


class SceneMirror:
    """One MjModel drawn into a viser server; show(frame) moves it to a captured Frame."""

    def __init__(self, server, model: mujoco.MjModel, focus_body: str | None = None):
        self.server = server
        self.model = model
        self._mirror = ViserMujocoScene(server, model, num_envs=1)
        # The camera stays where the watcher puts it: mjviser's tracking would instead slide the whole
        # world under a fixed camera to keep one body centred.
        self._mirror.camera_tracking_enabled = False
        self._draw_planes()
        self.look_at, self.camera_position = _overview(model, focus_body)
        server.initial_camera.look_at = self.look_at
        server.initial_camera.position = self.camera_position

    def add_visualization_gui(self) -> None:
        """mjviser's overlay and geom-group controls (contact points and forces, frames, groups)."""
        self._mirror.create_overlay_gui()
        self._mirror.create_groups_gui()

    def show(self, frame) -> None:
        """Move every body to where it was in `frame`."""
        self._mirror.update_from_arrays(
            frame.body_xpos[None],
            frame.body_xmat[None],
            qpos=frame.qpos[None],
            qvel=frame.qvel[None],
        )

    def reset_cameras(self) -> None:
        """Put every connected browser's camera back on the overview."""
        for client in self.server.get_clients().values():
            client.camera.look_at = self.look_at
            client.camera.position = self.camera_position

    def _draw_planes(self) -> None:
        """Redraw each fixed plane in place of mjviser's grid for it (same node name, so it replaces it).

        A printed plane becomes a textured quad. A plain one (the floor) stays a grid in a world
        without a mat, where it gives a sense of scale; next to a mat it becomes a solid sheet of its
        colour, since a grid (its lines and its translucent sheet alike) draws over the mat and
        washes out the print.
        """
        model = self.model
        data = mujoco.MjData(model)
        mujoco.mj_kinematics(model, data)
        printed = any(_plane_texture(model, geom) is not None for geom in range(model.ngeom))
        for geom in range(model.ngeom):
            body = int(model.geom_bodyid[geom])
            if model.geom_type[geom] != mujoco.mjtGeom.mjGEOM_PLANE or model.body_weldid[body] != 0:
                continue  # a plane on a moving body: mjviser draws it with the body (untextured)
            name = (
                f"/fixed_bodies/{_name(model, mujoco.mjtObj.mjOBJ_BODY, body)}/"
                f"{mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, geom)}"
            )
            quat = np.empty(4)
            mujoco.mju_mat2Quat(quat, data.geom_xmat[geom])
            image = _plane_texture(model, geom)
            half_x, half_y = (float(v) for v in model.geom_size[geom][:2])
            if image is None and not printed:
                continue  # mjviser's grid it is
            if image is None:
                quad, lift = _plain_quad(half_x, half_y, model.geom_rgba[geom]), 0.0
            else:
                quad, lift = _textured_quad(half_x, half_y, image), _MAT_LIFT_M
            normal = data.geom_xmat[geom].reshape(3, 3)[:, 2]
            self.server.scene.add_mesh_trimesh(
                name,
                quad,
                position=data.geom_xpos[geom] + lift * normal,
                wxyz=quat,
                cast_shadow=False,
                receive_shadow=True,
            )


def model_fingerprint(model: mujoco.MjModel) -> int:
    """Changes whenever what the scene draws changes: a restart on the same world and seed keeps it."""
    crc = 0
    for array in (
        model.geom_type,
        model.geom_size,
        model.geom_rgba,
        model.geom_pos,
        model.geom_quat,
        model.geom_bodyid,
        model.geom_matid,
        model.body_pos,
        model.body_quat,
        model.mat_rgba,
        model.tex_data,
    ):
        crc = zlib.crc32(np.ascontiguousarray(array).view(np.uint8), crc)
    return crc


def _plane_texture(model: mujoco.MjModel, geom: int) -> Image.Image | None:
    """The 2D texture printed on plane `geom`, as an image whose first row is the plane's +y edge."""
    if model.geom_type[geom] != mujoco.mjtGeom.mjGEOM_PLANE:
        return None
    material = int(model.geom_matid[geom])
    if material < 0:
        return None
    texture = int(model.mat_texid[material, int(mujoco.mjtTextureRole.mjTEXROLE_RGB)])
    if texture < 0 or model.tex_type[texture] != mujoco.mjtTexture.mjTEXTURE_2D:
        return None
    width, height, channels = (
        int(v) for v in (model.tex_width[texture], model.tex_height[texture], model.tex_nchannel[texture])
    )
    if channels not in (3, 4):
        return None
    start = int(model.tex_adr[texture])
    pixels = model.tex_data[start : start + width * height * channels].reshape(height, width, channels)
    return Image.fromarray(np.ascontiguousarray(pixels, dtype=np.uint8))


def _quad(half_x: float, half_y: float) -> trimesh.Trimesh:
    """A flat rectangle in its local xy plane, facing +z."""
    vertices = np.array(
        [[-half_x, -half_y, 0.0], [half_x, -half_y, 0.0], [half_x, half_y, 0.0], [-half_x, half_y, 0.0]]
    )
    return trimesh.Trimesh(vertices=vertices, faces=np.array([[0, 1, 2], [0, 2, 3]]), process=False)


def _plain_quad(half_x: float, half_y: float, rgba) -> trimesh.Trimesh:
    mesh = _quad(half_x, half_y)
    colour = (np.clip(rgba, 0.0, 1.0) * 255).astype(np.uint8)
    mesh.visual = trimesh.visual.ColorVisuals(vertex_colors=np.tile(colour, (4, 1)))
    return mesh


def _textured_quad(half_x: float, half_y: float, image: Image.Image) -> trimesh.Trimesh:
    """A flat rectangle in its local xy plane with `image` stretched over it once (texrepeat 1 1)."""
    # trimesh's uv origin is the image's bottom-left corner: the plane's -x,-y corner gets (0, 0), so
    # the image's first row lands on the +y edge.
    uv = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    material = trimesh.visual.material.PBRMaterial(
        baseColorTexture=image, metallicFactor=0.0, roughnessFactor=0.9
    )
    mesh = _quad(half_x, half_y)
    mesh.visual = trimesh.visual.TextureVisuals(uv=uv, material=material)
    return mesh


def _overview(model: mujoco.MjModel, focus_body: str | None):
    """(look_at, camera position) that frame the static scenery and the robot, seen from the south."""
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    low, high = np.full(3, np.inf), np.full(3, -np.inf)

    def include(centre, half):
        nonlocal low, high
        low = np.minimum(low, centre - half)
        high = np.maximum(high, centre + half)

    for geom in range(model.ngeom):
        if model.body_weldid[model.geom_bodyid[geom]] != 0 or model.geom_rgba[geom, 3] == 0:
            continue
        if model.geom_type[geom] == mujoco.mjtGeom.mjGEOM_PLANE:
            if _plane_texture(model, geom) is None:
                continue  # a bare floor stretches far beyond anything worth framing
            size = model.geom_size[geom]
            include(data.geom_xpos[geom], np.array([size[0], size[1], 0.0]))
        else:
            include(data.geom_xpos[geom], np.full(3, model.geom_rbound[geom]))
    if focus_body is not None and mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, focus_body) >= 0:
        include(data.body(focus_body).xpos, np.full(3, _MIN_FRAME_SPAN_M / 2))
    if not np.all(np.isfinite(low)):
        low, high = -np.full(3, _MIN_FRAME_SPAN_M / 2), np.full(3, _MIN_FRAME_SPAN_M / 2)
    centre = (low + high) / 2
    centre[2] = 0.0
    span = max(float(np.max(high[:2] - low[:2])) + 2 * _FRAME_MARGIN_M, _MIN_FRAME_SPAN_M)
    # From the south, about 50 degrees up, close enough for the span to fill most of a wide window.
    return centre, centre + np.array([0.0, -0.4 * span, 0.48 * span])


def _name(model, kind, index) -> str:
    name = mujoco.mj_id2name(model, kind, index)
    return name if name else f"body_{index}"
