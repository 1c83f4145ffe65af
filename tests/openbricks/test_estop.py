"""The e-stop latch halts every motor once and refuses motion until the program boundary."""

from openbricks import estop


def test_engage_halts_every_registered_motor_even_when_one_fails():
    halted = []

    def dead_servo():
        raise OSError("servo 3 is not responding on the bus")

    mark = estop.mark()
    estop.on_engage(lambda: halted.append("left"))
    estop.on_engage(dead_servo)
    estop.on_engage(lambda: halted.append("right"))
    try:
        failures = estop.engage("program button")
        assert halted == ["left", "right"]
        assert len(failures) == 1 and "servo 3" in str(failures[0][1])
        assert estop.engaged()
    finally:
        estop.clear(mark)


def test_motion_is_refused_until_cleared_and_the_refusal_cannot_be_swallowed_by_except_exception():
    estop.engage("program button")
    caught_by_user = False
    try:
        try:
            estop.check("run_angle()")
        except Exception:  # what a careless user program would write
            caught_by_user = True
    except KeyboardInterrupt as exc:
        assert "run_angle() refused: e-stop engaged (program button)" in str(exc)
    assert not caught_by_user
    estop.clear()
    estop.check("run_angle()")
    assert not estop.engaged()


def test_clear_with_a_mark_forgets_the_finished_programs_halts_only():
    calls = []
    estop.on_engage(lambda: calls.append("hub"))
    mark = estop.mark()
    estop.on_engage(lambda: calls.append("program motor"))
    estop.clear(mark)
    estop.engage()
    assert calls == ["hub"]
    estop.clear(mark - 1)
    assert not estop.engaged()
