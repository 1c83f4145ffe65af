"""The range-sensor contract."""

from fakes.expect import raises
from openbricks.distance import DistanceSensor


class _Sonar(DistanceSensor):
    pass


def test_a_driver_that_forgets_distance_mm_says_which_driver():
    with raises(NotImplementedError, "_Sonar does not support distance_mm()"):
        _Sonar().distance_mm()
