"""TB6612 channel: the L298N behaviour under the TB6612's own name and PWM rate."""

import machine

from fakes.expect import raises
from openbricks import pins
from openbricks.drivers.tb6612 import TB6612Motor


def test_drives_like_an_l298n_with_inaudible_pwm():
    pins.reset_claims()
    m = TB6612Motor(in1=9, in2=10, pwm=11)
    assert machine.board.pwms[11].freq() == 20000
    m.dc(-75)
    assert (machine.board.pins[9].value(), machine.board.pins[10].value()) == (0, 1)
    assert machine.board.pwms[11].duty_u16() == int(75 * 65535 / 100)
    m.brake()
    assert (machine.board.pins[9].value(), machine.board.pins[10].value()) == (1, 1)


def test_pin_errors_name_the_tb6612():
    pins.reset_claims()
    TB6612Motor(in1=9, in2=10, pwm=11)
    with raises(pins.ReservedPinError, "in use as the TB6612 IN2"):
        TB6612Motor(in1=1, in2=10, pwm=17)
