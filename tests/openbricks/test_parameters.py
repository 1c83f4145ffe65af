"""then= end states: the manual's strings and the Pybricks constants mean the same thing."""

from fakes.expect import raises
from openbricks.parameters import Direction, Stop, then_name


def test_manual_strings_and_constants_reach_the_same_end_state():
    assert then_name("coast") == then_name(Stop.COAST) == "coast"
    assert then_name("brake") == then_name(Stop.BRAKE) == "brake"
    assert then_name("hold") == then_name(Stop.HOLD) == "hold"
    assert then_name("continue") == then_name(Stop.NONE) == "continue"


def test_stop_is_the_manuals_alias_for_coast():
    assert then_name("stop") == "coast"


def test_letter_case_does_not_matter():
    assert then_name("HOLD") == "hold"
    assert then_name("Brake") == "brake"


def test_an_unknown_end_state_is_refused_with_the_valid_values():
    with raises(ValueError, "'coast' (alias 'stop'), 'brake', 'hold', 'continue'") as err:
        then_name("park")
    assert "park" in str(err.value)
    with raises(ValueError, "Stop.NONE"):
        then_name(None)
    with raises(ValueError, "is not an end state"):
        then_name(1)


def test_direction_signs():
    assert Direction.CLOCKWISE == 1
    assert Direction.COUNTERCLOCKWISE == -1
