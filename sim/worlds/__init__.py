"""The simulator's worlds: built from shipped files, never downloaded.

`--world` takes an alias from WORLDS, a world file (.toml beside its mat image; the built-in
worlds are such files in builtin/) or a path to an MJCF file. A world builder returns a fresh
MjSpec of the scene (floor, mat, walls, props) with no robot; the chassis is spliced in
afterwards at the start pose the world suggests (or the one the user gives).
"""

from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

import mujoco

from ..job import UnknownWorldError, world_file
from ..world_file import WorldSpec, load, open_world
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


BUILTIN = Path(__file__).parent / "builtin"


def _builtin(alias: str, score: Scoring) -> World:
    """A shipped world: its world file and mat image in builtin/, scored by its own module (the
    measures these missions report, progress along a route or the gap to a wall, are more than a
    world file's zone rules express)."""
    world = from_spec(load(BUILTIN / f"{alias}.toml"))
    return replace(world, alias=alias, score=score)


WORLDS: dict[str, World] = {
    "empty": World("empty", "a flat floor, nothing else", empty.build),
    **{
        alias: _builtin(alias, score)
        for alias, score in (
            ("line_track", line_track.score),
            ("zones", zones.score),
            ("arena", arena.score),
            ("wro", wro.score),
        )
    },
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
