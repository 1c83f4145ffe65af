"""BNO055 against a register-level chip: boot, fusion mode, heading frame and units."""

from machine import I2C, board

from fakes.expect import approx, raises
from fakes.i2c_chips import BNO055Chip, VL53L0XChip
from openbricks.drivers.bno055 import BNO055
from openbricks.interfaces import IMU


class DriveBase:
    """Stands in for openbricks.robotics.DriveBase taking the heading with use_gyro(True)."""


def _imu(chip=None, address=0x28):
    chip = chip or BNO055Chip()
    board.attach_i2c(0, address, chip)
    return BNO055(I2C(0), address=address), chip


def test_is_an_imu_running_the_accel_gyro_fusion_mode():
    imu, chip = _imu()
    assert isinstance(imu, IMU)
    assert chip.mode() == 0x08
    assert chip.fusing()


def test_construction_waits_out_the_power_on_boot():
    imu, chip = _imu(BNO055Chip(boot_ms=650))
    assert chip.fusing()


def test_heading_is_zero_where_the_robot_pointed_at_construction():
    chip = BNO055Chip()
    chip.heading_deg = 123.0
    imu, chip = _imu(chip)
    assert imu.heading() == 0.0
    chip.heading_deg = 123.0 + 30.0  # turned 30 degrees clockwise
    assert approx(imu.heading(), 30.0, 0.07)


def test_heading_wraps_to_plus_minus_180():
    imu, chip = _imu()
    chip.heading_deg = 190.0
    assert approx(imu.heading(), -170.0, 0.07)
    chip.heading_deg = 350.0
    assert approx(imu.heading(), -10.0, 0.07)
    chip.heading_deg = 180.0
    assert imu.heading() == -180.0


def test_reset_heading_declares_the_current_heading():
    imu, chip = _imu()
    chip.heading_deg = 45.0
    imu.reset_heading(90)
    assert approx(imu.heading(), 90.0, 0.07)
    chip.heading_deg = 55.0
    assert approx(imu.heading(), 100.0, 0.07)


def test_reset_heading_is_refused_while_a_drive_base_steers_by_it():
    imu, chip = _imu()
    db = DriveBase()
    imu.lock_heading(db)
    with raises(OSError, "can't reset heading while gyro in use"):
        imu.reset_heading()
    imu.unlock_heading(db)
    imu.reset_heading()


def test_euler_rates_and_acceleration_are_in_degrees_dps_and_m_s2():
    imu, chip = _imu()
    chip.roll_deg, chip.pitch_deg = 2.5, -4.0
    chip.gyro_dps = (1.0, -2.0, 33.5)
    chip.accel_ms2 = (0.5, 0.0, 9.81)
    heading, roll, pitch = imu.euler()
    assert heading == 0.0 and roll == 2.5 and pitch == -4.0
    assert imu.angular_velocity() == (1.0, -2.0, 33.5)
    assert approx(imu.acceleration()[2], 9.81, 0.01)


def test_units_are_set_explicitly_not_left_to_the_chip_default():
    imu, chip = _imu()
    assert chip.regs[0x3B] == 0x00


def test_alternate_address_works():
    imu, chip = _imu(address=0x29)
    assert chip.fusing()


def test_no_chip_names_the_address_and_the_adr_strap():
    with raises(OSError, "address=0x29"):
        BNO055(I2C(0))


def test_another_chip_at_the_address_is_refused():
    board.attach_i2c(0, 0x29, VL53L0XChip())
    with raises(OSError, "not a BNO055"):
        BNO055(I2C(0), address=0x29)
