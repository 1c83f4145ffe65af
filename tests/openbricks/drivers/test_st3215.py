"""ST-3215 driver against fake servos that answer SCS packets from their register files."""

import time

import machine

from fakes.expect import approx, raises
from fakes.scs_servo import FakeServo, ScsBus, from_sign_magnitude, scs
from openbricks import pins
from openbricks.drivers import st3215
from openbricks.drivers.st3215 import ST3215, ST3215Motor, SyncServoGroup
from openbricks.parameters import Stop

NEEDS_NATIVE = True  # the servos are the simulator's, on the native SCS codec


def _bus(*ids):
    st3215.forget_buses()
    pins.reset_claims()
    bus = ScsBus()
    for servo_id in ids:
        bus.add(FakeServo(servo_id))
    machine.board.attach_uart(1, bus)
    return bus


def _step_writes(servo):
    return [from_sign_magnitude(d[0] | d[1] << 8, 15) for a, d in servo.writes if a == scs.REG_GOAL_POSITION]


# --- wheel mode and odometry ------------------------------------------------------------


def test_construction_puts_the_servo_in_wheel_mode_with_torque_off_on_the_standard_pins():
    bus = _bus(1)
    ST3215Motor(1)
    servo = bus.servo(1)
    assert servo.mode == 1
    assert not servo.torque_enabled
    uart = machine.board.uarts[1]
    assert (uart._tx_pin, uart._rx_pin, uart._baud) == (14, 41, 1_000_000)


def test_run_speed_spins_the_shaft_and_angle_and_speed_follow_it():
    bus = _bus(1)
    m = ST3215Motor(1)
    m.run_speed(300)
    time.sleep_ms(1000)
    # 1500 deg/s^2 ramp to 300 deg/s takes 0.2 s: 30 deg during the ramp, 240 after it.
    assert approx(bus.servo(1).angle_deg(), 270, 3)
    assert approx(m.angle(), bus.servo(1).angle_deg(), 0.2)
    assert approx(m.speed(), 300, 1)


def test_angle_keeps_every_turn_when_the_program_reads_it_rarely():
    bus = _bus(1)
    m = ST3215Motor(1, max_dps=888)
    m.run_speed(888)
    time.sleep_ms(10_000)  # ~24 turns, ~3 wraps of the position window, and no reads in between
    assert approx(m.angle(), bus.servo(1).angle_deg(), 0.3)
    m.run_speed(-500)
    time.sleep_ms(7_000)
    assert approx(m.angle(), bus.servo(1).angle_deg(), 0.3)


def test_angle_survives_a_long_coast():
    bus = _bus(1)
    m = ST3215Motor(1, max_dps=888)
    m.run_speed(888)
    time.sleep_ms(3000)
    m.coast()
    time.sleep_ms(5000)
    assert approx(m.angle(), bus.servo(1).angle_deg(), 0.3)
    bus.servo(1).turn_shaft(-1000)  # turned by hand while free
    assert approx(m.angle(), bus.servo(1).angle_deg(), 0.3)


def test_run_speed_is_clamped_to_max_dps():
    bus = _bus(1)
    m = ST3215Motor(1, max_dps=400)
    m.run_speed(5000)
    time.sleep_ms(1000)
    assert approx(bus.servo(1).speed_dps(), 400, 1)


def test_invert_flips_the_command_and_the_readings_together():
    bus = _bus(2)
    m = ST3215Motor(2, invert=True)
    m.run_speed(200)
    time.sleep_ms(1000)
    assert bus.servo(2).speed_dps() < -199
    assert approx(m.speed(), 200, 1)
    assert approx(m.angle(), -bus.servo(2).angle_deg(), 0.2)


def test_reset_angle_sets_the_frame_and_run_target_uses_it():
    bus = _bus(1)
    m = ST3215Motor(1)
    bus.servo(1).turn_shaft(37)
    m.reset_angle(100)
    assert approx(m.angle(), 100, 0.1)
    m.run_target(300, 10)
    assert approx(m.angle(), 10, 0.5)
    assert approx(bus.servo(1).angle_deg(), 37 - 90, 0.5)


def test_brake_ramps_down_and_keeps_torque_coast_releases_it():
    bus = _bus(1)
    m = ST3215Motor(1)
    m.run_speed(600)
    time.sleep_ms(1000)
    m.brake()
    time.sleep_ms(100)
    assert 300 < bus.servo(1).speed_dps() < 500  # still ramping down at 1500 deg/s^2
    time.sleep_ms(400)
    assert bus.servo(1).speed_dps() == 0
    assert bus.servo(1).torque_enabled
    m.coast()
    assert not bus.servo(1).torque_enabled


def test_dc_drives_open_loop_and_speed_sags_to_zero_when_blocked():
    bus = _bus(1)
    m = ST3215Motor(1, max_dps=888)
    m.dc(50)
    time.sleep_ms(500)
    assert bus.servo(1).mode == 2
    assert approx(m.speed(), 444, 10)
    bus.servo(1).block()
    time.sleep_ms(50)
    assert m.speed() == 0
    m.dc(-250)  # clamped to -100
    bus.servo(1).unblock()
    time.sleep_ms(500)
    assert approx(m.speed(), -888, 15)


# --- run_angle in step mode -------------------------------------------------------------


def test_run_angle_beyond_seven_turns_is_chained_steps_and_lands_on_target():
    bus = _bus(1)
    m = ST3215Motor(1)
    m.run_angle(600, 3600)  # ten turns
    servo = bus.servo(1)
    assert approx(servo.angle_deg(), 3600, 0.5)
    assert approx(m.angle(), 3600, 0.5)
    assert _step_writes(servo) == [7 * 4096, 3 * 4096]
    assert not servo.torque_enabled  # default then="coast"
    m.run_angle(600, -3600)
    assert approx(m.angle(), 0, 1.0)
    assert approx(servo.angle_deg(), 0, 1.0)


def test_run_angle_crosses_the_single_turn_seam_the_right_way_round():
    bus = _bus(1)
    m = ST3215Motor(1)
    bus.servo(1).turn_shaft(350)
    m.reset_angle(350)
    m.run_angle(200, 30)
    assert approx(bus.servo(1).angle_deg(), 380, 0.5)
    assert approx(m.angle(), 380, 0.5)


def test_run_angle_takes_the_manuals_then_strings_and_the_constants():
    bus = _bus(1)
    m = ST3215Motor(1)
    servo = bus.servo(1)
    m.run_angle(300, 90, then="hold")
    assert servo.torque_enabled and servo.mode == 3
    servo.turn_shaft(20)  # push it off target: the position loop brings it back
    time.sleep_ms(500)
    assert approx(servo.angle_deg(), 90, 0.5)
    m.run_angle(300, 90, then=Stop.BRAKE)
    assert servo.torque_enabled and servo.mode == 1
    m.run_angle(300, 90, then="stop")
    assert not servo.torque_enabled
    with raises(ValueError, "'coast' (alias 'stop'), 'brake', 'hold', 'continue'"):
        m.run_angle(300, 90, then="park")


def test_run_angle_then_continue_keeps_spinning_at_the_move_speed():
    bus = _bus(1)
    m = ST3215Motor(1)
    m.run_angle(240, -180, then="continue")
    time.sleep_ms(500)
    assert approx(bus.servo(1).speed_dps(), -240, 1)
    assert m.angle() < -280


def test_two_motors_move_together_with_wait_false_and_done():
    bus = _bus(1, 2)
    left = ST3215Motor(1)
    right = ST3215Motor(2, invert=True)
    left.run_angle(360, 720, wait=False)
    right.run_angle(360, 720, wait=False)
    assert not left.done() and not right.done()
    polls = 0
    while not (left.done() and right.done()):
        time.sleep_ms(10)
        polls += 1
    assert 150 < polls < 400  # about two seconds of moving, not instant and not stuck
    assert approx(bus.servo(1).angle_deg(), 720, 0.5)
    assert approx(bus.servo(2).angle_deg(), -720, 0.5)


def test_a_long_move_without_wait_only_advances_while_done_is_polled():
    bus = _bus(1)
    m = ST3215Motor(1)
    m.run_angle(600, 5760, wait=False)  # 16 turns: three steps
    time.sleep_ms(20_000)
    assert approx(bus.servo(1).angle_deg(), 7 * 360, 0.5)  # parked after the first step
    while not m.done():
        time.sleep_ms(10)
    assert approx(bus.servo(1).angle_deg(), 5760, 0.5)
    assert approx(m.angle(), 5760, 0.5)


def test_a_new_command_supersedes_a_pending_move():
    bus = _bus(1)
    m = ST3215Motor(1)
    m.run_angle(300, 3600, wait=False)
    time.sleep_ms(200)
    m.run_speed(100)
    assert m.done()
    time.sleep_ms(1000)
    assert approx(bus.servo(1).speed_dps(), 100, 1)


def test_a_blocked_move_gives_up_after_stall_idle_ms_or_raises_when_asked():
    bus = _bus(1)
    m = ST3215Motor(1, stall_idle_ms=500)
    bus.servo(1).put_wall(100)
    start = time.ticks_ms()
    m.run_angle(300, 360, then="brake")
    assert time.ticks_diff(time.ticks_ms(), start) < 2000
    assert approx(m.angle(), 100, 0.5)
    strict = ST3215Motor(1, stall_idle_ms=500, raise_on_stall=True)
    with raises(RuntimeError, "ST3215Motor (servo id 1) stalled in run_angle: no progress for 500 ms"):
        strict.run_angle(300, 360)
    assert not bus.servo(1).torque_enabled


# --- hold, load, stall --------------------------------------------------------------------


def test_hold_keeps_the_shaft_where_it_stopped():
    bus = _bus(1)
    m = ST3215Motor(1)
    m.run_speed(300)
    time.sleep_ms(700)
    m.hold()
    time.sleep_ms(300)
    here = bus.servo(1).angle_deg()
    bus.servo(1).turn_shaft(-45)
    time.sleep_ms(500)
    assert approx(bus.servo(1).angle_deg(), here, 0.5)
    assert approx(m.angle(), here, 0.5)
    m.run_speed(100)  # back to wheel mode transparently
    time.sleep_ms(500)
    assert approx(bus.servo(1).speed_dps(), 100, 1)


def test_load_and_stalled_report_a_blocked_shaft_and_not_a_free_one():
    bus = _bus(1)
    m = ST3215Motor(1)
    m.run_speed(300)
    time.sleep_ms(500)
    assert not m.stalled()
    assert 0 < m.load() < 0.3 * ST3215Motor.STALL_TORQUE_MNM
    bus.servo(1).block()
    time.sleep_ms(50)
    assert m.stalled()
    assert approx(m.load(), ST3215Motor.STALL_TORQUE_MNM, 1)


def test_run_until_stalled_homes_gently_against_an_end_stop():
    bus = _bus(1)
    m = ST3215Motor(1)
    servo = bus.servo(1)
    servo.put_wall(-60)
    limits_seen = []
    original_write = servo.write

    def spy(address, data):
        if address == scs.REG_TORQUE_LIMIT:
            limits_seen.append(data[0] | data[1] << 8)
        original_write(address, data)

    servo.write = spy
    stop_angle = m.run_until_stalled(-200, then="hold", duty_limit=30)
    assert approx(stop_angle, -60, 0.5)
    assert limits_seen == [300, 1000]  # capped at 30 % for the push, restored afterwards
    assert servo.torque_enabled and servo.mode == 3
    time.sleep_ms(10)
    assert abs(m.load()) < 0.05 * ST3215Motor.STALL_TORQUE_MNM  # holding, no longer shoving the stop


def test_overload_protection_shows_in_faults_and_the_next_command_rearms_torque():
    bus = _bus(1)
    m = ST3215Motor(1)
    servo = bus.servo(1)
    servo.block()
    m.run_speed(200)
    time.sleep_ms(2500)
    assert not servo.torque_enabled  # the servo unloaded itself
    m.speed()
    assert m.faults() == ("overload",)
    servo.unblock()
    m.run_speed(150)
    time.sleep_ms(500)
    assert servo.torque_enabled
    assert approx(servo.speed_dps(), 150, 1)


# --- a silent servo, wiring mistakes ---------------------------------------------------


def test_a_servo_that_never_answers_fails_construction_with_the_full_diagnosis():
    _bus(1)
    with raises(
        OSError, "motor is not responding on the bus: ST3215Motor (servo id 3) on UART1 tx=14 rx=41"
    ) as e:
        ST3215Motor(3)
    assert "0 replies, 2 failed reads (2 in a row)" in str(e.value)
    assert "`openbricks servo-id --scan` lists the ids actually answering on the bus" in str(e.value)


def test_a_servo_that_goes_silent_mid_run_names_side_slot_and_counts():
    bus = _bus(1)
    m = ST3215Motor(1, tx=14, rx=6)
    m.set_label("right wheel", 1)
    m.run_speed(100)
    bus.servo(1).silent = True
    assert m.angle() is None
    assert m.speed() is None
    assert m.load() is None
    with raises(OSError, "not responding on the bus: right wheel (servo id 1, slot 1) on UART1 tx=14 rx=6"):
        m.stalled()
    with raises(OSError, "failed reads") as e:
        m.run_speed(50)
    replies, failed, in_a_row = m.bus.stats(1)
    assert "%d replies, %d failed reads (%d in a row)" % (replies, failed, in_a_row) in str(e.value)
    assert in_a_row >= 8 and replies >= 5
    bus.servo(1).silent = False
    m.run_speed(50)
    assert m.bus.stats(1)[2] == 0


def test_a_servo_whose_id_was_changed_stops_answering_to_the_old_one():
    bus = _bus(1)
    m = ST3215Motor(1)
    assert m.ping()
    bus.change_id(1, 7)
    assert not m.ping()
    assert ST3215Motor(7).ping()


def test_bus_pins_go_through_the_reserved_pin_guard():
    _bus(1)
    pins.set_chip("esp32s3")
    with raises(pins.ReservedPinError, "GPIO 19"):
        ST3215Motor(1, tx=19, rx=41)
    st3215.forget_buses()
    pins.claim(39, "program button", owner="launcher")
    with raises(pins.ReservedPinError, "in use as the program button"):
        ST3215Motor(1, tx=14, rx=39)


def test_servos_on_one_uart_share_the_bus_and_must_agree_on_its_wiring():
    _bus(1, 2)
    a = ST3215Motor(1)
    b = ST3215(2)
    assert a.bus is b.bus
    assert b.bus.devices == [a, b]
    with raises(ValueError, "UART1 is already the servo bus on tx=14 rx=41"):
        ST3215Motor(3, tx=17, rx=16)


def test_replies_are_checked_and_adapters_that_echo_their_own_tx_work():
    class EchoingAdapter:
        def __init__(self, inner):
            self.inner = inner
            self.corrupt_next = 0

        def handle(self, data):
            reply = self.inner.handle(data)
            if self.corrupt_next and reply:
                self.corrupt_next -= 1
                reply = reply[:-1] + bytes(((reply[-1] + 1) & 0xFF,))
            return bytes(data) + reply

    inner = _bus(1)
    adapter = EchoingAdapter(inner)
    machine.board.attach_uart(1, adapter)
    m = ST3215Motor(1)
    m.run_speed(200)
    time.sleep_ms(500)
    assert approx(m.angle(), inner.servo(1).angle_deg(), 0.2)
    adapter.corrupt_next = 1  # one bad checksum: counted as a failed read, retried
    failed_before = m.bus.stats(1)[1]
    assert m.speed() is not None
    assert m.bus.stats(1)[1] == failed_before + 1


# --- sync writes, adoption ------------------------------------------------------------


def test_sync_group_sets_every_speed_in_one_packet():
    bus = _bus(1, 2)
    thumb = ST3215Motor(1)
    index = ST3215Motor(2, invert=True)
    group = SyncServoGroup([thumb, index])
    group.set_goal_speeds([200, 150])
    syncs = [p for p in bus.log if p[1] == scs.SYNC_WRITE]
    assert len(syncs) == 1
    assert syncs[0][2][:2] == bytes((scs.REG_GOAL_SPEED, 2))
    time.sleep_ms(1000)
    assert approx(bus.servo(1).speed_dps(), 200, 1)
    assert approx(bus.servo(2).speed_dps(), -150, 1)
    assert approx(index.speed(), 150, 1)


def test_sync_group_refuses_position_servos_and_servos_on_other_buses():
    bus = _bus(1, 2)
    wheel = ST3215Motor(1)
    arm = ST3215(2)
    with raises(TypeError, "servo id 2 is a ST3215 (position mode)"):
        SyncServoGroup([wheel, arm]).set_goal_speeds([10, 10])
    other = ScsBus()
    other.add(FakeServo(5))
    machine.board.attach_uart(2, other)
    far = ST3215Motor(5, uart_id=2, tx=4, rx=5)
    with raises(ValueError, "a SYNC WRITE reaches one bus only"):
        SyncServoGroup([wheel, far])
    assert bus.servo(1).speed_dps() == 0


def test_handing_the_uart_over_routes_the_motor_through_its_new_owner():
    class Port:
        def __init__(self):
            self.calls = []

        def run_speed(self, slot, dps):
            self.calls.append(("run_speed", slot, dps))

        def angle(self, slot):
            return 12.5

    _bus(1)
    m = ST3215Motor(1, invert=True)
    wiring = m.bus.hand_over()
    assert wiring == (1, 14, 41, 1_000_000, None)
    with raises(OSError, "UART1 is deinitialised"):
        machine.board.uarts[1].any()  # free for the native bus engine to open
    with raises(OSError, "UART1 belongs to the DriveBase's native bus engine"):
        m.ping()
    port = Port()
    m.adopt(port, 0)
    m.run(200)
    assert port.calls == [("run_speed", 0, 200)]
    assert m.angle() == 12.5
    assert (m.servo_id, m.invert, m.steps_per_dps) == (1, True, 4096 / 360)


# --- position servo -------------------------------------------------------------------------


def test_position_servo_moves_to_an_angle_inside_its_range():
    bus = _bus(4)
    arm = ST3215(4, min_raw=1024, max_raw=3072, range_deg=180)
    servo = bus.servo(4)
    assert (servo.reg16(scs.REG_MIN_ANGLE), servo.reg16(scs.REG_MAX_ANGLE)) == (1024, 3072)
    servo.turn_shaft(90)  # horn starts at raw 1024 = 0 degrees of the range
    assert arm.move_to(90) is True
    time.sleep_ms(500)
    assert approx(arm.angle(), 90, 0.2)
    assert approx(servo.angle_deg(), 180, 0.2)
    with raises(ValueError, "outside this servo's range 0..180 degrees"):
        arm.move_to(200)


def test_position_servo_reports_a_move_that_cannot_finish():
    bus = _bus(4)
    arm = ST3215(4)
    bus.servo(4).put_wall(30)
    assert arm.move_to(120) is False
    bus.servo(4).silent = True
    assert arm.angle() is None
