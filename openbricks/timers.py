"""Hardware timer registry: which of the ESP32's hardware timers serves whom, claimed in code.

MicroPython's ESP32 port has no virtual timers, only hardware timers 0..3, and two users of one timer
silently take it from each other (the second `Timer(n).init()` replaces the first's callback). So,
like GPIOs (`pins.claim`), each timer is claimed by one role before it is used, and a second role
asking for a held timer gets an error naming the holder and how to move one of them. Claiming again
for the same role is allowed (a launcher or driver re-initialising).

The runtime's assignment:
  0  LAUNCHER           the program button watcher
  1  BLUETOOTH_BUTTON   the Bluetooth button's poll; also the fallback motor_process tick
                        (robotics.tick), which only runs on hosts with no native tick and no button
  2  BLE_REPL           the BLE REPL pump
  3  IMU                ICM-45686 heading sampling
"""

from micropython import const

LAUNCHER = const(0)
BLUETOOTH_BUTTON = const(1)
BLE_REPL = const(2)
IMU = const(3)

_claims = {}  # timer id -> (role, hint)


class TimerInUseError(ValueError):
    """A hardware timer was asked for that another role holds. `.timer_id`, `.role`, `.holder`."""

    def __init__(self, timer_id, role, holder, hint):
        self.timer_id = timer_id
        self.role = role
        self.holder = holder
        text = "hardware timer %s can't be used for the %s: the %s holds it" % (timer_id, role, holder)
        if hint:
            text += "; " + hint
        super().__init__(text)


def claim(timer_id, role, hint=""):
    """Take `timer_id` for `role`, or raise TimerInUseError when another role holds it. `hint` tells a
    later claimant how to move this role to another timer, e.g. "pass timer_id= to Launcher()"."""
    held = _claims.get(timer_id)
    if held is not None and held[0] != role:
        raise TimerInUseError(timer_id, role, held[0], held[1])
    _claims[timer_id] = (role, hint)


def release(timer_id, role):
    """Hand `timer_id` back if `role` holds it; anything else is a no-op."""
    held = _claims.get(timer_id)
    if held is not None and held[0] == role:
        del _claims[timer_id]


def holder(timer_id):
    """The role holding `timer_id`, or None when it is free."""
    held = _claims.get(timer_id)
    return None if held is None else held[0]


def reset_claims():
    """Forget every claim (tests start from a clean slate)."""
    _claims.clear()
