"""E-stop latch: once the stop button fires, motors halt and every further motion command refuses.

Interrupting the program is not enough on its own: a `KeyboardInterrupt` lands only between
bytecodes, a user `try/except` can swallow it, and a motor left running at speed keeps driving off the
table while the launcher retries. So the launcher engages this latch first. Drivers register a halt
callback (cut torque, coast) that runs immediately, and call `check()` at the top of each motion
command so a program that survives the interrupt still can't move anything. The latch clears only at
the program boundary, when the launcher calls `clear()`.
"""

_state = {"engaged": False, "reason": ""}
_halts = []  # callables run once per engage(); drivers add theirs at construction


class EStopError(KeyboardInterrupt):
    """A motion command was refused because the e-stop is engaged.

    It is a KeyboardInterrupt so that it unwinds the program exactly like the stop it stands for,
    and a user's `except Exception:` can't swallow it.
    """


def engaged():
    """True while the latch is set (between a stop press and the end of the program)."""
    return _state["engaged"]


def reason():
    return _state["reason"]


def on_engage(halt):
    """Run `halt()` whenever the e-stop engages (a driver's torque-off or coast)."""
    if halt not in _halts:
        _halts.append(halt)


def remove(halt):
    if halt in _halts:
        _halts.remove(halt)


def engage(why="stop button"):
    """Set the latch and halt every registered motor; returns the failures as (halt, exception) pairs.

    A halt that raises (a servo that dropped off the bus) must not keep the others running, so every
    callback runs and the failures are reported to the caller, which logs them.
    """
    _state["engaged"] = True
    _state["reason"] = why
    return _run(_halts)


def halt_since(keep):
    """Halt the motors registered after `mark()` returned `keep`, without setting the latch.

    The launcher calls this when a program ends, however it ends: a motor the program left running
    (or was driving when it raised) must not keep the robot moving once nothing controls it.
    Returns the failures as (halt, exception) pairs, like `engage()`.
    """
    return _run(_halts[keep:])


def _run(halts):
    failures = []
    for halt in tuple(halts):
        try:
            halt()
        except Exception as exc:  # noqa: BLE001 - one failed motor must not spare the rest
            failures.append((halt, exc))
    return failures


def check(action="motion command"):
    """Raise EStopError if the latch is set; drivers call this before moving anything."""
    if _state["engaged"]:
        raise EStopError(
            "%s refused: e-stop engaged (%s); motion is allowed again when the next program starts"
            % (action, _state["reason"])
        )


def mark():
    """How many halts are registered now; pass it to `clear()` at the program boundary."""
    return len(_halts)


def clear(keep=None):
    """Release the latch. With `keep`, also forget halts registered after `mark()` returned it:
    the drivers a finished program built are gone, and halting them on the next stop would touch
    hardware the next program may have wired differently."""
    _state["engaged"] = False
    _state["reason"] = ""
    if keep is not None:
        del _halts[keep:]
