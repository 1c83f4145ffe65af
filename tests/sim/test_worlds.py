"""The worlds: they compile with either robot, hold still, carry their mats where the layout says,
shuffle props by seed, and score a final state the way a mission would be judged."""

import math

import mujoco
import numpy as np
import pytest

from openbricks_sim.chassis import CHASSIS, ROBOT_BODY, add_chassis
from openbricks_sim.worlds import (
    WORLDS,
    FinalState,
    UnknownWorldError,
    arena,
    final_state,
    from_file,
    line_track,
    resolve,
    wro,
    zones,
)
from openbricks_sim.worlds.scoring import Pose

MISSION_WORLDS = ("line_track", "zones", "arena", "wro")


def compile_world(alias, chassis="st3032", seed=0, pose=None):
    world = WORLDS[alias]
    spec = world.build(seed)
    add_chassis(spec, CHASSIS[chassis], *(pose or world.start_mm_deg))
    model = spec.compile()
    return model, mujoco.MjData(model)


@pytest.mark.parametrize("alias", sorted(WORLDS))
@pytest.mark.parametrize("chassis", sorted(CHASSIS))
def test_every_world_compiles_and_the_robot_rests_at_its_start_pose(alias, chassis):
    model, data = compile_world(alias, chassis)
    mujoco.mj_step(model, data, nstep=500)
    pose = final_state(model, data).robot
    x, y, heading = WORLDS[alias].start_mm_deg
    assert math.hypot(pose.x_mm - x, pose.y_mm - y) < 1.0
    assert abs(pose.heading_deg - heading) < 0.2
    assert np.all(np.isfinite(data.qpos))
    assert data.body(ROBOT_BODY).xpos[2] > 0.02  # standing on the mat, not sunk through it


def test_mission_worlds_have_a_scoring_hook_and_an_empty_floor_has_none():
    for alias in MISSION_WORLDS:
        assert callable(WORLDS[alias].score)
    assert WORLDS["empty"].score is None


def mat_texture(model, geom="mat"):
    """The mat's texture as an (H, W, 3) array, straight out of the compiled model."""
    material = model.geom_matid[model.geom(geom).id]
    tex = model.mat_texid[material][mujoco.mjtTextureRole.mjTEXROLE_RGB]
    h, w = model.tex_height[tex], model.tex_width[tex]
    start = model.tex_adr[tex]
    return model.tex_data[start : start + h * w * 3].reshape(h, w, 3)


def texel_at(model, x_mm, y_mm, geom="mat"):
    img = mat_texture(model, geom)
    half_x, half_y = (model.geom(geom).size[:2] * 1000.0).tolist()
    col = int((x_mm + half_x) / (2 * half_x) * img.shape[1])
    row = int((half_y - y_mm) / (2 * half_y) * img.shape[0])
    return tuple(int(v) for v in img[row, col])


def test_line_track_prints_the_line_from_start_to_the_finish_bar_and_the_branch_to_the_right():
    model, _ = compile_world("line_track")
    path, (jx, jy) = line_track.route()
    for x, y in path.points()[::25]:
        assert max(texel_at(model, x, y)) < 60, f"no line at ({x:.0f}, {y:.0f})"
    assert max(texel_at(model, jx, jy - line_track.BRANCH_MM + 15)) < 60  # the branch, below the line
    assert min(texel_at(model, jx, jy + 60)) > 200  # and nothing mirrored above it
    ex, ey = path.x_mm, path.y_mm
    for dx in (-70, 0, 70):  # the finish bar spans more than the 56 mm QTR window
        assert max(texel_at(model, ex + dx, ey - 20)) < 60
    assert min(texel_at(model, -500, 300)) > 200  # open mat is white


def test_zones_mat_colours_match_the_zone_table():
    model, _ = compile_world("zones")
    for name, (x0, y0, x1, y1, rgb) in zones.ZONES.items():
        assert texel_at(model, (x0 + x1) / 2, (y0 + y1) / 2) == rgb, name


def test_wro_table_is_competition_size_and_walled():
    model, _ = compile_world("wro")
    assert tuple(np.round(model.geom("mat").size[:2] * 2000.0, 1)) == (2362.0, 1143.0)
    north = model.geom("wall_north")
    assert north.pos[1] - north.size[1] == pytest.approx(1.143 / 2)
    assert mat_texture(model).nbytes < 16 * 2**20  # the bar is 120 MB per process, all in


def prop_layout(model):
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return {name: (round(p.x_mm, 3), round(p.y_mm, 3)) for name, p in final_state(model, data).props.items()}


def test_wro_seed_gives_a_reproducible_layout_of_twelve_blocks():
    build = WORLDS["wro"].build
    first = prop_layout(build(7).compile())
    again = prop_layout(build(7).compile())
    other = prop_layout(build(8).compile())
    assert len(first) == 12
    assert first == again
    assert first != other
    colours = sorted(name.rsplit("_", 1)[-1] for name in first)
    assert colours == sorted(["red", "green", "blue", "yellow"] * 3)


def test_wro_blocks_stay_on_their_slots_whatever_the_seed():
    spec = WORLDS["wro"].spec
    slots = np.array([spec.to_centre(*p) for p in spec.slots["table"].positions])
    jitter = spec.slots["table"].jitter_mm
    for seed in range(5):
        for x, y in prop_layout(WORLDS["wro"].build(seed).compile()).values():
            assert np.min(np.hypot(slots[:, 0] - x, slots[:, 1] - y)) <= jitter * math.sqrt(2)


def test_wro_blocks_have_mass_and_move_when_the_robot_drives_into_one():
    # Put the robot just behind a block and push it with a plain speed loop on both wheels.
    spec = WORLDS["wro"].spec
    layout = [(p.colour, *spec.to_centre(x, y), -h) for p, x, y, h in from_file.layout(spec, 0)]
    colour, bx, by, _ = layout[0]
    model, data = compile_world("wro", pose=(bx - 140.0, by, 0.0))
    block = model.body(f"prop_00_{colour}")
    assert model.body_mass[block.id] == pytest.approx(0.05)  # a 50 g LEGO-built element
    wheels = [model.joint(name).dofadr[0] for name in ("left_wheel", "right_wheel")]
    for _ in range(800):  # about 150 mm of travel: the block moves, but not into its neighbour
        data.ctrl[:] = 0.3 * (math.radians(300) - data.qvel[wheels])
        mujoco.mj_step(model, data)
    moved = final_state(model, data).props[f"prop_00_{colour}"]
    assert moved.x_mm > bx + 50.0  # shoved forward, not a fixed obstacle
    for name, pose in final_state(model, data).props.items():  # the others did not stir
        if name != f"prop_00_{colour}":
            _, x, y, _ = layout[int(name[5:7])]
            assert math.hypot(pose.x_mm - x, pose.y_mm - y) < 0.5


def test_wro_scores_blocks_in_targets_of_their_own_colour():
    red_target = next(v for v in wro.TARGETS.values() if v[2] == "red")
    blue_target = next(v for v in wro.TARGETS.values() if v[2] == "blue")
    state = FinalState(
        robot=Pose(0, 0, 0),
        props={
            "prop_00_red": Pose(red_target[0] + 30, red_target[1] - 40, 10),
            "prop_01_red": Pose(blue_target[0], blue_target[1], 0),
            "prop_02_green": Pose(-600, 170, 0),
        },
    )
    result = wro.score(state)
    assert result["points"] == 10
    assert result["sorted"] == 1
    assert result["in_wrong_target"] == 1
    assert result["targets"]["prop_02_green"] is None


def test_line_track_scores_a_stop_at_the_finish_bar_and_not_a_stop_short_or_past_it():
    path, _ = line_track.route()
    ex, ey = path.x_mm, path.y_mm  # the bar's near edge; the home straight runs toward -y
    at_bar = line_track.score(FinalState(robot=Pose(ex, ey + 70, 90)))
    assert at_bar["finished"] and at_bar["progress_pct"] > 95
    assert not line_track.score(FinalState(robot=Pose(ex, ey + 400, 90)))["finished"]
    assert not line_track.score(FinalState(robot=Pose(ex, ey - 200, 90)))["finished"]
    start = line_track.score(FinalState(robot=Pose(*WORLDS["line_track"].start_mm_deg)))
    assert not start["finished"] and start["progress_mm"] == pytest.approx(50.0, abs=1.0)


def test_zones_score_names_the_zone_under_the_robot():
    assert zones.score(FinalState(robot=Pose(500, 0, 0))) == {"zone": "red"}
    assert zones.score(FinalState(robot=Pose(500, 300, 0))) == {"zone": "green"}
    assert zones.score(FinalState(robot=Pose(*WORLDS["zones"].start_mm_deg))) == {"zone": None}


def test_arena_score_measures_the_gap_to_the_walls():
    start = arena.score(FinalState(robot=Pose(*WORLDS["arena"].start_mm_deg)))
    assert start == {"nearest_wall_mm": 300.0, "ahead_mm": 1300.0}
    facing_pillar = arena.score(FinalState(robot=Pose(300, -200, -90)))  # heading -90: facing +y
    assert facing_pillar["ahead_mm"] == pytest.approx(350.0)


def test_resolve_takes_an_alias_or_an_mjcf_file_and_names_the_choices_otherwise(tmp_path):
    assert resolve("wro") is WORLDS["wro"]
    xml = tmp_path / "ramp.xml"
    xml.write_text('<mujoco><worldbody><geom name="ground" type="plane" size="1 1 .1"/></worldbody></mujoco>')
    model = resolve(str(xml)).build(0).compile()
    assert model.geom("ground").type == mujoco.mjtGeom.mjGEOM_PLANE
    with pytest.raises(UnknownWorldError, match="line_track"):
        resolve("linetrack")


def test_the_arena_scores_the_faces_its_world_file_builds():
    model, _ = compile_world("arena")
    pillar = model.geom("pillar")
    px, py, side = arena.PILLAR_MM
    assert tuple(np.round(pillar.pos[:2] * 1000, 3)) == (px, py)
    assert tuple(np.round(pillar.size[:2] * 2000, 3)) == (side, side)
    east = model.geom("wall_east")
    assert (east.pos[0] - east.size[0]) * 1000 == pytest.approx(arena.INNER_MM[0] / 2)


def test_the_builtin_mats_are_the_images_their_script_draws():
    from openbricks_sim.worlds.builtin import draw_mats

    for alias, draw in draw_mats.MATS.items():
        model, _ = compile_world(alias)
        assert np.array_equal(mat_texture(model), draw().pixels), alias
