"""A fake `micropython` module for CPython: the few helpers the runtime calls."""

_scheduled = []


def reset():
    del _scheduled[:]


def const(value):
    return value


def schedule(fn, arg):
    # The ESP32 port runs scheduled callbacks between bytecodes soon after; run them now.
    fn(arg)


def alloc_emergency_exception_buf(size):
    pass


def mem_info(verbose=None):
    pass


def opt_level(level=None):
    return 0 if level is None else None


def native(fn):
    return fn


def viper(fn):
    return fn
