"""The done-when of a season's table: programs run on a world made only from a PNG and a world file.
A line follower follows the printed line, a colour reader names each patch, a push scores the
rule's points, and a sweep draws a different layout per seed and the same one for a seed again."""

import json

import pytest

from openbricks_sim.job import SimJob
from openbricks_sim.run import run_program
from openbricks_sim.sweep import sweep

from .season_table import PATCH_MM, PATCHES, SIZE_MM, write_table

HALF_W, HALF_H = SIZE_MM[0] / 2, SIZE_MM[1] / 2

DRIVE = """
from openbricks.drivers.st3032 import ST3032Motor
from openbricks.robotics import DriveBase
left = ST3032Motor(servo_id=1, uart_id=1, tx=14, rx=41)
right = ST3032Motor(servo_id=2, uart_id=1, tx=14, rx=41, invert=True)
db = DriveBase(left, right, wheel_diameter_mm=88, axle_track_mm=138)
"""

LINE_FOLLOWER = (
    DRIVE
    + """
import time
from openbricks.drivers.qtr import QTRLineSensor
qtr = QTRLineSensor()
for direction, ms in ((-1, 450), (1, 900), (-1, 450)):
    db.move_wheels(direction * 120, -direction * 120)
    qtr.calibrate(duration_ms=ms, poll_ms=5)
db.stop(then="brake")
qtr.set_mode("left")
previous = 0
start = time.ticks_ms()
while time.ticks_diff(time.ticks_ms(), start) < 5000:
    error = qtr.edge_error()
    turn = 4.0 * error + 12.0 * (error - previous)
    previous = error
    db.move_wheels(300 + turn, 300 - turn)
    time.sleep_ms(5)
db.stop(then="brake")
"""
)

COLOUR_READER = (
    DRIVE
    + """
from machine import I2C, Pin
from openbricks.drivers.tca9548a import TCA9548A
from openbricks.drivers.tcs34725 import TCS34725
sensor = TCS34725(TCA9548A(I2C(0, sda=Pin(15), scl=Pin(16), freq=400_000))[0])

def name(r, g, b):
    if r > 1.5 * b and g > 1.5 * b and min(r, g) > 0.6 * max(r, g):
        return "yellow"
    top = max(r, g, b)
    return "red" if top == r else "green" if top == g else "blue"

for patch in range(4):
    if patch:
        db.straight(300)
    print(name(*sensor.rgb()))
"""
)

PUSHER = (
    DRIVE
    + """
db.settings(straight_speed=150)
db.straight(740)
"""
)


@pytest.fixture(scope="module")
def table(tmp_path_factory):
    return str(write_table(tmp_path_factory.mktemp("season")))


def run(table, source, start_xy_deg, **kw):
    x, y, heading = start_xy_deg
    return run_program(
        "mission.py", source=source, world=table, start_mm_deg=(x - HALF_W, y - HALF_H, -heading), **kw
    )


def test_a_line_follower_follows_the_printed_line(table):
    result = run(table, LINE_FOLLOWER, (250, 571, 0), limit_ms=20_000)
    assert result.exit == "finished", result.output
    assert result.pose["x_mm"] + HALF_W > 1000  # a metre and more along the line
    assert abs(result.pose["y_mm"] + HALF_H - 571) < 30  # and still on it


def test_a_colour_reader_names_each_patch(table):
    names = list(PATCHES)
    x0, y0 = PATCHES[names[0]][1]
    result = run(table, COLOUR_READER, (x0 + PATCH_MM / 2 - 60, y0 + PATCH_MM / 2 - 20, 0), limit_ms=20_000)
    assert result.exit == "finished", result.output
    assert result.output.split() == names


def test_pushing_the_block_into_its_zone_scores_the_rule(table):
    result = run(table, PUSHER, (300, 1000, 0), limit_ms=15_000)
    assert result.exit == "finished", result.output
    assert result.score["zones"]["prop_00_pusher_target"] == "green_goal"
    assert result.score["rules"][0] == 25 and result.score["points"] == 25


def test_a_sweep_draws_five_layouts_and_a_seed_again_gives_its_result_again(table, tmp_path):
    program = tmp_path / "wait.py"
    program.write_text("from openbricks.tools import wait\nimport openbricks.drivers.qtr\nwait(100)\n")
    job = SimJob(str(program), world=table, limit_ms=2_000)
    rows = sorted(sweep(job, range(5), workers=2), key=lambda row: row.seed)
    layouts = [json.dumps(row.result.score["props"], sort_keys=True) for row in rows]
    assert len(set(layouts)) == 5
    (again,) = sweep(job, [2], workers=1)
    assert again.result.score == rows[2].result.score
