"""Reserved-GPIO guard: a pin mistake fails at construction, naming the pin, not somewhere far away.

Two kinds of mistakes are caught:

- pins the running chip can never give to user wiring: numbers that don't exist, the SPI-flash and
  PSRAM lines, the ESP32-S3 native-USB pair, and (for output roles) the classic ESP32's input-only
  range. Wiring these crashes the chip, drops the USB link or silently reads nothing.
- pins somebody already owns: the program button, the Bluetooth button, the status LED, or another
  driver. A second claimant gets an error naming the holder and how to move it.

The chip is read from the firmware's machine string (`sys.implementation._machine`, else
`os.uname().machine`). Off-chip (CPython, the simulator, unix/WebAssembly MicroPython) no chip is
recognised and only the ownership check applies, since the pins there are fakes, not wiring. Tests
pin a chip with `set_chip()`.

Strapping pins (0/3/45/46 on the S3, 0/2/5/12/15 on the ESP32) are deliberately allowed: after boot
they are ordinary GPIOs and the standard wiring uses some of them.
"""

import os
import sys

ESP32 = "esp32"
ESP32S3 = "esp32s3"

_CHIP_TITLES = {ESP32: "ESP32", ESP32S3: "ESP32-S3"}

# Per-chip tables as (first, last, reason) ranges, kept as tuples so nothing large is built at import.
_MISSING = {
    ESP32: ((20, 20), (24, 24), (28, 31), (40, 1 << 30)),
    ESP32S3: ((22, 25), (49, 1 << 30)),
}
_USABLE_TEXT = {
    ESP32: "0-19, 21-23, 25-27 and 32-39",
    ESP32S3: "0-21 and 26-48",
}
_RESERVED = {
    ESP32: ((6, 11, "wired to the SPI flash"),),
    ESP32S3: ((26, 32, "wired to the SPI flash/PSRAM"), (19, 20, "the native-USB D-/D+ pair")),
}
# Only on modules whose machine string reports it (octal-PSRAM S3, WROVER-style ESP32 with PSRAM).
_PSRAM_RESERVED = {
    ESP32: (16, 17, "wired to the PSRAM on modules with SPIRAM"),
    ESP32S3: (33, 37, "wired to the octal PSRAM"),
}
_INPUT_ONLY = {ESP32: (34, 39)}

_override = None  # (chip, psram) forced by set_chip(); None means autodetect
_detected = None  # cached (chip, psram) from the machine string
_claims = {}  # pin -> (role, owner, hint)


class ReservedPinError(ValueError):
    """A GPIO was requested that can't (or shouldn't) be wired by the caller.

    `.pin` the GPIO number, `.role` what the caller wanted it for, `.reason` why it is refused,
    `.owner` who holds it (a runtime/driver owner, or the chip for hardware-reserved pins),
    `.requester` who asked (if given).
    """

    def __init__(self, pin, role, reason, owner, requester=None, hint=""):
        self.pin = pin
        self.role = role
        self.reason = reason
        self.owner = owner
        self.requester = requester
        self.hint = hint
        who = "" if requester is None else " for %s" % _owner_name(requester)
        text = "GPIO %s can't be used as %s%s: %s (owner: %s)" % (pin, role, who, reason, owner)
        if hint:
            text += "; " + hint
        super().__init__(text)


def _owner_name(owner):
    if owner is None or isinstance(owner, str):
        return owner
    return type(owner).__name__


def _parse_machine(text):
    """Map a firmware machine string such as 'ESP32S3 module (spiram octal) with ESP32S3' to a chip."""
    text = text.lower()
    chip_part = text.rsplit(" with ", 1)[-1].replace("-", "").strip()
    if chip_part.startswith(ESP32S3):
        chip = ESP32S3
    elif chip_part == ESP32 or chip_part.startswith("esp32 "):
        chip = ESP32
    else:
        return None, False
    if chip == ESP32S3:
        psram = "oct" in text
    else:
        psram = "spiram" in text or "psram" in text or "wrover" in text
    return chip, psram


def _machine_string():
    text = getattr(sys.implementation, "_machine", None)
    if text:
        return text
    try:
        return os.uname().machine
    except (AttributeError, OSError):
        return ""


def _chip_and_psram():
    global _detected
    if _override is not None:
        return _override
    if _detected is None:
        _detected = _parse_machine(_machine_string())
    return _detected


def chip():
    """The chip the guard validates against ("esp32", "esp32s3"), or None off-chip."""
    return _chip_and_psram()[0]


def set_chip(chip, psram=False):
    """Force the chip model ("esp32", "esp32s3") and whether its PSRAM pins are taken;
    `None` returns to autodetection. For tests and the simulator."""
    global _override
    if chip is None:
        _override = None
        return
    if chip not in _CHIP_TITLES:
        raise ValueError("unknown chip %r: use 'esp32', 'esp32s3' or None" % (chip,))
    _override = (chip, bool(psram))


def _chip_reason(pin, output):
    """Why the chip itself forbids `pin`, or None if it may be wired."""
    model, psram = _chip_and_psram()
    if model is None:
        return None
    title = _CHIP_TITLES[model]
    if not isinstance(pin, int) or pin < 0:
        return "not a GPIO number"
    for first, last in _MISSING[model]:
        if first <= pin <= last:
            return "GPIO %d doesn't exist on the %s (its GPIOs are %s)" % (pin, title, _USABLE_TEXT[model])
    ranges = _RESERVED[model]
    if psram:
        ranges = ranges + (_PSRAM_RESERVED[model],)
    for first, last, why in ranges:
        if first <= pin <= last:
            return "GPIO %d-%d on the %s are %s" % (first, last, title, why)
    span = _INPUT_ONLY.get(model)
    if output and span and span[0] <= pin <= span[1]:
        return "GPIO %d-%d on the %s are input-only and can't drive an output" % (span[0], span[1], title)
    return None


def check(pin, role, output=True, owner=None):
    """Raise ReservedPinError unless `pin` may be wired for `role` by `owner`; claims nothing.

    `output` says whether the pin must drive (it only matters on the classic ESP32, whose
    GPIO 34-39 are input-only).
    """
    reason = _chip_reason(pin, output)
    if reason is not None:
        model = _CHIP_TITLES[chip()]
        raise ReservedPinError(
            pin, role, reason, "the %s chip" % model, owner, "wire %s to another GPIO" % role
        )
    held = _claims.get(pin)
    if held is not None and not _same_owner(held[1], owner):
        held_role, held_owner, hint = held
        raise ReservedPinError(
            pin,
            role,
            "in use as the %s" % held_role,
            _owner_name(held_owner),
            owner,
            hint or "wire %s to another GPIO" % role,
        )


def _same_owner(a, b):
    return a is b or (isinstance(a, str) and a == b)


# Who holds a pin claimed without an owner: the firmware runtime itself (a button it wires at boot).
RUNTIME_OWNER = "the firmware runtime"


def claim(pin, role, hint="", owner=None, output=True):
    """Take `pin` for `role` (manual 7.8.1: `claim(pin, role, hint="")`).

    `owner` is who holds it, a name or the driver object itself; None means the firmware runtime.
    Raises ReservedPinError for a chip-reserved pin or one held by a different owner. Claiming again
    for the same owner is allowed (a driver re-initialising). `hint` tells a later claimant how to
    move this owner elsewhere, e.g. "pass button_pin= to Launcher()". `output`: see check().
    """
    if owner is None:
        owner = RUNTIME_OWNER
    check(pin, role, output, owner)
    _claims[pin] = (role, owner, hint)


def release(pin, owner=None):
    """Hand `pin` back. Unknown pins are a no-op; releasing another owner's pin is a bug and raises."""
    held = _claims.get(pin)
    if held is None:
        return
    if owner is not None and not _same_owner(held[1], owner):
        raise ValueError(
            "GPIO %s is claimed by %s as the %s, not by %s; only its owner can release it"
            % (pin, _owner_name(held[1]), held[0], _owner_name(owner))
        )
    del _claims[pin]


def owner_of(pin):
    """(role, owner) of the claim on `pin`, or None when it is free."""
    held = _claims.get(pin)
    return None if held is None else (held[0], held[1])


def snapshot():
    """The current set of claimed pins, to hand to `release_since()` later."""
    return tuple(_claims)


def release_since(before):
    """Forget every claim made after `snapshot()` returned `before`.

    The launcher calls this when a program ends: the drivers a program built are garbage by then,
    and their claims would otherwise make the same program fail on its next run.
    """
    for pin in tuple(_claims):
        if pin not in before:
            del _claims[pin]


def reset_claims():
    """Forget every claim and return to chip autodetection (tests start from a clean slate)."""
    global _override, _detected
    _claims.clear()
    _override = None
    _detected = None
