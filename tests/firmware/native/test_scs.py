"""The serial-bus (SCS/STS) packet codec, through the host binding and, for
memory safety, as plain C under AddressSanitizer.

Expected packets are written out by hand from the manual's formula
CHECKSUM = ~(ID + LEN + INSTR + sum(PARAM)) & 0xFF, LEN = params + 2.
"""

import shutil
import struct
import subprocess
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from openbricks_native import scs

REPO = Path(__file__).resolve().parents[3]
NATIVE = REPO / "firmware" / "native"
FUZZ_DRIVER = Path(__file__).with_name("scs_fuzz.c")

servo_ids = st.integers(0, scs.MAX_SERVO_ID)
addressable_ids = st.integers(0, scs.BROADCAST_ID)
registers = st.integers(0, 0x7F)
payloads = st.binary(min_size=1, max_size=16)


def decode_all(data, decode=scs.decode_status):
    """Parse a receive buffer the way the bus engine does; returns (frames, leftover bytes)."""
    frames = []
    while True:
        f = decode(data)
        data = data[f.consumed :]
        if f.result == "need_more":
            return frames, data
        if f.result == "ok":
            frames.append(f)


# --- packets as the manual spells them -------------------------------------------------------


def test_ping_matches_the_manuals_checksum():
    # ~(0x01 + 0x02 + 0x01) = ~0x04 = 0xFB
    assert scs.ping(1) == bytes.fromhex("FF FF 01 02 01 FB")


def test_broadcast_ping_for_a_lone_servo():
    # ~(0xFE + 0x02 + 0x01) & 0xFF = ~0x01 = 0xFE
    assert scs.ping(scs.BROADCAST_ID) == bytes.fromhex("FF FF FE 02 01 FE")


def test_read_present_position():
    # ~(0x01 + 0x04 + 0x02 + 0x38 + 0x02) = ~0x41 = 0xBE
    assert scs.read(1, scs.REG_PRESENT_POSITION, 2) == bytes.fromhex("FF FF 01 04 02 38 02 BE")


def test_write_goal_speed_reverse_300():
    # -300 steps/s: magnitude 0x012C with bit 15 set = 0x812C, low byte first.
    # ~(0x01 + 0x05 + 0x03 + 0x2E + 0x2C + 0x81) = ~0xE4 = 0x1B
    packet = scs.write(1, scs.REG_GOAL_SPEED, scs.encode_speed(-300))
    assert packet == bytes.fromhex("FF FF 01 05 03 2E 2C 81 1B")


def test_broadcast_torque_off():
    # ~(0xFE + 0x04 + 0x03 + 0x28 + 0x00) & 0xFF = ~0x2D = 0xD2
    assert scs.write(scs.BROADCAST_ID, scs.REG_TORQUE_ENABLE, b"\x00") == bytes.fromhex(
        "FF FF FE 04 03 28 00 D2"
    )


def test_sync_write_two_wheels():
    # LEN = 2 (reg, data_len) + 2 x (id + 2 bytes) + 2 = 10
    # 0xFE + 0x0A + 0x83 + 0x2E + 0x02 + 0x01 + 0xE8 + 0x03 + 0x02 + 0xE8 + 0x83 = 0x414; ~0x14 = 0xEB
    packet = scs.sync_write(scs.REG_GOAL_SPEED, [(1, scs.encode_speed(1000)), (2, scs.encode_speed(-1000))])
    assert packet == bytes.fromhex("FF FF FE 0A 83 2E 02 01 E8 03 02 E8 83 EB")


def test_status_reply_with_position():
    # Servo 1, no error, present position 2048 = 0x0800: ~(0x01 + 0x04 + 0x00 + 0x00 + 0x08) = ~0x0D = 0xF2
    reply = bytes.fromhex("FF FF 01 04 00 00 08 F2")
    assert scs.status(1, 0, b"\x00\x08") == reply
    s = scs.decode_status(reply)
    assert (s.result, s.consumed, s.id, s.error) == ("ok", len(reply), 1, 0)
    assert scs.decode_position(s.params) == 2048


def test_checksum_is_the_complement_of_the_byte_sum():
    assert scs.checksum(bytes.fromhex("01 02 01")) == 0xFB
    assert scs.checksum(b"") == 0xFF
    assert scs.checksum(b"\xff\x01") == 0xFF  # the sum wraps at 8 bits


# --- round trips --------------------------------------------------------------------------------


@given(addressable_ids)
def test_ping_round_trip(servo_id):
    f = scs.decode_frame(scs.ping(servo_id))
    assert (f.result, f.id, f.instruction, f.params) == ("ok", servo_id, scs.PING, b"")


@given(servo_ids, st.integers(0, 0xFF), st.integers(1, 8))
def test_read_round_trip(servo_id, register, length):
    if register + length > 0x100:
        return
    f = scs.decode_frame(scs.read(servo_id, register, length))
    assert (f.result, f.id, f.instruction, f.params) == ("ok", servo_id, scs.READ, bytes([register, length]))


@given(addressable_ids, registers, payloads)
def test_write_round_trip(servo_id, register, data):
    packet = scs.write(servo_id, register, data)
    f = scs.decode_frame(packet)
    assert (f.result, f.consumed, f.id, f.instruction) == ("ok", len(packet), servo_id, scs.WRITE)
    assert f.params == bytes([register]) + data


@given(
    registers,
    st.integers(1, 4).flatmap(
        lambda n: st.lists(st.tuples(servo_ids, st.binary(min_size=n, max_size=n)), min_size=1, max_size=12)
    ),
)
def test_sync_write_round_trip(register, rows):
    f = scs.decode_frame(scs.sync_write(register, rows))
    assert (f.result, f.id, f.instruction) == ("ok", scs.BROADCAST_ID, scs.SYNC_WRITE)
    data_len = len(rows[0][1])
    assert f.params[:2] == bytes([register, data_len])
    body = f.params[2:]
    stride = 1 + data_len
    assert [(body[i], body[i + 1 : i + stride]) for i in range(0, len(body), stride)] == rows


@given(servo_ids, st.integers(0, 0xFF), st.binary(max_size=32))
def test_status_round_trip(servo_id, error, params):
    s = scs.decode_status(scs.status(servo_id, error, params))
    assert (s.result, s.id, s.error, s.params) == ("ok", servo_id, error, params)


def test_largest_frame_round_trips():
    data = bytes(range(252))  # 252 data bytes + the register = 253 params, LEN = 255
    packet = scs.write(1, 0, data)
    assert packet[3] == 0xFF and len(packet) == 259
    f = scs.decode_frame(packet)
    assert f.result == "ok" and f.params == b"\x00" + data


# --- receive buffers as a UART delivers them ------------------------------------------------------


def test_replies_are_found_among_garbage_and_back_to_back():
    a = scs.status(1, 0, b"\x00\x08")
    b = scs.status(2, scs.FLAG_OVERLOAD, b"")
    c = scs.status(3, 0, b"\x12")
    stream = b"\x00\x13\xff" + a + b + b"\xfe\xff\x7f" + c + b"\xff"
    frames, leftover = decode_all(stream)
    assert [(f.id, f.error, f.params) for f in frames] == [
        (1, 0, b"\x00\x08"),
        (2, scs.FLAG_OVERLOAD, b""),
        (3, 0, b"\x12"),
    ]
    assert leftover == b"\xff"  # may be the start of the next header: kept


def test_extra_header_bytes_are_preamble():
    reply = scs.status(7, 0, b"\x01")
    s = scs.decode_status(b"\xff\xff\xff\xff" + reply)
    assert (s.result, s.id, s.consumed) == ("ok", 7, 4 + len(reply))


@pytest.mark.parametrize("cut", range(0, 8))
def test_truncated_reply_asks_for_more_and_says_how_much(cut):
    reply = scs.status(1, 0, b"\x00\x08")
    s = scs.decode_status(reply[:cut])
    assert s.result == "need_more"
    assert s.consumed == 0  # nothing dropped: the partial reply is kept for the next read
    assert 1 <= s.needed <= len(reply) - cut
    if cut >= 4:  # once LEN has arrived the exact remainder is known
        assert s.needed == len(reply) - cut


def test_garbage_before_a_partial_reply_is_released():
    s = scs.decode_status(b"\x10\x20\x30" + scs.status(1, 0, b"\x00")[:5])
    assert (s.result, s.consumed) == ("need_more", 3)


@pytest.mark.parametrize("position", [2, 4, 5, 6, 7])
@pytest.mark.parametrize("flip", [0x01, 0x80, 0xFF])
def test_any_corrupted_byte_is_a_bad_checksum(position, flip):
    reply = bytearray(scs.status(1, 0, b"\x00\x08"))
    reply[position] ^= flip
    s = scs.decode_status(bytes(reply))
    assert s.result == "bad_checksum"
    assert s.consumed == 1  # rescan from the next byte


def test_resynchronises_after_a_corrupt_reply():
    bad = bytearray(scs.status(1, 0, b"\x00\x08"))
    bad[5] ^= 0x40
    good = scs.status(2, 0, b"\x34\x12")
    frames, _ = decode_all(bytes(bad) + good)
    assert [(f.id, f.params) for f in frames] == [(2, b"\x34\x12")]


def test_length_below_two_is_rejected():
    s = scs.decode_status(bytes.fromhex("FF FF 01 01 00"))
    assert (s.result, s.consumed) == ("bad_length", 1)


def test_a_reply_cannot_come_from_the_broadcast_id():
    echo = scs.ping(scs.BROADCAST_ID)  # our own broadcast heard back on a single-wire bus
    assert scs.decode_status(echo).result == "bad_header"
    assert scs.decode_status(echo).consumed == 1
    assert scs.decode_frame(echo).result == "ok"  # as a request it is fine


def test_params_are_a_copy_not_a_view_of_the_buffer():
    buf = bytearray(scs.status(1, 0, b"\x00\x08"))
    s = scs.decode_status(buf)
    buf[5] = 0x55
    assert s.params == b"\x00\x08"


@settings(max_examples=400, suppress_health_check=[HealthCheck.too_slow])
@given(st.binary(max_size=300))
def test_arbitrary_bytes_never_break_the_parser(data):
    for decode in (scs.decode_frame, scs.decode_status):
        remaining = data
        while True:
            f = decode(remaining)
            assert f.result in {"ok", "need_more", "bad_checksum", "bad_header", "bad_length"}
            assert 0 <= f.consumed <= len(remaining)
            if f.result == "ok":
                # What was accepted is exactly the frame its fields encode to (f[4]: instruction or error).
                frame = remaining[f.consumed - 6 - len(f.params) : f.consumed]
                assert scs.frame(f.id, f[4], f.params) == frame
            elif f.result != "need_more":
                assert f.consumed >= 1
            remaining = remaining[f.consumed :]
            if f.result == "need_more":
                break


@given(st.lists(st.tuples(servo_ids, st.integers(0, 0xFF), st.binary(max_size=8)), max_size=6), st.data())
def test_replies_survive_being_split_into_arbitrary_reads(replies, data):
    stream = b"".join(scs.status(i, e, p) for i, e, p in replies)
    cuts = sorted(data.draw(st.lists(st.integers(0, len(stream)), max_size=6)))
    buffer, got = b"", []
    for lo, hi in zip([0, *cuts], [*cuts, len(stream)], strict=True):
        buffer += stream[lo:hi]
        frames, buffer = decode_all(buffer)
        got += [(f.id, f.error, f.params) for f in frames]
    assert got == replies


# --- register encodings ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("steps_per_s", "raw"),
    [
        (0, 0x0000),
        (1, 0x0001),
        (-1, 0x8001),
        (300, 0x012C),
        (-300, 0x812C),
        (32767, 0x7FFF),
        (-32767, 0xFFFF),
    ],
)
def test_speed_is_sign_magnitude_with_the_direction_in_bit_15(steps_per_s, raw):
    assert scs.encode_speed(steps_per_s) == struct.pack("<H", raw)
    assert scs.decode_speed(struct.pack("<H", raw)) == steps_per_s


def test_negative_zero_reads_as_zero():
    assert scs.decode_speed(b"\x00\x80") == 0
    assert scs.decode_position(b"\x00\x80") == 0
    assert scs.decode_load(b"\x00\x04") == 0


@pytest.mark.parametrize(("tenths_pct", "raw"), [(0, 0x000), (500, 0x1F4), (-500, 0x5F4), (-1000, 0x7E8)])
def test_load_is_sign_magnitude_with_the_direction_in_bit_10(tenths_pct, raw):
    assert scs.encode_load(tenths_pct) == struct.pack("<H", raw)
    assert scs.decode_load(struct.pack("<H", raw)) == tenths_pct


def test_load_ignores_bits_above_its_sign():
    assert scs.decode_load(struct.pack("<H", 0xF800 | 0x1F4)) == 500


def test_position_keeps_the_multi_turn_sign():
    assert scs.encode_position(-4096 * 7) == struct.pack("<H", 0x8000 | 28672)
    assert scs.decode_position(struct.pack("<H", 0x8000 | 28672)) == -28672


@given(st.integers(-32767, 32767))
def test_speed_and_position_round_trip(value):
    assert scs.decode_speed(scs.encode_speed(value)) == value
    assert scs.decode_position(scs.encode_position(value)) == value


@given(st.integers(-1023, 1023))
def test_load_round_trips(value):
    assert scs.decode_load(scs.encode_load(value)) == value


@pytest.mark.parametrize(
    ("encode", "value"),
    [
        (scs.encode_speed, 32768),
        (scs.encode_speed, -32768),
        (scs.encode_load, 1024),
        (scs.encode_position, 2**40),
    ],
)
def test_values_that_do_not_fit_are_refused_not_wrapped(encode, value):
    with pytest.raises(ValueError, match="does not fit"):
        encode(value)


def test_register_values_are_two_bytes():
    with pytest.raises(ValueError, match="2 bytes"):
        scs.decode_speed(b"\x01")


# --- status error flags ---------------------------------------------------------------------------


def test_error_flags_have_feetech_names():
    assert scs.flag_names(0) == ()
    assert scs.flag_names(scs.FLAG_VOLTAGE | scs.FLAG_OVERLOAD) == ("voltage", "overload")
    assert scs.flag_names(0xFF) == (
        "voltage",
        "angle",
        "overheat",
        "overcurrent",
        "bit4",
        "overload",
        "bit6",
        "bit7",
    )


def test_an_overheating_servo_is_reported_in_its_reply():
    s = scs.decode_status(scs.status(4, scs.FLAG_OVERHEAT, b"\x00\x00"))
    assert scs.flag_names(s.error) == ("overheat",)


# --- argument errors ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: scs.ping(255), r"servo id 255 is out of range 0\.\.254"),
        (lambda: scs.ping(-1), r"servo id -1"),
        (lambda: scs.read(scs.BROADCAST_ID, 0x38, 2), r"not broadcast.* 254 is out of range 0\.\.253"),
        (lambda: scs.read(1, 0x38, 0), r"read length 0 is out of range 1\.\.253"),
        (lambda: scs.read(1, 0x100, 1), r"register 256 is out of range 0\.\.255"),
        (lambda: scs.read(1, 0xFF, 2), r"read of 2 bytes at register 0xFF runs past register 0xFF"),
        (lambda: scs.write(1, 0x2A, b""), r"write data is 0 bytes; it must be 1\.\.252"),
        (lambda: scs.write(1, 0, bytes(253)), r"write data is 253 bytes"),
        (lambda: scs.write(1, 0xFE, b"abc"), r"write of 3 bytes at register 0xFE runs past"),
        (lambda: scs.sync_write(0x2E, []), r"sync_write has 0 rows"),
        (
            lambda: scs.sync_write(0x2E, [(1, b"ab"), (2, b"a")]),
            r"servo 2 is 1 bytes but the first row has 2",
        ),
        (lambda: scs.sync_write(0x2E, [(scs.BROADCAST_ID, b"ab")]), r"sync_write servo id 254"),
        (lambda: scs.sync_write(0x00, [(i, bytes(4)) for i in range(60)]), r"exceed"),
        (lambda: scs.status(scs.BROADCAST_ID, 0), r"a reply comes from one servo"),
        (lambda: scs.status(1, 0x100), r"error flags 256"),
    ],
)
def test_bad_arguments_name_what_is_wrong(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def test_sync_write_rows_must_be_pairs():
    with pytest.raises(TypeError, match=r"row 0 must be an \(id, data\) pair"):
        scs.sync_write(0x2E, [1, 2])


def test_submodule_is_importable_by_name():
    import openbricks_native.scs as by_name

    assert by_name is scs


# --- the C codec under AddressSanitizer -----------------------------------------------------------


@pytest.fixture(scope="module")
def fuzz_driver(tmp_path_factory):
    """scs.c and the fuzz driver built with ASan + UBSan; any out-of-bounds byte aborts it."""
    gcc = shutil.which("gcc")
    assert gcc, "gcc is required to build the sanitized SCS fuzz driver (apt-get install gcc)"
    exe = tmp_path_factory.mktemp("scs_fuzz") / "scs_fuzz"
    cmd = [
        gcc,
        "-std=c99",
        "-g",
        "-O1",
        "-fsanitize=address,undefined",
        "-fno-sanitize-recover=all",
        "-fno-omit-frame-pointer",
        f"-I{NATIVE}",
        str(NATIVE / "scs.c"),
        str(FUZZ_DRIVER),
        "-o",
        str(exe),
    ]
    built = subprocess.run(cmd, capture_output=True, text=True)
    assert built.returncode == 0, f"building the sanitized fuzz driver failed:\n{built.stderr}"
    return exe


def test_c_fuzz_loop_under_address_sanitizer(fuzz_driver):
    run = subprocess.run(
        [fuzz_driver, "random", "200000", "20261122"], capture_output=True, text=True, timeout=120
    )
    assert run.returncode == 0, f"the C codec broke under the fuzz loop:\n{run.stderr[-4000:]}"
    assert run.stdout.strip() == "ok 200000"


# Inputs for the sanitized parser: arbitrary bytes, and mostly-valid streams (real packets with
# garbage between them and the tail cut off), where a bounds bug is likeliest to hide.
fuzz_inputs = st.one_of(
    st.binary(max_size=300),
    st.tuples(
        st.lists(
            st.one_of(
                st.builds(scs.status, servo_ids, st.integers(0, 255), st.binary(max_size=20)),
                st.builds(scs.ping, addressable_ids),
                st.builds(scs.write, addressable_ids, registers, payloads),
                st.binary(max_size=6),
                st.just(b"\xff\xff"),
            ),
            max_size=5,
        ).map(b"".join),
        st.integers(0, 300),
    ).map(lambda stream_cut: stream_cut[0][: stream_cut[1]]),
)


@settings(max_examples=60, suppress_health_check=[HealthCheck.too_slow], deadline=None)
@given(st.lists(fuzz_inputs, min_size=1, max_size=40))
def test_hypothesis_inputs_under_address_sanitizer(fuzz_driver, inputs):
    records = b"".join(struct.pack("<H", len(data)) + data for data in inputs)
    run = subprocess.run([fuzz_driver, "stdin"], input=records, capture_output=True, timeout=60)
    assert run.returncode == 0, f"the C codec broke on one of {inputs!r}:\n{run.stderr.decode()[-4000:]}"
    assert run.stdout == b"ok\n" * len(inputs)
