"""Hardware timers are claimed like GPIOs: one role a timer, and a second role is told who holds it."""

from fakes.expect import raises
from openbricks import timers
from openbricks.bluetooth_button import BluetoothToggleButton
from openbricks.hub import PushButton


def test_a_held_timer_refuses_another_role_naming_the_holder_and_how_to_move_it():
    timers.reset_claims()
    timers.claim(timers.LAUNCHER, "launcher", "pass timer_id= to launcher.start()")
    with raises(timers.TimerInUseError, "hardware timer 0 can't be used for the Bluetooth button") as err:
        timers.claim(timers.LAUNCHER, "Bluetooth button")
    assert "the launcher holds it; pass timer_id= to launcher.start()" in str(err.value)
    assert timers.holder(timers.LAUNCHER) == "launcher"


def test_the_same_role_may_claim_again_and_a_released_timer_is_free():
    timers.reset_claims()
    timers.claim(timers.IMU, "ICM-45686 sampling")
    timers.claim(timers.IMU, "ICM-45686 sampling")  # a driver re-initialising
    timers.release(timers.IMU, "launcher")  # not the holder: nothing happens
    assert timers.holder(timers.IMU) == "ICM-45686 sampling"
    timers.release(timers.IMU, "ICM-45686 sampling")
    assert timers.holder(timers.IMU) is None


def test_the_bluetooth_button_on_the_launchers_timer_is_refused_before_it_takes_it():
    timers.reset_claims()
    timers.claim(timers.LAUNCHER, "launcher", "pass timer_id= to launcher.start()")
    button = PushButton(0)
    toggle = BluetoothToggleButton(button, timer_id=timers.LAUNCHER, program_running=lambda: False)
    with raises(timers.TimerInUseError, "the launcher holds it"):
        toggle.start()
    own = BluetoothToggleButton(button, program_running=lambda: False).start()
    assert timers.holder(timers.BLUETOOTH_BUTTON) == "Bluetooth button"
    own.stop()
    assert timers.holder(timers.BLUETOOTH_BUTTON) is None
