"""L298N channel: what the bridge pins and the enable PWM do for each command."""

import machine

from fakes.expect import raises
from openbricks import pins
from openbricks.drivers.l298n import L298NMotor


def _bridge():
    """(IN1, IN2, EN duty %) as the board sees them."""
    board = machine.board
    return board.pins[1].value(), board.pins[2].value(), round(board.pwms[17].duty_u16() * 100 / 65535)


def _motor(**kwargs):
    pins.reset_claims()
    return L298NMotor(in1=1, in2=2, pwm=17, **kwargs)


def test_dc_sets_direction_pins_and_enable_duty():
    m = _motor()
    assert machine.board.pwms[17].freq() == 1000
    assert _bridge() == (0, 0, 0)
    m.dc(60)
    assert _bridge() == (1, 0, 60)
    m.dc(-30)
    assert _bridge() == (0, 1, 30)
    m.dc(250)
    assert _bridge() == (1, 0, 100)


def test_invert_swaps_the_direction():
    m = _motor(invert=True)
    m.dc(40)
    assert _bridge() == (0, 1, 40)


def test_brake_shorts_the_winding_coast_and_zero_duty_release_it():
    m = _motor()
    m.dc(80)
    m.brake()
    assert _bridge() == (1, 1, 100)
    m.dc(80)
    m.coast()
    assert _bridge() == (0, 0, 0)
    m.dc(50)
    m.stop()  # Pybricks stop() coasts
    assert _bridge() == (0, 0, 0)
    m.dc(50)
    m.dc(0)
    assert _bridge() == (0, 0, 0)


def test_closed_loop_commands_say_this_motor_has_no_feedback():
    m = _motor()
    with raises(NotImplementedError, "L298NMotor does not support run_speed(); it has no speed feedback"):
        m.run(200)  # Pybricks run() is closed-loop speed
    with raises(NotImplementedError, "L298NMotor does not support hold(); it has no position control"):
        m.hold()
    with raises(NotImplementedError, "L298NMotor does not support angle(); it has no encoder"):
        m.angle()
    with raises(NotImplementedError, "L298NMotor does not support run_angle()"):
        m.run_angle(100, 90)
    assert m.done()
    assert _bridge() == (0, 0, 0)


def test_a_runtime_pin_is_refused_and_a_failed_construction_keeps_no_pins():
    pins.reset_claims()
    pins.claim(39, "program button", owner="launcher", hint="pass button_pin= to Launcher()")
    with raises(pins.ReservedPinError, "GPIO 39 can't be used as L298N PWM/EN"):
        L298NMotor(in1=1, in2=2, pwm=39)
    assert pins.owner_of(1) is None and pins.owner_of(2) is None
    L298NMotor(in1=1, in2=2, pwm=17)  # the corrected wiring goes through


def test_chip_reserved_pins_and_doubled_pins_are_refused():
    pins.reset_claims()
    pins.set_chip("esp32s3")
    with raises(pins.ReservedPinError, "native-USB"):
        L298NMotor(in1=19, in2=2, pwm=17)
    with raises(ValueError, "L298N IN1 and L298N IN2 are both GPIO 5"):
        L298NMotor(in1=5, in2=5, pwm=17)


def test_two_motors_cannot_share_a_pin_until_one_is_closed():
    first = _motor()
    with raises(pins.ReservedPinError, "in use as the L298N PWM/EN"):
        L298NMotor(in1=9, in2=10, pwm=17)
    first.close()
    assert machine.board.pwms[17].duty_u16() == 0  # the enable pin no longer drives the bridge
    L298NMotor(in1=9, in2=10, pwm=17)
