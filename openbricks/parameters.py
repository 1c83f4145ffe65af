"""Pybricks-style constants, and the one place `then=` end states are decided.

The manual documents end states as strings ("coast", "stop", "brake", "hold",
"continue"); Pybricks programs pass `Stop.COAST` and friends. The constants are
those canonical strings themselves, so both spellings flow through the same
code path and the cost on the hub is a few interned strings.
"""


class Stop:
    """How a motion ends (Pybricks `Stop`). `NONE` keeps the motor at speed."""

    COAST = "coast"
    BRAKE = "brake"
    HOLD = "hold"
    NONE = "continue"


class Direction:
    """Which way counts as positive on a motor shaft (Pybricks `Direction`).

    Drivers take `invert=`; `invert = direction == Direction.COUNTERCLOCKWISE`.
    """

    CLOCKWISE = 1
    COUNTERCLOCKWISE = -1


# Every spelling accepted for `then=`, mapped to its canonical end state.
# "stop" is the manual's alias for coasting (Pybricks `Motor.stop()` coasts).
_THEN_NAMES = {
    "coast": Stop.COAST,
    "stop": Stop.COAST,
    "brake": Stop.BRAKE,
    "hold": Stop.HOLD,
    "continue": Stop.NONE,
}


def then_name(value):
    """Return the canonical end state ("coast", "brake", "hold" or "continue") for `value`.

    Accepts the `Stop` constants and the manual's strings (any letter case).
    Anything else raises ValueError listing what is accepted, at the call that
    passed it, rather than a motor silently doing nothing at the end of a move.
    """
    if isinstance(value, str):
        name = _THEN_NAMES.get(value.lower())
        if name is not None:
            return name
    raise ValueError(
        "then=%r is not an end state; use one of 'coast' (alias 'stop'), 'brake', 'hold', "
        "'continue', or Stop.COAST / Stop.BRAKE / Stop.HOLD / Stop.NONE" % (value,)
    )
