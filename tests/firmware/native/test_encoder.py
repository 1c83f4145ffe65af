"""The PCNT encoder core (firmware/native/encoder.c) fed the way the hub's hard tick feeds it: what a
PCNT unit's 16-bit counter reads, which returns to 0 at +-32767, sampled every millisecond while an
MG370 or a JGB37-520 turns. Positions, wraps, direction and degrees are what a user's angle() sees.
"""

import pytest
from hypothesis import given
from hypothesis import strategies as st

from openbricks_native import PCNTEncoder

PCNT_LIMIT = 32767
MG370_CPR = int(500 * 4 * 34.014)  # 68028 counts per output turn
JGB37_CPR = 1320


class PcntCounter:
    """An ESP32 PCNT unit configured at +-limit: counts every edge and returns to 0 on reaching a limit."""

    def __init__(self, limit=PCNT_LIMIT):
        self.limit = limit
        self.value = 0

    def move(self, counts):
        value = self.value + counts
        while value >= self.limit:
            value -= self.limit
        while value <= -self.limit:
            value += self.limit
        self.value = value
        return value


def int16(count):
    """A plain 16-bit two's-complement counter's reading of `count`."""
    return (count + 32768) % 65536 - 32768


def test_an_mg370_at_full_speed_for_a_minute_reads_its_turns_exactly():
    # 1000 deg/s output = ~189 counts per millisecond; the counter wraps every ~173 ms.
    enc, pcnt = PCNTEncoder(MG370_CPR), PcntCounter()
    enc.sample(pcnt.value)
    per_ms = MG370_CPR * 1000 / 360 / 1000
    true = 0.0
    for _ in range(60_000):
        before = int(true)
        true += per_ms
        enc.sample(pcnt.move(int(true) - before))
    assert enc.count() == int(true)
    assert enc.angle() == pytest.approx(int(true) * 360 / MG370_CPR, abs=0.01)
    assert enc.angle() == pytest.approx(60_000, rel=1e-4)
    assert enc.direction() == 1


def test_backwards_through_the_low_limit_counts_down():
    enc, pcnt = PCNTEncoder(JGB37_CPR), PcntCounter()
    enc.sample(pcnt.value)
    for _ in range(300):
        enc.sample(pcnt.move(-500))
    assert enc.count() == -150_000
    assert enc.direction() == -1
    assert enc.angle() == pytest.approx(-150_000 * 360 / JGB37_CPR)


def test_invert_flips_count_direction_and_reset_frame():
    enc, pcnt = PCNTEncoder(JGB37_CPR, invert=True), PcntCounter()
    enc.sample(pcnt.value)
    enc.sample(pcnt.move(660))
    assert enc.count() == -660 and enc.angle() == pytest.approx(-180.0) and enc.direction() == -1
    enc.reset(1000)
    enc.sample(pcnt.move(-20))
    assert enc.count() == 1020


def test_reset_makes_the_current_position_read_the_value_given():
    enc, pcnt = PCNTEncoder(JGB37_CPR), PcntCounter()
    enc.sample(pcnt.value)
    enc.sample(pcnt.move(30_000))
    enc.reset()
    assert enc.count() == 0
    enc.sample(pcnt.move(5_000))  # across the +32767 wrap
    assert enc.count() == 5_000
    enc.reset(-1320)
    assert enc.angle() == pytest.approx(-360.0)


def test_the_first_sample_only_sets_where_counting_starts():
    enc = PCNTEncoder(JGB37_CPR)
    enc.sample(12_345)
    assert enc.count() == 0 and enc.direction() == 0
    enc.sample(12_346)
    assert enc.count() == 1


def test_a_shaft_at_rest_reports_no_direction():
    enc = PCNTEncoder(JGB37_CPR)
    enc.sample(7)
    enc.sample(8)
    enc.sample(8)
    assert enc.direction() == 0


def test_angles_stay_exact_far_beyond_float_precision_of_the_count():
    # 2**26 counts: a float of the count alone would round to 4; whole turns keep the remainder.
    enc = PCNTEncoder(MG370_CPR, modulus=65536)
    enc.sample(0)
    total = 0
    for _ in range(2048):
        total += 32_767
        enc.sample(int16(total))
    enc.sample(int16(total + 3))
    total += 3
    assert enc.count() == total
    turns, rest = divmod(total, MG370_CPR)
    assert enc.angle() - turns * 360 == pytest.approx(rest * 360 / MG370_CPR, abs=0.05)


@pytest.mark.parametrize(
    ("kwargs", "error", "text"),
    [
        ({"counts_per_rev": 0}, ValueError, "counts_per_rev must be > 0"),
        ({"counts_per_rev": -1320}, ValueError, "counts_per_rev must be > 0"),
        ({"counts_per_rev": 1.5}, TypeError, "counts_per_rev must be an int"),
        ({"counts_per_rev": True}, TypeError, "counts_per_rev must be an int"),
        ({"counts_per_rev": 1320, "modulus": 2}, ValueError, "modulus must be 4..65536"),
        ({"counts_per_rev": 1320, "modulus": 70000}, ValueError, "modulus must be 4..65536"),
        ({"counts_per_rev": 1320, "pin_a": 7, "pin_b": 8}, OSError, "no PCNT peripheral"),
    ],
)
def test_bad_construction_says_what_and_how(kwargs, error, text):
    with pytest.raises(error, match=text):
        PCNTEncoder(**kwargs)


def test_sample_rejects_what_no_counter_reads():
    enc = PCNTEncoder(JGB37_CPR)
    with pytest.raises(TypeError, match="raw must be an int"):
        enc.sample(1.0)
    with pytest.raises(ValueError, match="out of range"):
        enc.sample(2**40)


def test_a_closed_encoder_says_so():
    enc = PCNTEncoder(JGB37_CPR)
    enc.close()
    with pytest.raises(ValueError, match="was closed"):
        enc.count()


def test_max_step_is_half_the_counter_period():
    assert PCNTEncoder(JGB37_CPR).max_step() == 16383
    assert PCNTEncoder(JGB37_CPR, modulus=65536).max_step() == 32767


@given(
    steps=st.lists(st.integers(-16383, 16383), max_size=200),
    start=st.integers(-32766, 32766),
    invert=st.booleans(),
)
def test_any_motion_within_half_a_period_per_sample_is_counted_exactly_on_a_pcnt(steps, start, invert):
    enc, pcnt = PCNTEncoder(JGB37_CPR, invert=invert), PcntCounter()
    pcnt.value = start
    enc.sample(pcnt.value)
    true = 0
    for step in steps:
        true += step
        enc.sample(pcnt.move(step))
    assert enc.count() == (-true if invert else true)
    if steps:
        last = steps[-1] * (-1 if invert else 1)
        assert enc.direction() == (last > 0) - (last < 0)


@given(
    steps=st.lists(st.integers(-32767, 32767), max_size=200),
    start=st.integers(-(2**20), 2**20),
    reset_at=st.integers(-(2**31), 2**31),
)
def test_any_motion_within_half_a_period_is_counted_exactly_on_a_16_bit_counter(steps, start, reset_at):
    enc = PCNTEncoder(JGB37_CPR, modulus=65536)
    enc.sample(int16(start))
    enc.reset(reset_at)
    true = start
    for step in steps:
        true += step
        enc.sample(int16(true))
    assert enc.count() == reset_at + true - start


@given(modulus=st.integers(4, 65536), steps=st.lists(st.integers(-(2**15), 2**15), max_size=50))
def test_any_counter_period_unwraps_any_small_enough_motion(modulus, steps):
    enc = PCNTEncoder(JGB37_CPR, modulus=modulus)
    limit = enc.max_step()
    enc.sample(0)
    true = 0
    for step in steps:
        step = max(-limit, min(limit, step))
        true += step
        enc.sample(true % modulus)
    assert enc.count() == true
