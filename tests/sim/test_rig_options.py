"""The sensor rig's build options reach a run: the colour sensor or range finder wired straight to the
I2C bus with no mux (`bare_0x29`), and which laser range finder sits on the mux (`range_finder`),
through run_program, `python -m openbricks_sim.run` and `openbricks sim run`."""

import json

from openbricks_sim import cli
from openbricks_sim.run import ERROR, FINISHED, run_program
from openbricks_sim.sensors import rig
from openbricks_sim.worlds import arena

# The left colour site (60 mm ahead, 20 mm left of the axle) over the zones mat's red zone.
OVER_RED = (440.0, 80.0, 0.0)

BARE_COLOUR_SENSOR = """\
from machine import I2C, Pin
from openbricks.drivers.tcs34725 import TCS34725

colour = TCS34725(I2C(0, sda=Pin(15), scl=Pin(16), freq=400_000))
r, g, b = colour.rgb()
print("red" if r > 2 * g and r > 2 * b else "not red", r, g, b)
"""

RANGE_FINDER_ON_THE_MUX = """\
from machine import I2C, Pin
from openbricks.drivers.tca9548a import TCA9548A
from openbricks.drivers.vl53l1x import VL53L1X

mux = TCA9548A(I2C(0, sda=Pin(15), scl=Pin(16)))
print(VL53L1X(mux[7]).distance_mm())
"""


def run(source, **kwargs):
    return run_program("mission.py", source=source, **kwargs)


def test_a_colour_sensor_wired_straight_to_the_bus_reads_the_mat():
    result = run(BARE_COLOUR_SENSOR, world="zones", start_mm_deg=OVER_RED, bare_0x29="tcs34725")
    assert result.exit == FINISHED, result.error
    assert result.output.startswith("red ")
    assert result.job["bare_0x29"] == "tcs34725"


def test_without_the_option_the_colour_sensor_the_program_builds_on_the_bare_bus_is_wired_there():
    result = run(BARE_COLOUR_SENSOR, world="zones", start_mm_deg=OVER_RED)
    assert result.exit == FINISHED, result.error
    assert result.output.startswith("red ")


def test_the_mux_carries_the_range_finder_the_run_asks_for():
    start = (-500.0, 0.0, 0.0)
    expected_mm = arena.INNER_MM[0] / 2 - (start[0] + 95.0)  # the east wall from the distance site
    result = run(RANGE_FINDER_ON_THE_MUX, world="arena", start_mm_deg=start, range_finder="vl53l1x")
    assert result.exit == FINISHED, result.error
    assert abs(int(result.output) - expected_mm) <= 2
    assert run(RANGE_FINDER_ON_THE_MUX, world="arena", start_mm_deg=start).exit == ERROR  # a VL53L0X


def test_openbricks_sim_run_passes_the_rig_options_and_the_hub_dir(tmp_path, capsys):
    script = tmp_path / "mission.py"
    script.write_text(BARE_COLOUR_SENSOR + "open('/seen.txt', 'w').write('red')\n")
    x_m, y_m = OVER_RED[0] / 1000, OVER_RED[1] / 1000
    hub = tmp_path / "hub"
    status = cli.main(
        ["run", str(script), "--world", "zones", "--x", str(x_m), "--y", str(y_m), "--yaw", "0"]
        + ["--bare-0x29", "tcs34725", "--range-finder", "vl53l1x", "--hub-dir", str(hub), "--json"]
    )
    summary = json.loads(capsys.readouterr().out)
    assert status == cli.EXIT_OK, summary["error"]
    assert summary["output"].startswith("red ")
    assert summary["job"]["range_finder"] == "vl53l1x" and summary["seed"] == 0
    assert (hub / "seen.txt").read_text() == "red"


def test_the_clis_choices_are_the_rigs():
    assert set(cli.RANGE_FINDERS) == set(rig.RANGE_FINDERS)
    assert set(cli.BARE_0X29_PARTS) == {part for part in rig.BARE_0X29 if part is not None}
