"""Assertions that read the same under pytest and under MicroPython (which has no pytest)."""


class raises:
    """`with raises(OSError, "not responding"):` passes only if the block raises that
    exception type with that text in its message; the exception is kept as `.value`."""

    def __init__(self, exc_type, match=None):
        self.exc_type = exc_type
        self.match = match
        self.value = None

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        if exc_type is None:
            raise AssertionError("expected %s, nothing was raised" % self.exc_type.__name__)
        if not issubclass(exc_type, self.exc_type):
            return False
        self.value = exc
        if self.match is not None and self.match not in str(exc):
            raise AssertionError(
                "%s raised with %r, expected it to mention %r" % (exc_type.__name__, str(exc), self.match)
            )
        return True


def approx(actual, expected, tolerance):
    """assert approx(x, 1.0, 1e-3): True when |actual - expected| <= tolerance."""
    return abs(actual - expected) <= tolerance
