"""The ICM-45686 core (firmware/native/icm45686.c) against a register model of the chip, fed the way
the hub's hard tick feeds it: one 13-byte burst per millisecond, gyro Z into the heading integrator,
and a drive base that reads the heading in C.
"""

import math
import random
import struct

import pytest
from hypothesis import given
from hypothesis import strategies as st

import openbricks_native as native
from tests.firmware.native.drivebase_rig import AXLE_TRACK_MM, WHEEL_DIAMETER_MM, Chassis

WHO_AM_I, PWR_MGMT0, ACCEL_CONFIG0, GYRO_CONFIG0, MISC2 = 0x72, 0x10, 0x1B, 0x1C, 0x7F
GYRO_FS_DPS = (4000.0, 2000.0, 1000.0, 500.0, 250.0, 125.0, 62.5, 31.25, 15.625)
ACCEL_FS_G = (32.0, 16.0, 8.0, 4.0, 2.0)
NO_DATA = -32768


class Chip:
    """A face-up ICM-45686 on a robot body (registers per DS-000577, bank 0).

    `rate_cw_dps` is the body's turn rate clockwise from above; the chip reports it on gyro Z
    counter-clockwise-positive, plus its bias and noise. Registers read 0 for 1 ms after a soft reset.
    """

    def __init__(self, who_am_i=0xE9, bias_dps=0.7, noise_dps=0.05, seed=3):
        self.who_am_i = who_am_i
        self.bias_dps = bias_dps
        self.noise_dps = noise_dps
        self.rng = random.Random(seed)
        self.now_us = 0
        self.rate_cw_dps = 0.0
        self.accel_g = (0.01, -0.02, 1.0)
        self.transfers = []
        self.regs = bytearray(128)
        self._reset()

    def _reset(self):
        self.regs = bytearray(128)
        self.regs[ACCEL_CONFIG0] = 0x06
        self.regs[GYRO_CONFIG0] = 0x06
        self.regs[WHO_AM_I] = self.who_am_i
        self.usable_from_us = self.now_us + 1000

    def delay_ms(self, ms):
        self.now_us += ms * 1000

    def gyro_fs(self):
        return GYRO_FS_DPS[self.regs[GYRO_CONFIG0] >> 4]

    def accel_fs(self):
        return ACCEL_FS_G[(self.regs[ACCEL_CONFIG0] >> 4) & 7]

    def data(self):
        pwr = self.regs[PWR_MGMT0]
        accel_on, gyro_on = (pwr & 3) in (2, 3), ((pwr >> 2) & 3) in (2, 3)
        gz = -self.rate_cw_dps + self.bias_dps + self.rng.gauss(0.0, self.noise_dps)
        gyro = (0.3, -0.2, gz)

        def counts(value, fs):
            return max(-32767, min(32767, round(value * 32768 / fs)))

        accel = [counts(a, self.accel_fs()) if accel_on else NO_DATA for a in self.accel_g]
        rates = [counts(w, self.gyro_fs()) if gyro_on else NO_DATA for w in gyro]
        return struct.pack("<6h", *accel, *rates)

    def transfer(self, data):
        self.transfers.append(bytes(data))
        if self.now_us < self.usable_from_us:
            return bytes(len(data))
        reg = data[0] & 0x7F
        if data[0] & 0x80:
            block = self.data() if reg == 0 else b""
            out = bytearray(len(data))
            for i in range(1, len(data)):
                r = reg + i - 1
                out[i] = block[r] if r < len(block) else self.regs[r & 0x7F]
            return bytes(out)
        for i, value in enumerate(data[1:]):
            r = (reg + i) & 0x7F
            if r == MISC2 and value & 0x02:
                self._reset()
            elif r != WHO_AM_I:
                self.regs[r] = value
        return bytes(len(data))


def new_imu(chip=None, **kwargs):
    chip = chip or Chip()
    return native.ICM45686(chip.transfer, delay_ms=chip.delay_ms, **kwargs), chip


def run(imu, chip, ms, rate_cw_dps=0.0):
    chip.rate_cw_dps = rate_cw_dps
    for _ in range(ms):
        chip.now_us += 1000
        imu.sample(chip.now_us)


def test_setup_resets_checks_the_chip_and_selects_1000_dps_4_g_low_noise():
    imu, chip = new_imu()
    assert chip.transfers[0] == bytes((MISC2, 0x02))
    assert chip.transfers[1][0] == WHO_AM_I | 0x80
    assert (chip.regs[GYRO_CONFIG0], chip.regs[ACCEL_CONFIG0], chip.regs[PWR_MGMT0]) == (0x25, 0x35, 0x0F)
    assert chip.now_us >= 52_000  # reset settle + gyro start-up waited through delay_ms
    assert imu.stats() == (0, 0, True)


def test_setup_without_waiting_after_the_reset_finds_no_chip():
    chip = Chip()
    with pytest.raises(OSError, match=r"WHO_AM_I \(0x72\) reads 0x00, expected 0xE9; nothing drives MISO"):
        native.ICM45686(chip.transfer)


def test_another_chip_on_the_bus_is_named_by_its_who_am_i():
    with pytest.raises(OSError, match=r"reads 0x67, expected 0xE9; another chip\?"):
        new_imu(Chip(who_am_i=0x67))


def test_the_s_variant_is_accepted():
    imu, _ = new_imu(Chip(who_am_i=0xEE))
    assert imu.stats()[2] is True


def test_each_sample_is_one_13_byte_burst_from_the_data_registers_scaled_to_dps_and_g():
    imu, chip = new_imu(Chip(noise_dps=0.0, bias_dps=0.0))
    chip.transfers.clear()
    run(imu, chip, 1, rate_cw_dps=-250.0)
    (burst,) = chip.transfers
    assert len(burst) == 13 and burst[0] == 0x80
    gx, gy, gz = imu.gyro()
    assert (gx, gy, gz) == pytest.approx((0.3, -0.2, 250.0), abs=1000 / 32768)
    assert imu.acceleration() == pytest.approx((0.01, -0.02, 1.0), abs=4 / 32768)
    assert imu.stats() == (1, 0, True)


def test_a_sensor_that_reads_no_data_is_a_missed_sample():
    imu, chip = new_imu()
    run(imu, chip, 10)
    chip.regs[PWR_MGMT0] = 0x03  # gyro off: gyro registers read -32768
    assert imu.sample(chip.now_us + 1000) is False
    assert imu.stats() == (10, 1, True)


def test_the_heading_learns_the_bias_at_rest_and_follows_a_turn():
    imu, chip = new_imu(Chip(bias_dps=0.7))
    run(imu, chip, 600)
    assert imu.calibrated() and imu.bias() == pytest.approx(0.7, abs=0.02)
    run(imu, chip, 1000, rate_cw_dps=90.0)
    run(imu, chip, 200)
    assert imu.heading() == pytest.approx(90.0, abs=0.3)
    assert imu.rate() == pytest.approx(0.0, abs=0.3)


def test_a_transfer_that_raises_reaches_the_caller_of_sample():
    chip = Chip()
    fault = []

    def transfer(data):
        if fault:
            raise OSError(5, "SPI bus fault")
        return chip.transfer(data)

    imu = native.ICM45686(transfer, delay_ms=chip.delay_ms)
    assert imu.sample(chip.now_us) is True
    fault.append(True)
    with pytest.raises(OSError, match="SPI bus fault"):
        imu.sample(chip.now_us + 1000)
    assert imu.stats() == (1, 1, True)


def test_a_transfer_of_the_wrong_length_says_so():
    chip = Chip()
    with pytest.raises(ValueError, match="returned 1 bytes for a 2-byte transfer"):
        native.ICM45686(lambda data: b"\x00", delay_ms=chip.delay_ms)


@pytest.mark.parametrize(
    ("kwargs", "error", "text"),
    [
        ({"scale": 0.0}, ValueError, "scale must be non-zero"),
        ({"delay_ms": 5}, TypeError, "delay_ms must be a callable"),
        ({"sck": 12, "mosi": 13, "miso": 11, "cs": 17}, OSError, "no SPI peripheral"),
    ],
)
def test_bad_construction_says_what_and_how(kwargs, error, text):
    chip = Chip()
    with pytest.raises(error, match=text):
        native.ICM45686(chip.transfer, **kwargs)


def test_no_transfer_is_refused():
    with pytest.raises(TypeError, match="transfer must be a callable"):
        native.ICM45686()


@given(st.binary(min_size=12, max_size=12))
def test_any_burst_is_a_bounded_sample_or_a_miss(block):
    chip = Chip()
    wire = [chip.transfer]
    imu = native.ICM45686(lambda data: wire[0](data), delay_ms=chip.delay_ms)
    wire[0] = lambda data: b"\x00" + block
    ok = imu.sample(1000)
    values = struct.unpack("<6h", block)
    assert ok == (NO_DATA not in values)
    if ok:
        assert all(abs(g) <= 1000.0 for g in imu.gyro())
        assert all(abs(a) <= 4.0 for a in imu.acceleration())
        assert imu.gyro()[2] == pytest.approx(values[5] * 1000 / 32768)
    assert math.isfinite(imu.heading())


def drive_with(heading_source_of, imu, chip, chassis):
    """A 1 kHz loop as the hub's hard tick runs it: sample the IMU, then tick the drive base."""
    duties = [0.0, 0.0]

    def writer(side):
        def write(duty):
            duties[side] = duty

        return write

    def coaster(side):
        def coast():
            duties[side] = None

        return coast

    db = native.DriveBase(
        WHEEL_DIAMETER_MM,
        AXLE_TRACK_MM,
        read_left=lambda: chassis.encoders_deg[0],
        read_right=lambda: chassis.encoders_deg[1],
        write_left=writer(0),
        write_right=writer(1),
        coast_left=coaster(0),
        coast_right=coaster(1),
        heading=heading_source_of(imu),
    )
    process = native.MotorProcess()
    process.subscribe(db)
    now_ms = 0

    def period():
        nonlocal now_ms
        before = chassis.heading_deg
        chassis.step(tuple(duties), 0.001)
        chip.rate_cw_dps = (chassis.heading_deg - before) / 0.001
        chip.now_us += 1000
        imu.sample(chip.now_us)
        now_ms += 1
        process.tick(now_ms)

    for _ in range(600):  # at rest: the bias locks
        period()
    db.use_gyro(True)
    db.straight(1000)
    for _ in range(20_000):
        period()
        if db.done():
            break
    for _ in range(300):
        period()
    return db


def test_a_drive_base_steers_by_the_native_imu_through_wheel_slip():
    """The left tyre slips 5 %: the encoders see a straight line; the gyro, read in C, sees the curve."""
    imu, chip = new_imu()
    chassis = Chassis(slip=(0.05, 0.0))
    drive_with(lambda imu: imu, imu, chip, chassis)
    assert abs(chassis.heading_deg) < 0.5, f"the robot ended {chassis.heading_deg:.2f} deg off"
    assert chassis.x_mm == pytest.approx(1000, abs=30)


def test_the_native_heading_steers_as_the_python_one_does():
    results = []
    for source in (lambda imu: imu, lambda imu: imu.heading):
        imu, chip = new_imu()
        chassis = Chassis(slip=(0.05, 0.0))
        drive_with(source, imu, chip, chassis)
        results.append((chassis.x_mm, chassis.y_mm, chassis.heading_deg))
    assert results[0] == pytest.approx(results[1], abs=1e-6)


def test_a_drive_base_refuses_a_heading_that_is_neither_callable_nor_an_imu():
    with pytest.raises(TypeError, match=r"heading must be a callable returning degrees or a native IMU"):
        native.DriveBase(WHEEL_DIAMETER_MM, AXLE_TRACK_MM, heading=42)
