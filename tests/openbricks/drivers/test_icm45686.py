"""ICM-45686 over a register-level SPI chip: configuration, heading integration, bias learning, NVS seed."""

import time

from machine import board

from fakes.expect import approx, raises
from fakes.spi_imu import ICM45686Chip
from openbricks import pins
from openbricks.drivers.icm45686 import ICM45686

CS = 17


class DriveBase:
    """Stands in for openbricks.robotics.DriveBase taking the heading with use_gyro(True)."""


def _imu(chip=None, **kwargs):
    chip = chip or ICM45686Chip()
    board.attach_spi(CS, chip)
    return ICM45686(sck=12, mosi=13, miso=11, cs=CS, **kwargs), chip


def _still(ms):
    time.sleep_ms(ms)


def test_construction_resets_then_powers_gyro_and_accel_in_low_noise_at_1000_dps():
    imu, chip = _imu()
    assert chip.soft_resets == 1
    assert chip.regs[0x10] == 0x0F
    assert chip.gyro_fs_dps() == 1000.0
    assert chip.accel_fs_g() == 4.0
    assert imu.stats()[2] is True


def test_a_clockwise_turn_reads_positive_heading():
    imu, chip = _imu()
    _still(600)
    chip.yaw_rate_dps = 90.0
    time.sleep_ms(1000)
    chip.yaw_rate_dps = 0.0
    _still(100)
    assert approx(imu.heading(), 90.0, 0.5), imu.heading()


def test_heading_is_continuous_past_a_full_turn():
    imu, chip = _imu()
    _still(600)
    chip.yaw_rate_dps = -200.0
    time.sleep_ms(2000)  # 400 degrees counter-clockwise
    chip.yaw_rate_dps = 0.0
    assert approx(imu.heading(), -400.0, 2.0), imu.heading()


def test_a_face_down_breakout_uses_scale_plus_one():
    chip = ICM45686Chip()
    chip.face_up = False
    imu, chip = _imu(chip, scale=1.0)
    _still(600)
    chip.yaw_rate_dps = 45.0
    time.sleep_ms(1000)
    assert approx(imu.heading(), 45.0, 0.5), imu.heading()


def test_gyro_bias_is_learned_at_rest_and_stops_the_drift():
    chip = ICM45686Chip()
    chip.gyro_bias_dps = 0.8
    imu, chip = _imu(chip)
    assert not imu.calibrated()
    _still(1000)
    assert imu.calibrated()
    start = imu.heading()
    _still(10_000)
    assert abs(imu.heading() - start) < 0.2, imu.heading() - start
    assert abs(imu.heading()) < 0.5  # the drift before the lock was taken back out too


def test_a_robot_that_moves_from_boot_does_not_learn_its_motion_as_bias():
    imu, chip = _imu()
    chip.yaw_rate_dps = 3.0  # a slow crawl, inside the plausible-bias range
    for step in range(20):
        chip.yaw_rate_dps = 3.0 if step % 2 == 0 else -3.0
        time.sleep_ms(100)
    assert not imu.calibrated()


def test_saved_bias_seeds_the_next_boot_so_it_is_corrected_at_once():
    chip = ICM45686Chip()
    chip.gyro_bias_dps = -1.2
    imu, chip = _imu(chip)
    with raises(OSError, "keep the robot still"):
        imu.save_calibration()
    _still(700)
    imu.save_calibration()
    imu.close()
    again, chip = _imu(chip)
    assert again.calibrated()
    chip.yaw_rate_dps = 30.0
    time.sleep_ms(1000)  # moving from the first sample: no still window to learn from
    assert approx(again.heading(), 30.0, 0.3), again.heading()


def test_reset_heading_sets_the_current_pose_and_keeps_the_bias():
    imu, chip = _imu()
    _still(600)
    chip.yaw_rate_dps = 50.0
    time.sleep_ms(500)
    chip.yaw_rate_dps = 0.0
    imu.reset_heading(10)
    assert approx(imu.heading(), 10.0, 0.01)
    assert imu.calibrated()


def test_reset_heading_is_refused_while_a_drive_base_steers_by_the_gyro():
    imu, chip = _imu()
    db = DriveBase()
    imu.lock_heading(db)
    assert imu.heading_locked_by() is db
    with raises(OSError, "can't reset heading while gyro in use") as err:
        imu.reset_heading()
    assert "DriveBase" in str(err.value) and "use_gyro(False)" in str(err.value)
    with raises(OSError, "already steers"):
        imu.lock_heading(DriveBase())
    imu.unlock_heading(db)
    imu.reset_heading()
    assert imu.heading_locked_by() is None


def test_gyro_and_acceleration_are_in_dps_and_g():
    imu, chip = _imu()
    chip.gyro_xy_dps = (12.5, -3.0)
    chip.accel_g = (0.0, 0.5, 1.0)
    _still(10)
    gx, gy, _gz = imu.gyro()
    ax, ay, az = imu.acceleration()
    assert approx(gx, 12.5, 0.05) and approx(gy, -3.0, 0.05)
    assert approx(ay, 0.5, 0.001) and approx(az, 1.0, 0.001)


def test_without_a_timer_each_call_takes_a_sample():
    imu, chip = _imu(timer_id=None)
    reads = chip.data_reads
    imu.heading()
    imu.gyro()
    assert chip.data_reads == reads + 2
    _still(1000)
    assert chip.data_reads == reads + 2


def test_stats_count_good_and_bad_samples():
    imu, chip = _imu()
    _still(100)
    ok, errors, configured = imu.stats()
    assert ok >= 19 and errors == 0 and configured
    chip.regs[0x10] = 0x00  # the gyro powered down under us: the chip reads "no data"
    _still(50)
    assert imu.stats()[1] >= 9


def test_an_unwired_bus_is_reported_with_the_pins():
    chip = ICM45686Chip()
    chip.silent = True
    with raises(OSError, "reads 0xFF") as err:
        _imu(chip)
    assert "SCK=12 MOSI=13 MISO=11 CS=17" in str(err.value)


def test_spi_pins_are_claimed():
    imu, _chip = _imu()
    with raises(pins.ReservedPinError, "GPIO 17"):
        pins.claim(17, "status LED", owner="hub")
    imu.close()
    pins.claim(17, "status LED", owner="hub")


def test_sampling_stops_once_the_program_that_built_it_has_given_its_pins_back():
    claims = pins.snapshot()  # what the launcher does around a run
    imu, chip = _imu()
    time.sleep_ms(100)
    assert chip.data_reads > 0
    pins.release_since(claims)  # the run ended: the IMU is the finished program's garbage
    time.sleep_ms(500)  # its timer notices within a few samples
    reads = chip.data_reads
    time.sleep_ms(2000)
    assert chip.data_reads == reads  # no SPI traffic (or scheduler load) from a dead program
    pins.claim(17, "L298N PWM/EN", owner="L298N")  # the next program may wire the pins its own way
    time.sleep_ms(100)
    assert chip.data_reads == reads
