"""The simulator's worlds: built by code from shipped files, never downloaded.

`--world` takes an alias from WORLDS or a path to an MJCF file. A world
builder returns a fresh MjSpec of the scene (floor, mat, walls, props) with
no robot; the chassis is spliced in afterwards at the start pose the world
suggests (or the one the user gives).
"""

from collections.abc import Callable
from dataclasses import dataclass

import mujoco

from ..job import UnknownWorldError, world_file
from ..world_file import WorldSpec, open_world
from . import arena, empty, line_track, wro, zones
from .scoring import FinalState, Scoring, final_state


@dataclass(frozen=True)
class World:
    alias: str
    description: str
    build: Callable[[int], mujoco.MjSpec]  # seed -> scene spec
    start_mm_deg: tuple[float, float, float] = (0.0, 0.0, 0.0)  # x, y, heading
    score: Scoring | None = None  # FinalState -> score dict; None: the world has no mission
    spec: WorldSpec | None = None  # the world file it was read from, if any


def from_spec(spec: WorldSpec) -> World:
    """A World of a checked world file: its scene is built per seed, its mat read once per process."""
    from . import from_file

    return World(
        spec.name,
        spec.description,
        lambda seed: from_file.build_scene(spec, seed),
        spec.start_mm_deg,
        from_file.scorer(spec),
        spec,
    )


WORLDS: dict[str, World] = {
    "empty": World("empty", "a flat floor, nothing else", empty.build),
    "line_track": World(
        "line_track",
        "a 20 mm black line on a 2000 x 1200 mm mat: bends, a junction and a finish bar",
        line_track.build,
        line_track.START_MM_DEG,
        line_track.score,
    ),
    "zones": World(
        "zones",
        "coloured zones and a skewed black align line on a 1500 x 1000 mm mat",
        zones.build,
        zones.START_MM_DEG,
        zones.score,
    ),
    "arena": World(
        "arena",
        "a 1600 x 1000 mm arena walled in 100 mm high, with a pillar: for the distance sensors",
        arena.build,
        arena.START_MM_DEG,
        arena.score,
    ),
    "wro": World(
        "wro",
        "a WRO-size 2362 x 1143 mm competition table: printed mat, walls, 12 blocks shuffled by the seed",
        wro.build,
        wro.START_MM_DEG,
        wro.score,
    ),
}

__all__ = ["WORLDS", "FinalState", "Scoring", "UnknownWorldError", "World", "final_state", "resolve"]


def resolve(name_or_path: str) -> World:
    """An alias from WORLDS, a world file (.toml, or a mat image as IMAGE@WxH), or an MJCF file (its
    own floor and props; start at the origin)."""
    if name_or_path in WORLDS:
        return WORLDS[name_or_path]
    spec = open_world(name_or_path)  # raises WorldFileError (an UnknownWorldError) naming each problem
    if spec is not None:
        return from_spec(spec)
    path = world_file(name_or_path)  # what can be told without MuJoCo, told the same way everywhere
    if path is None:  # an alias of job.WORLD_ALIASES that WORLDS lacks: a test keeps them in step
        raise UnknownWorldError(f"unknown world {name_or_path!r}")
    try:
        mujoco.MjSpec.from_file(str(path))
    except ValueError as exc:  # MuJoCo's parser: the file, line and what is wrong
        raise UnknownWorldError(f"world file {path} is not a model MuJoCo can load: {exc}") from None
    return World(path.stem, f"MJCF file {path}", lambda _seed: mujoco.MjSpec.from_file(str(path)))
