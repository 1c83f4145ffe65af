"""The emulated serial bus: the unchanged ST3032Motor driver against servos whose loops run natively
on the simulated wheels, and the firmware's C engine a DriveBase adopts the wheels onto, talking to
them over an emulated wire with 1 Mbaud half-duplex byte timing."""

import pytest

import openbricks_native as native
from openbricks_sim.shim import Shim
from openbricks_sim.simulation import Simulation


@pytest.fixture
def sim():
    s = Simulation("empty", "st3032", epoch_ms=0)
    with Shim(s):
        yield s
    s.close()


def motors():
    from openbricks.drivers.st3032 import ST3032Motor

    return ST3032Motor(1), ST3032Motor(2, invert=True)


def test_the_driver_pings_and_runs_a_speed_on_the_servos_own_loop(sim):
    import time

    left, right = motors()
    left.run_speed(360)
    right.run_speed(360)
    time.sleep_ms(1500)
    assert left.speed() == pytest.approx(360, rel=0.03)
    assert right.speed() == pytest.approx(360, rel=0.03)
    pose = sim.physics.pose()
    assert pose.x_mm > 300, "invert=True on the mirrored right servo: both wheels roll forward"
    assert abs(pose.heading_deg) < 1.0
    bus = sim.wiring.bus
    assert bus.servo(1).mode == native.scs.MODE_WHEEL and bus.servo(1).torque_enabled


def test_multi_turn_angle_follows_the_wheel_far_past_the_position_register_window(sim):
    import time

    left, _ = motors()
    left.run_speed(720)
    for _ in range(15):  # 15 s at 2 turns/s: 30 turns, the register window holds about 8
        time.sleep_ms(1000)
        left.angle()
    left.brake()
    time.sleep_ms(300)
    true_deg = sim.physics.wheel_angle_deg(0)
    assert true_deg > 30 * 360 * 0.95
    assert left.angle() == pytest.approx(true_deg, abs=0.2)


def test_run_angle_moves_by_relative_steps_and_holds(sim):
    left, _ = motors()
    start = left.angle()
    left.run_angle(360, 720)  # waits until the step parks
    assert left.angle() - start == pytest.approx(720, abs=1.0)
    assert sim.physics.wheel_angle_deg(0) == pytest.approx(start + 720, abs=1.0)


def test_open_loop_duty_spins_at_a_share_of_no_load_speed(sim):
    import time

    left, _ = motors()
    left.dc(50)
    time.sleep_ms(1000)
    assert sim.wiring.bus.servo(1).mode == native.scs.MODE_DUTY
    assert 300 < left.speed() < 450, "half duty: about half of 888 deg/s, less the robot's load"


def test_a_missing_servo_is_reported_like_on_the_hub(sim):
    from openbricks.drivers.st3032 import ST3032Motor

    with pytest.raises(OSError, match="not responding on the bus"):
        ST3032Motor(7)


def test_an_adopted_pair_runs_a_native_drivebase_from_the_bus_engine(sim):
    import _openbricks_native

    engine = _openbricks_native.serial_bus(1)
    left_slot = engine.adopt(1)
    right_slot = engine.adopt(2, invert=True)
    assert sim.wiring.bus.servo(1).mode == native.scs.MODE_DUTY
    db = native.DriveBase(88, 138, left_io=engine.motor_io(left_slot), right_io=engine.motor_io(right_slot))
    _openbricks_native.motor_process.subscribe(db)
    x0 = sim.physics.pose().x_mm
    db.straight(300, then="hold")
    sim.clock.advance_us(3_000_000)
    assert db.done()
    assert sim.physics.pose().x_mm - x0 == pytest.approx(300, abs=2.0)
    assert engine.angle_deg(right_slot) == pytest.approx(engine.angle_deg(left_slot), abs=2.0)
    replies, failed, in_a_row = engine.stats(left_slot)
    assert replies >= 3000 and failed == 0 and in_a_row == 0


def test_drive_wheel_runs_the_simulated_servos_own_speed_loop_and_lands_the_moves(sim):
    from openbricks.robotics import DriveBase

    left, right = motors()
    db = DriveBase(left, right, wheel_diameter_mm=88, axle_track_mm=138, drive="wheel")
    db.straight(300)
    pose = sim.physics.pose()
    assert pose.x_mm == pytest.approx(300, abs=3.0)
    db.turn(90)
    assert sim.physics.pose().heading_deg == pytest.approx(90, abs=1.5)


def test_adopted_wheels_run_angle_and_hold_on_the_engines_own_slot_core(sim):
    import time

    from openbricks.robotics import DriveBase

    left, right = motors()
    db = DriveBase(left, right, wheel_diameter_mm=88, axle_track_mm=138)
    db.straight(100)
    start = left.angle()
    left.run_angle(360, 360)  # the drive base lets go; st_move_core runs the move on the tick
    assert left.done()
    assert left.angle() - start == pytest.approx(360, abs=3.0)
    right.hold()
    held = right.angle()
    time.sleep_ms(300)
    assert right.angle() == pytest.approx(held, abs=1.0)
    db.straight(100)  # and the drive base takes both wheels back
    assert db.done()


def test_the_engine_speaks_scs_packets_on_the_wire_with_real_byte_timing(sim):
    import _openbricks_native

    engine = _openbricks_native.serial_bus(1)
    left_slot, right_slot = engine.adopt(1), engine.adopt(2, invert=True)
    engine.motor_io(left_slot).write_duty(30)
    engine.motor_io(right_slot).write_duty(30)
    wire = sim.wiring.engine._wire
    busy_before, packets_before = wire.stats["line_busy_us"], wire.stats["packets"]
    sim.clock.advance_us(500_000)
    # Each millisecond: one 14-byte sync write of both duties and two 8-byte reads answered in 12 bytes.
    assert wire.stats["packets"] - packets_before == pytest.approx(3 * 500, abs=6)
    busy_per_ms = (wire.stats["line_busy_us"] - busy_before) / 500
    assert busy_per_ms == pytest.approx(140 + 2 * (80 + 120), abs=2)
    assert 540 <= engine.bus_stats()["last_tick_bus_us"] <= 1000  # the reply delays count too
    pose = sim.physics.pose()
    assert pose.x_mm > 20, "30 % duty on both wheels drives the robot forward"


def test_unplugging_an_adopted_servo_counts_failed_reads_and_trips_the_watchdog(sim):
    import _openbricks_native

    engine = _openbricks_native.serial_bus(1)
    left_slot, right_slot = engine.adopt(1), engine.adopt(2, invert=True)
    db = native.DriveBase(88, 138, left_io=engine.motor_io(left_slot), right_io=engine.motor_io(right_slot))
    _openbricks_native.motor_process.subscribe(db)
    db.drive(100, 0)
    sim.clock.advance_us(200_000)
    sim.wiring.bus.servo(2).unplug()
    sim.clock.advance_us(50_000)
    assert engine.angle_deg(right_slot) is None
    assert engine.stats(right_slot)[2] >= 40
    with pytest.raises(OSError, match="right"):
        db.done()


def test_a_released_servo_answers_the_driver_again(sim):
    import time

    import _openbricks_native

    engine = _openbricks_native.serial_bus(1)
    slot = engine.adopt(1)
    engine.release(slot)
    with pytest.raises(ValueError, match="not an adopted servo"):
        engine.motor_io(slot)
    left, _ = motors()
    left.run_speed(200)
    time.sleep_ms(800)
    assert left.speed() == pytest.approx(200, rel=0.05)


def test_only_the_servo_uart_has_an_engine(sim):
    import _openbricks_native

    with pytest.raises(OSError, match="UART1"):
        _openbricks_native.serial_bus(2)
