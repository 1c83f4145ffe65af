"""A fake of MicroPython's `os.dupterm` / `os.dupterm_notify`: the REPL's view of a duplicated terminal.

It behaves as extmod/os_dupterm.c does with a Python stream: input is pulled
one byte at a time through the stream's readinto(); `None` means "nothing
yet", 0 means end of file and detaches the stream; the interrupt character,
while code is executing, becomes a scheduled KeyboardInterrupt instead of
input. REPL output goes to every attached stream's write().
"""

import os

SLOTS = 1  # the ESP32 port has one dupterm slot
CHAR_CTRL_C = 3

_state = {"slots": [None] * SLOTS, "stdin": bytearray(), "interrupt_char": -1, "interrupts": 0}


def reset():
    _state["slots"] = [None] * SLOTS
    _state["stdin"] = bytearray()
    _state["interrupt_char"] = -1
    _state["interrupts"] = 0


def dupterm(stream=None, index=0):
    if not 0 <= index < SLOTS:
        raise ValueError("invalid dupterm index")
    previous = _state["slots"][index]
    _state["slots"][index] = stream
    return previous


def dupterm_notify(_obj=None):
    """Drain every attached stream into the REPL's stdin ring, as the port does on notify."""
    one = bytearray(1)
    for index in range(SLOTS):
        while True:
            stream = _state["slots"][index]
            if stream is None:
                break
            n = stream.readinto(one)
            if n is None:
                break
            if n == 0:
                _state["slots"][index] = None  # EOF: the port deactivates the stream
                break
            if one[0] == _state["interrupt_char"]:
                _state["interrupts"] += 1
            else:
                _state["stdin"].append(one[0])


class _OsWithDupterm:
    """`os` plus the two fakes, for an interpreter whose built-in `os` takes no new attributes."""

    dupterm = staticmethod(dupterm)
    dupterm_notify = staticmethod(dupterm_notify)

    def __getattr__(self, name):
        return getattr(os, name)


def install():
    # CPython and the WebAssembly port let a test add attributes to `os`; the unix port's `os` is
    # read-only, so there the runtime imports a stand-in (sys.modules comes before built-ins).
    # None of them has dupterm off-chip.
    try:
        os.dupterm = dupterm
        os.dupterm_notify = dupterm_notify
    except AttributeError:
        import sys

        sys.modules["os"] = _OsWithDupterm()


# --- the test's side -----------------------------------------------------------------


def attached(index=0):
    return _state["slots"][index]


def executing(flag=True):
    """While code runs the REPL arms Ctrl-C as the interrupt character; while it waits for input
    Ctrl-C is ordinary input."""
    _state["interrupt_char"] = CHAR_CTRL_C if flag else -1


def stdin():
    """Bytes the REPL has received so far."""
    return bytes(_state["stdin"])


def interrupts():
    return _state["interrupts"]


def repl_print(text):
    """The REPL writes `text` to the terminal (print() on the hub)."""
    data = text.encode() if isinstance(text, str) else bytes(text)
    for stream in _state["slots"]:
        if stream is not None:
            stream.write(data)
