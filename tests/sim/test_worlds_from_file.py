"""A world built from a world file and a PNG: the mat lies at its printed size, the sensors read it
where it was printed, props are drawn by the seed, and the file's rules score a final state."""

import mujoco
import numpy as np
import pytest

from openbricks_sim.chassis import CHASSIS, add_chassis
from openbricks_sim.sensors.color import TCS34725Model
from openbricks_sim.sensors.mat import GroundProbe, srgb_to_linear
from openbricks_sim.sensors.qtr import POSITIONS_MM, QTRBarModel
from openbricks_sim.sensors.registers import physics_clock_us
from openbricks_sim.worlds import FinalState, resolve
from openbricks_sim.worlds.from_file import layout
from openbricks_sim.worlds.scoring import Pose

from .season_table import INK, LINE_Y_MM, PAPER, PATCH_MM, PATCHES, SIZE_MM, write_table

HALF_W, HALF_H = SIZE_MM[0] / 2, SIZE_MM[1] / 2


@pytest.fixture(scope="module")
def table(tmp_path_factory):
    return write_table(tmp_path_factory.mktemp("season"))


@pytest.fixture(scope="module")
def world(table):
    return resolve(str(table))


def placed(world, x_mm, y_mm, heading_ccw_deg=0.0, seed=0):
    """The robot settled at a pose given in the mat's lower-left frame."""
    spec = world.build(seed)
    add_chassis(spec, CHASSIS["st3032"], x_mm - HALF_W, y_mm - HALF_H, -heading_ccw_deg)
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_step(model, data, nstep=100)
    return model, data


def test_the_mat_texture_is_the_png_stretched_to_the_printed_size(world):
    model = world.build(0).compile()
    mat = model.geom("mat")
    assert tuple(np.round(mat.size[:2] * 2000, 3)) == (2362.0, 1143.0)
    texture = model.texture("mat_texture")
    assert (int(texture.width[0]), int(texture.height[0])) == SIZE_MM
    assert world.start_mm_deg == (250 - HALF_W, 571 - HALF_H, -0.0)
    walls = [model.geom(i).name for i in range(model.ngeom) if model.geom(i).name.startswith("wall_")]
    assert len(walls) == 4


def test_a_line_edge_reads_where_it_is_printed_within_a_millimetre(world):
    # The robot faces +y across the line; samples along the sensor's forward axis walk across the edge.
    model, data = placed(world, 1800, 500, heading_ccw_deg=90)
    probe = GroundProbe(model, data)
    site = model.site("color_0").id
    offsets = np.arange(-60.0, 60.0, 0.05)
    spots = np.zeros((len(offsets), 1, 2))
    spots[:, 0, 0] = offsets / 1000.0
    reflectance, _ = probe.look(site, spots)
    level = reflectance.mean(axis=1)
    mid = (srgb_to_linear(PAPER).mean() + srgb_to_linear(INK).mean()) / 2
    dark = level < mid
    first = int(np.argmax(dark))
    last = len(dark) - 1 - int(np.argmax(dark[::-1]))
    site_y = data.site_xpos[site][1] * 1000.0 + HALF_H
    lower_edge, upper_edge = site_y + offsets[first], site_y + offsets[last]
    assert abs(lower_edge - LINE_Y_MM[0]) <= 1.0
    assert abs(upper_edge - LINE_Y_MM[1]) <= 1.0


def test_the_qtr_bar_sees_the_line_under_its_middle_elements(world):
    model, data = placed(world, 1600, 571)  # facing +x along the line: the bar lies across it
    bar = QTRBarModel(GroundProbe(model, data), physics_clock_us(data), noise_counts=0.0)
    raw = bar.raw12()
    on_line = [abs(x) < 10 for x in POSITIONS_MM]  # the 20 mm line under elements at -4 and +4 mm
    assert min(r for r, dark in zip(raw, on_line, strict=True) if dark) > 3000
    assert max(r for r, dark in zip(raw, on_line, strict=True) if not dark) < 1000


@pytest.mark.parametrize("name", sorted(PATCHES))
def test_each_colour_patch_reads_its_colour_where_it_is_printed(world, name):
    rgb, (x0, y0) = PATCHES[name]
    # color_0 sits 60 mm ahead and 20 mm left of the robot's centre: put it over the patch's middle.
    model, data = placed(world, x0 + PATCH_MM / 2 - 60, y0 + PATCH_MM / 2 - 20)
    chip = TCS34725Model(GroundProbe(model, data), "color_0", physics_clock_us(data))
    light = np.asarray(chip.light_per_cycle())  # R, G, B as the chip integrates them
    seen, _ = GroundProbe(model, data).look(model.site("color_0").id, np.zeros((1, 1, 2)))
    assert np.allclose(seen[0], srgb_to_linear(rgb), atol=0.01)  # the patch's own print colour
    assert np.argmax(light) == np.argmax(rgb)


def test_five_seeds_give_five_layouts_and_a_seed_gives_its_layout_again(table):
    from openbricks_sim.world_file import load

    spec = load(table)
    layouts = [
        tuple((p.name, round(x, 6), round(y, 6)) for p, x, y, _h in layout(spec, seed)) for seed in range(5)
    ]
    assert len(set(layouts)) == 5
    assert layout(spec, 3) == layout(spec, 3)
    for placed_props in layouts:
        assert sorted(name for name, _x, _y in placed_props) == [
            "blue",
            "pusher_target",
            "red_block",
            "red_block",
        ]


def test_the_rules_score_a_prop_in_its_zone_and_the_robot_parked(world):
    inside = Pose(1150 - HALF_W, 1000 - HALF_H, 0.0)
    outside = Pose(700 - HALF_W, 571 - HALF_H, 0.0)
    parked = Pose(2100 - HALF_W, 600 - HALF_H, 0.0)
    score = world.score(FinalState(robot=parked, props={"prop_00_pusher_target": inside}, time_s=10.0))
    assert score["points"] == 30 and score["rules"] == [25, 5]
    assert score["zones"] == {"prop_00_pusher_target": "green_goal"} and score["robot_zone"] == "parking"
    assert score["in_time"] is True
    score = world.score(FinalState(robot=outside, props={"prop_00_pusher_target": outside}, time_s=200.0))
    assert score["points"] == 0 and score["in_time"] is False


def test_a_bare_image_is_an_empty_walled_table_of_the_given_size(table):
    world = resolve(f"{table.parent / 'mat.png'}@1181x571.5")
    model = world.build(0).compile()
    assert tuple(np.round(model.geom("mat").size[:2] * 2000, 3)) == (1181.0, 571.5)
    assert world.start_mm_deg == (0.0, 0.0, -0.0) and world.score is None


def test_a_pdf_mat_renders_its_first_page_at_the_printed_size(tmp_path):
    from PIL import Image

    from openbricks_sim.worlds.mat_image import MAX_PX_PER_MM, load_mat

    pixels = np.full((100, 200, 3), PAPER, dtype=np.uint8)
    pixels[:, 100:] = PATCHES["blue"][0]
    Image.fromarray(pixels).save(tmp_path / "mat.pdf", resolution=72)
    mat = load_mat(tmp_path / "mat.pdf", (400.0, 200.0))
    h, w = round(200 * MAX_PX_PER_MM), round(400 * MAX_PX_PER_MM)
    assert mat.shape == (h, w, 3)
    assert np.abs(mat[h // 2, w // 4].astype(int) - PAPER).max() < 8  # the left half: paper
    assert np.abs(mat[h // 2, 3 * w // 4].astype(int) - PATCHES["blue"][0]).max() < 8


def test_a_finer_image_is_reduced_to_a_texel_a_millimetre_with_its_edge_where_it_was_printed(tmp_path):
    from PIL import Image

    from openbricks_sim.worlds.mat_image import load_mat

    # 400 x 200 mm drawn at 2.5 px/mm: ink from the left edge up to x = 123.2 mm (pixel 308).
    pixels = np.full((500, 1000, 3), PAPER, dtype=np.uint8)
    pixels[:, :308] = INK
    Image.fromarray(pixels).save(tmp_path / "fine.png")
    mat = load_mat(tmp_path / "fine.png", (400.0, 200.0))
    assert mat.shape == (200, 400, 3)
    level = srgb_to_linear(mat[100]).mean(axis=1)  # along x, texel centres at i + 0.5 mm
    mid = (srgb_to_linear(PAPER).mean() + srgb_to_linear(INK).mean()) / 2
    i = int(np.argmax(level > mid))
    edge = i - 0.5 + (mid - level[i - 1]) / (level[i] - level[i - 1])  # linear between texel centres
    assert abs(edge - 123.2) <= 1.0
