"""A World from a checked world file: the mat image laid at its printed size, walls, obstacles, the
seeded draw of props onto their slots, and the file's scoring rules.

The draw follows the way a competition's rules draw a round: per slot group (in the file's order),
one permutation of the group's slots from the seed says which prop stands on which slot (slots past
the props stay empty), then each placed prop is nudged within its slot's jitter. One
numpy Generator carries through every group, so one seed always gives one table.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import mujoco
import numpy as np

from ..world_file import Box, Cylinder, Prop, WorldSpec
from .mat_image import load_mat
from .props import PropKind, add_prop, prop_name
from .scene import new_scene
from .scoring import FinalState
from .table import MM, WALL_RGBA, add_border, add_floor, add_mat, add_wall

_PROP_BODY = re.compile(r"^prop_\d+_(.+)$")


@dataclass(frozen=True)
class MatRaster:
    """What add_mat lays: an RGB raster and the printed size it is stretched to."""

    pixels: np.ndarray
    width_mm: float
    height_mm: float

    @property
    def width_px(self) -> int:
        return int(self.pixels.shape[1])

    @property
    def height_px(self) -> int:
        return int(self.pixels.shape[0])


def layout(spec: WorldSpec, seed: int) -> list[tuple[Prop, float, float, float]]:
    """(prop, x_mm, y_mm, heading_deg CCW) of every prop for this seed, in the file's frame."""
    rng = np.random.default_rng(seed)
    placed: list[tuple[Prop, float, float, float]] = []
    for prop in spec.props:
        if prop.at is not None:
            placed.append((prop, *prop.at))
    for group in spec.slots.values():
        members = [p for p in spec.props if p.slots == group.name for _ in range(p.count)]
        if not members:
            continue
        order = rng.permutation(len(group.positions))
        for (x, y), i in zip(group.positions, order, strict=True):
            if i >= len(members):
                continue
            dx, dy = rng.uniform(-group.jitter_mm, group.jitter_mm, size=2)
            turn = rng.uniform(-group.jitter_deg, group.jitter_deg)
            placed.append((members[i], float(x + dx), float(y + dy), float(-turn)))
    return placed


def build_scene(spec: WorldSpec, seed: int) -> mujoco.MjSpec:
    scene = new_scene(spec.name)
    if spec.props:  # resting props sleep until touched: a full table costs next to nothing per step
        scene.option.enableflags |= mujoco.mjtEnableBit.mjENBL_SLEEP
    add_floor(scene, half_size_m=max(5.0, max(spec.size_mm) * MM))
    width, height = spec.size_mm
    add_mat(scene, MatRaster(load_mat(spec.mat, spec.size_mm), width, height))
    if spec.walls is not None:
        add_border(scene, width, height, height_mm=spec.walls[0], thickness_mm=spec.walls[1])
    for index, obstacle in enumerate(spec.obstacles):
        _add_obstacle(scene, spec, index, obstacle)
    for index, (prop, x, y, heading) in enumerate(layout(spec, seed)):
        cx, cy = spec.to_centre(x, y)
        kind = PropKind(prop.size_mm, prop.mass_g / 1000.0, prop.friction)
        add_prop(scene, prop_name(index, prop.name), kind, prop.rgb, cx, cy, -heading)
    return scene


def _add_obstacle(scene, spec: WorldSpec, index: int, obstacle: Box | Cylinder) -> None:
    x, y = spec.to_centre(obstacle.x_mm, obstacle.y_mm)
    rgba = list(WALL_RGBA) if obstacle.rgb is None else [c / 255 for c in obstacle.rgb] + [1.0]
    name = obstacle.name or f"obstacle_{index:02d}"
    if isinstance(obstacle, Box):
        if obstacle.heading_deg == 0.0:
            add_wall(
                scene,
                name,
                x,
                y,
                obstacle.size_mm[0],
                obstacle.size_mm[1],
                obstacle.size_mm[2],
                rgba,
            )
            return
        yaw = math.radians(obstacle.heading_deg)
        sx, sy, sz = obstacle.size_mm
        scene.worldbody.add_geom(
            name=name,
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=[sx / 2 * MM, sy / 2 * MM, sz / 2 * MM],
            pos=[x * MM, y * MM, sz / 2 * MM],
            quat=[math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)],
            rgba=rgba,
        )
    else:
        scene.worldbody.add_geom(
            name=name,
            type=mujoco.mjtGeom.mjGEOM_CYLINDER,
            size=[obstacle.radius_mm * MM, obstacle.height_mm / 2 * MM, 0.0],
            pos=[x * MM, y * MM, obstacle.height_mm / 2 * MM],
            rgba=rgba,
        )


def scorer(spec: WorldSpec):
    """The file's rules as a scoring hook, or None when it has neither rules nor zones."""
    if not spec.rules and not spec.zones:
        return None
    zones = {z.name: z for z in spec.zones}
    kinds = {p.name: p for p in spec.props}

    def zone_of(x_mm, y_mm):
        x, y = spec.from_centre(x_mm, y_mm)
        return next((z.name for z in spec.zones if z.contains(x, y)), None)

    def score(state: FinalState) -> dict:
        props = {}
        for body, pose in sorted(state.props.items()):
            match = _PROP_BODY.match(body)
            if match and match.group(1) in kinds:
                props[body] = (kinds[match.group(1)], spec.from_centre(pose.x_mm, pose.y_mm))
        robot = spec.from_centre(state.robot.x_mm, state.robot.y_mm) if state.robot else None
        total = 0.0
        per_rule = []
        for rule in spec.rules:
            zone = zones[rule.zone]
            if rule.robot:
                hits = int(robot is not None and zone.contains(*robot) == rule.inside)
            else:
                hits = sum(
                    1
                    for kind, xy in props.values()
                    if rule.prop in ("*", kind.name, kind.colour) and zone.contains(*xy) == rule.inside
                )
            per_rule.append(hits * rule.points)
            total += hits * rule.points
        result = {
            "points": _number(total),
            "rules": [_number(p) for p in per_rule],
            "zones": {body: zone_of(*spec.to_centre(*xy)) for body, (_kind, xy) in props.items()},
            # where each prop ended on the mat (lower-left frame, mm): a sweep's rows show the draw
            "props": {body: [round(xy[0], 1), round(xy[1], 1)] for body, (_kind, xy) in props.items()},
            "robot_zone": zone_of(state.robot.x_mm, state.robot.y_mm) if state.robot else None,
        }
        if spec.time_limit_s is not None:
            result["in_time"] = state.time_s <= spec.time_limit_s + 1e-9
        return result

    return score


def _number(value: float):
    return int(value) if float(value).is_integer() else round(value, 3)
