"""openbricks._native re-exports the native cores lazily, and says clearly when they are missing."""

import sys

from fakes.expect import raises


def _without_native():
    """Hide the cores (the host build, or the unix MicroPython's built-in module): a None entry in
    sys.modules makes CPython's import of it fail and MicroPython's return None, as on a build
    without them."""
    saved = sys.modules.get("_openbricks_native")
    sys.modules["_openbricks_native"] = None
    return saved


def _restore(saved):
    if saved is not None:
        sys.modules["_openbricks_native"] = saved
    else:
        del sys.modules["_openbricks_native"]


def _fresh_gateway():
    """openbricks._native imported anew: the one loaded earlier keeps the cores it has resolved."""
    import openbricks

    loaded = sys.modules.pop("openbricks._native", None)
    __import__("openbricks._native")
    fresh = sys.modules["openbricks._native"]
    if loaded is not None:
        sys.modules["openbricks._native"] = loaded
        openbricks._native = loaded
    return fresh


def test_importing_the_module_never_needs_the_cores():
    saved = _without_native()
    try:
        _native = _fresh_gateway()
        assert not _native.available()
        with raises(ImportError, "not in this MicroPython build"):
            _native.Servo  # noqa: B018 - the attribute access is the import
        with raises(ImportError, "not in this MicroPython build"):
            _native.motor_process  # noqa: B018
    finally:
        _restore(saved)


def test_unknown_names_are_attribute_errors_naming_the_cores():
    from openbricks import _native

    with raises(AttributeError, "the cores are motor_process, Servo"):
        _native.Motor  # noqa: B018
