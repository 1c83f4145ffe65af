"""IMU models on the chassis: gyro Z follows the body's yaw rate with the sign the drivers expect,
the accelerometer feels gravity, and the BNO055's fused heading follows the robot round."""

import math
import struct

import numpy as np
import pytest

from openbricks_sim.sensors.imu import BNO055Model, BodyMotion, ICM45686Model
from openbricks_sim.sensors.registers import physics_clock_us

from .placed import place, spin_in_place, step_ms

GYRO_1000DPS = (2 << 4) | 5  # GYRO_CONFIG0 as openbricks.drivers.icm45686 programs it
ACCEL_4G = (3 << 4) | 5
LOW_NOISE = 0x0F


def icm(**kw):
    model, data = place("empty", 0.0, 0.0)
    chip = ICM45686Model(BodyMotion(model, data), physics_clock_us(data), **kw)
    return chip, model, data


def configure(chip, model, data):
    chip.transfer(bytes([0x7F, 0x02]))  # soft reset
    step_ms(model, data, 2)
    chip.transfer(bytes([0x1C, GYRO_1000DPS]))
    chip.transfer(bytes([0x1B, ACCEL_4G]))
    chip.transfer(bytes([0x10, LOW_NOISE]))


def read_sample(chip):
    reply = chip.transfer(bytes([0x80]) + bytes(12))
    ax, ay, az, gx, gy, gz = struct.unpack_from("<6h", reply, 1)
    return (ax * 4.0 / 32768, ay * 4.0 / 32768, az * 4.0 / 32768), (gx, gy, gz * 1000.0 / 32768)


def clockwise_rate_dps(model, data):
    """The body's turn rate seen from above, clockwise positive (heading convention)."""
    return -math.degrees(data.qvel[5])


def test_who_am_i_and_sensors_off_until_powered():
    chip, model, data = icm()
    assert chip.transfer(bytes([0x72 | 0x80, 0]))[1] == 0xE9
    reply = chip.transfer(bytes([0x80]) + bytes(12))
    assert set(struct.unpack_from("<6h", reply, 1)) == {-32768}


def test_soft_reset_blanks_the_chip_for_a_millisecond():
    chip, model, data = icm()
    chip.transfer(bytes([0x7F, 0x02]))
    assert chip.transfer(bytes([0x72 | 0x80, 0]))[1] == 0
    step_ms(model, data, 2)
    assert chip.transfer(bytes([0x72 | 0x80, 0]))[1] == 0xE9


def test_at_rest_the_accelerometer_reads_one_g_up_and_the_gyro_only_its_bias():
    chip, model, data = icm(bias_dps=(0.0, 0.0, 0.4), noise_dps=0.0)
    configure(chip, model, data)
    step_ms(model, data, 100)
    accel, gyro = read_sample(chip)
    assert accel[2] == pytest.approx(1.0, abs=0.01)
    assert abs(accel[0]) < 0.01 and abs(accel[1]) < 0.01
    assert gyro[2] == pytest.approx(0.4, abs=0.05)


def test_gyro_z_reads_a_clockwise_spin_as_negative_so_the_drivers_scale_minus_one_gives_heading():
    chip, model, data = icm(bias_dps=(0.0, 0.0, 0.0), noise_dps=0.0)
    configure(chip, model, data)
    spin_in_place(model, data, 600, wheel_dps=200.0)
    _, gyro = read_sample(chip)
    rate = clockwise_rate_dps(model, data)
    assert rate > 50.0  # really spinning clockwise
    assert -gyro[2] == pytest.approx(rate, abs=0.1)


def test_integrated_gyro_matches_the_body_rotation():
    chip, model, data = icm(bias_dps=(0.0, 0.0, 0.0))
    configure(chip, model, data)
    motion = BodyMotion(model, data)
    start_yaw = motion.yaw_roll_pitch_deg()[0]
    heading = 0.0
    for _ in range(400):  # 2 s at 200 Hz, as the driver samples
        spin_in_place(model, data, 5, wheel_dps=250.0)
        heading += -read_sample(chip)[1][2] * 0.005
    turned = (start_yaw - motion.yaw_roll_pitch_deg()[0]) % 360
    assert heading % 360 == pytest.approx(turned, abs=1.0)


def test_bias_is_seeded_and_small():
    a, _, _ = icm(seed=5)
    b, _, _ = icm(seed=5)
    c, _, _ = icm(seed=6)
    assert np.array_equal(a.bias_dps, b.bias_dps)
    assert not np.array_equal(a.bias_dps, c.bias_dps)
    assert np.all(np.abs(a.bias_dps) <= 0.5)


def bno():
    model, data = place("empty", 0.0, 0.0)
    chip = BNO055Model(BodyMotion(model, data), physics_clock_us(data), heading_noise_deg=0.0)
    return chip, model, data


def euler(chip):
    return [v / 16 for v in struct.unpack("<3h", chip.read_mem(0x1A, 6))]


def test_bno055_fusion_outputs_are_zero_in_config_mode_and_live_7_ms_after_imu_mode():
    chip, model, data = bno()
    assert chip.read_mem(0x00, 1) == b"\xa0"
    assert chip.read_mem(0x08, 6) == bytes(6)
    chip.write_mem(0x3D, b"\x08")
    step_ms(model, data, 3)
    assert chip.read_mem(0x08, 6) == bytes(6)
    step_ms(model, data, 5)
    ax, ay, az = struct.unpack("<3h", chip.read_mem(0x08, 6))
    assert az / 100 == pytest.approx(9.81, abs=0.05)


def test_bno055_heading_starts_at_zero_and_grows_clockwise():
    chip, model, data = bno()
    chip.write_mem(0x3D, b"\x08")
    step_ms(model, data, 10)
    assert euler(chip)[0] == pytest.approx(0.0, abs=0.1)
    motion = BodyMotion(model, data)
    start = motion.yaw_roll_pitch_deg()[0]
    spin_in_place(model, data, 700, wheel_dps=200.0)
    turned_cw = (start - motion.yaw_roll_pitch_deg()[0]) % 360
    assert turned_cw > 20.0
    assert euler(chip)[0] == pytest.approx(turned_cw, abs=0.1)
    gx, gy, gz = struct.unpack("<3h", chip.read_mem(0x14, 6))
    assert -gz / 16 == pytest.approx(clockwise_rate_dps(model, data), abs=0.2)
