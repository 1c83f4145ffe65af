"""JGB37-520 open-loop side: bridge commands, encoder angle and pins, with or without the native core."""

import machine

from fakes.dc_motor import QuadratureLines
from fakes.expect import approx, raises
from openbricks import pins
from openbricks.drivers.jgb37_520 import JGB37Motor


def _motor(**kwargs):
    pins.reset_claims()
    try:
        import _openbricks_native

        _openbricks_native.motor_process.reset()
    except ImportError:
        pass
    lines = QuadratureLines(7, 8)
    return JGB37Motor(in1=1, in2=2, pwm=17, encoder_a=7, encoder_b=8, **kwargs), lines


def _bridge():
    board = machine.board
    return board.pins[1].value(), board.pins[2].value(), round(board.pwms[17].duty_u16() * 100 / 65535)


def test_dc_brake_and_coast_drive_the_bridge():
    m, _ = _motor()
    m.dc(45)
    assert _bridge() == (1, 0, 45)
    m.dc(-120)
    assert _bridge() == (0, 1, 100)
    m.brake()
    assert _bridge() == (1, 1, 100)
    m.coast()
    assert _bridge() == (0, 0, 0)


def test_angle_is_the_encoder_count_at_1320_counts_per_turn():
    m, lines = _motor()
    lines.move(1320 + 330)
    assert approx(m.angle(), 450, 1e-6)
    m.reset_angle(90)
    lines.move(-660)
    assert approx(m.angle(), -90, 1e-6)


def test_invert_flips_bridge_and_encoder_encoder_invert_only_the_encoder():
    m, lines = _motor(invert=True)
    m.dc(30)
    assert _bridge() == (0, 1, 30)
    lines.move(-132)  # the mirrored motor turning "forward" counts down
    assert approx(m.angle(), 36, 1e-6)
    m.close()
    m, lines = _motor(encoder_invert=True)
    m.dc(30)
    assert _bridge() == (1, 0, 30)
    lines.move(-132)
    assert approx(m.angle(), 36, 1e-6)


def test_counts_per_output_rev_sets_the_scale():
    m, lines = _motor(counts_per_output_rev=44 * 4 * 30)  # an 11-pulse encoder read at 44 pulses
    lines.move(5280)
    assert approx(m.angle(), 360, 1e-6)


def test_a_reserved_encoder_pin_fails_construction_and_frees_the_bridge_pins():
    pins.reset_claims()
    pins.claim(39, "program button", owner="launcher")
    with raises(pins.ReservedPinError, "GPIO 39 can't be used as JGB37Motor encoder B"):
        JGB37Motor(in1=1, in2=2, pwm=17, encoder_a=7, encoder_b=39)
    assert pins.owner_of(1) is None and pins.owner_of(17) is None
    JGB37Motor(in1=1, in2=2, pwm=17, encoder_a=7, encoder_b=8)


def test_closed_loop_commands_need_the_native_core_and_say_so_when_it_is_missing():
    m, _ = _motor()
    try:
        import _openbricks_native  # noqa: F401
    except ImportError:
        with raises(NotImplementedError, "JGB37Motor.run_speed() needs the native servo core"):
            m.run(100)
        with raises(NotImplementedError, "dc(), brake(), coast() and angle() work without it"):
            m.run_angle(100, 90)
        assert m.done()
        return
    m.run_speed(100)
    assert _openbricks_native.motor_process.is_subscribed(m._servo)  # the 1 kHz tick will run it


def test_the_encoder_counts_on_a_free_pcnt_unit_where_the_runtime_has_one():
    m, lines = _motor()
    right = JGB37Motor(in1=9, in2=10, pwm=11, encoder_a=12, encoder_b=13, invert=True)
    left_unit, right_unit = machine.board.pcnt_units[0], machine.board.pcnt_units[1]
    assert (left_unit._phase_a, left_unit._phase_b, left_unit._phases) == (7, 8, 4)
    assert (right_unit._phase_a, right_unit._phase_b) == (12, 13)
    assert not machine.board.pins[7]._handler  # no per-edge interrupt on the hub's CPU
    lines.move(330)
    assert approx(m.angle(), 90, 1e-6)
    QuadratureLines(12, 13).move(-660)
    assert approx(right.angle(), 180, 1e-6)
    m.close()
    assert 0 not in machine.board.pcnt_units and pins.owner_of(7) is None  # the unit is free


def test_pcnt_unit_pins_the_encoder_to_that_unit():
    pins.reset_claims()
    JGB37Motor(in1=1, in2=2, pwm=17, encoder_a=7, encoder_b=8, pcnt_unit=3)
    assert machine.board.pcnt_units[3]._phase_a == 7 and 0 not in machine.board.pcnt_units


def test_without_machine_encoder_the_encoder_counts_in_a_pin_interrupt():
    saved = machine.Encoder
    machine.Encoder = None
    try:
        m, lines = _motor()
    finally:
        machine.Encoder = saved
    assert not machine.board.pcnt_units
    assert machine.board.pins[7]._handler is not None
    lines.move(1320 + 330)
    assert approx(m.angle(), 450, 1e-6)
