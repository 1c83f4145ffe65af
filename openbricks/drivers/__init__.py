"""One module per supported component; import the one your wiring uses (nothing is imported eagerly)."""

from openbricks import pins


def claim_pins(owner, claims):
    """Claim every (pin, role, output) in `claims` for `owner`, or none of them.

    A driver takes several GPIOs; if the third is refused, the first two must
    not stay claimed by a half-built object, or the corrected retry fails on
    them. A pin given for two roles of one driver is refused too: the guard
    would let the same owner through twice.
    """
    taken = []
    try:
        for pin, role, output in claims:
            for other_pin, other_role in taken:
                if other_pin == pin:
                    raise ValueError(
                        "%s and %s are both GPIO %s; each signal needs its own pin" % (other_role, role, pin)
                    )
            pins.claim(pin, role, owner=owner, output=output)
            taken.append((pin, role))
    except Exception:
        release_pins(owner, [pin for pin, _role in taken])
        raise


def release_pins(owner, pin_numbers):
    for pin in pin_numbers:
        pins.release(pin, owner)
