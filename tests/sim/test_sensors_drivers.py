"""The unchanged hub drivers (openbricks.drivers) against the simulated robot's sensor rig, through
the shim's machine buses: what a program on the hub would read, standing in each world."""

import math

import pytest

from openbricks_sim.shim import Shim
from openbricks_sim.simulation import Simulation
from openbricks_sim.worlds import WORLDS, arena

SITE_AHEAD_MM = 95.0  # the chassis' distance site


@pytest.fixture
def hub(request):
    world, start = request.param
    sim = Simulation(world, "st3032", seed=1, start_mm_deg=start, epoch_ms=0)
    with Shim(sim):
        yield sim
    sim.close()


def free_joint_qpos(physics):
    """Where the robot's free joint (x, y, z, then the orientation quaternion) starts in qpos."""
    return physics.model.joint("robot_free").qposadr[0]


def at(world, x_mm, y_mm, heading_deg=0.0):
    return pytest.mark.parametrize("hub", [(world, (x_mm, y_mm, heading_deg))], indirect=True)


def colour_sensors():
    from machine import I2C, Pin

    from openbricks.drivers.tca9548a import TCA9548A
    from openbricks.drivers.tcs34725 import TCS34725

    mux = TCA9548A(I2C(0, sda=Pin(15), scl=Pin(16), freq=400_000))
    return TCS34725(mux[0]), TCS34725(mux[1])


@at("zones", 440.0, 120.0)  # on the red zone's north edge: left sensor over white, right over red
def test_tcs34725_driver_behind_the_mux_names_the_colours_under_each_sensor(hub):
    left, right = colour_sensors()
    r, g, b = right.rgb()
    assert r > 200 and g < 40 and b < 40
    assert min(left.rgb()) > 235
    assert 75 <= left.ambient() <= 95
    assert right.ambient() < left.ambient()


@at("line_track", WORLDS["line_track"].start_mm_deg[0], WORLDS["line_track"].start_mm_deg[1] - 20.0)
def test_tcs34725_over_the_black_line_reads_dark(hub):
    left, right = colour_sensors()  # the left sensor (20 mm left of centre) sits on the line
    assert left.ambient() < 8
    assert right.ambient() > 75


@at("line_track", *WORLDS["line_track"].start_mm_deg)
def test_qtr_line_sensor_calibrates_on_a_sweep_and_sees_the_line_centred(hub):
    import time

    from openbricks.drivers.qtr import QTRLineSensor

    qtr = QTRLineSensor()
    robot = hub.physics
    # Sweep by hand, as a person would: slide the robot across the line while calibrate() runs.
    y = free_joint_qpos(robot) + 1
    y0 = robot.data.qpos[y]
    for step in range(-40, 41, 4):
        robot.data.qpos[y] = y0 + step / 1000.0
        qtr.calibrate(duration_ms=10)
    robot.data.qpos[y] = y0
    time.sleep_ms(5)
    reading = qtr.read()
    assert qtr.calibrated()
    assert abs(reading.position()) < 2.0
    assert reading.dark_count() in (2, 4)
    qtr.set_mode("left")
    assert reading.edge_error() > 40  # the left setpoint element (-16 mm) sits on white mat


@at("arena", -500.0, 0.0)
def test_vl53l0x_driver_behind_the_mux_ranges_the_east_wall(hub):
    from machine import I2C, Pin

    from openbricks.drivers.tca9548a import TCA9548A
    from openbricks.drivers.tcs34725 import TCS34725
    from openbricks.drivers.vl53l0x import VL53L0X

    # The baseline build: every 0x29 part on its own mux channel, so they share the bus.
    mux = TCA9548A(I2C(0, sda=Pin(15), scl=Pin(16)))
    colour = TCS34725(mux[0])
    tof = VL53L0X(mux[7])
    assert colour.ambient() > 50  # plain light-grey arena floor
    expected = arena.INNER_MM[0] / 2 - (-500.0 + SITE_AHEAD_MM)
    assert abs(tof.distance_mm() - expected) <= 2


@pytest.mark.parametrize("hub, bare", [(("arena", (-500.0, 0.0, 0.0)), "vl53l1x")], indirect=["hub"])
def test_a_bare_range_finder_build_wires_it_straight_to_the_bus(hub, bare):
    from machine import I2C, Pin

    from openbricks.drivers.vl53l1x import VL53L1X
    from openbricks_sim.sensors.rig import attach_sensors

    attach_sensors(hub.physics, hub.board, seed=1, bare_0x29=bare)
    tof = VL53L1X(I2C(0, sda=Pin(15), scl=Pin(16)))
    expected = arena.INNER_MM[0] / 2 - (-500.0 + SITE_AHEAD_MM)
    assert abs(tof.distance_mm() - expected) <= 2


@at("arena", -500.0, 0.0)
def test_hcsr04_driver_times_the_echo_from_the_east_wall(hub):
    from openbricks.drivers.hcsr04 import HCSR04

    sonar = HCSR04(trig=18, echo=40)
    expected = arena.INNER_MM[0] / 2 - (-500.0 + SITE_AHEAD_MM)
    assert abs(sonar.distance_mm() - expected) <= 5


@at("empty", 0.0, 0.0)
def test_icm45686_driver_learns_its_bias_at_rest_and_holds_heading(hub):
    import time

    from openbricks.drivers.icm45686 import ICM45686

    imu = ICM45686(sck=12, mosi=13, miso=11, cs=17)
    while not imu.calibrated():
        time.sleep_ms(100)
    imu.reset_heading(0)
    time.sleep_ms(5000)
    assert abs(imu.heading()) < 0.2  # a 0.5 dps bias left unlearned would be 2.5 degrees


@at("empty", 0.0, 0.0)
def test_bno055_driver_heading_follows_a_spin_clockwise_positive(hub):
    import time

    from machine import I2C, Pin

    from openbricks.drivers.bno055 import BNO055

    imu = BNO055(I2C(0, sda=Pin(15), scl=Pin(16)))
    robot = hub.physics
    assert abs(imu.heading()) < 0.5
    # Turn the robot 30 degrees clockwise by hand (MuJoCo yaw is counter-clockwise).
    q = free_joint_qpos(robot)
    half = math.radians(-30.0) / 2
    robot.data.qpos[q + 3 : q + 7] = [math.cos(half), 0.0, 0.0, math.sin(half)]
    time.sleep_ms(20)
    assert imu.heading() == pytest.approx(30.0, abs=0.5)


def test_the_rig_is_wired_as_documented_and_no_0x29_part_sits_on_the_bare_bus():
    from openbricks_sim.sensors import rig

    sim = Simulation("empty", "st3032", seed=0, epoch_ms=0)
    try:
        sensors = sim.sensors
        assert set(sim.board.i2c_bus(rig.I2C_BUS)) == {rig.MUX_ADDRESS, rig.BNO055_ADDRESS, rig.OLED_ADDRESS}
        assert [ch for ch in range(8) if sensors.mux.channels[ch]] == [0, 1, rig.RANGE_FINDER_CHANNEL]
        assert sim.board.spi_devices[rig.ICM45686_CS] is sensors.icm45686
        assert all(pin in sim.board.analog for pin in range(1, 11))
        assert rig.HCSR04_ECHO in sim.board.pulses
        with pytest.raises(ValueError, match="bare_0x29 must be one of"):
            rig.attach_sensors(sim.physics, sim.board, bare_0x29="tcs3472")
    finally:
        sim.close()
