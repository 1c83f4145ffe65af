"""TDK ICM-45686 6-axis IMU on SPI: the gyro heading source.

The gyro's Z rate integrates into a continuous (multi-turn) heading,
clockwise-positive like the drive base. Its zero-rate bias is learned while
the robot stands still (locked after ~0.5 s at rest, then tracked slowly) and
can be saved to NVS so the next boot starts corrected. The integrator is the
C core (`_openbricks_native.ImuYaw`) when the firmware or host extension has
it, the same algorithm in Python otherwise.

On the firmware the chip is the native `_openbricks_native.ICM45686` (the C
driver of firmware/native/icm45686.c on the ESP32's SPI): the 1 kHz hard tick
takes one burst per millisecond and integrates the heading in C, and a drive
base steering by this IMU reads that heading in C too (`native_heading()`), so
no Python runs in its loop. Elsewhere (the simulator, the tests) samples are
taken on a periodic `machine.Timer` (`timer_id`, by default the hardware timer
`openbricks.timers` assigns to the IMU, claimed there). With `timer_id=None` no
timer is taken and every heading()/gyro() call samples instead, for a caller
that polls fast enough (>= 10 Hz: longer gaps are not integrated, since the
motion in between is unknown).

SPI (datasheet DS-000577): first byte = register | 0x80 for a read; sensor
data at 0x00-0x0B little-endian, accel then gyro; -32768 means "no data".
"""

import struct
import time

from machine import SPI, Pin, Timer
from micropython import const

from openbricks import _native, pins, timers
from openbricks.interfaces import HeadingFrame

_ACCEL_DATA = const(0x00)
_PWR_MGMT0 = const(0x10)
_ACCEL_CONFIG0 = const(0x1B)
_GYRO_CONFIG0 = const(0x1C)
_WHO_AM_I = const(0x72)
_REG_MISC2 = const(0x7F)

_READ = const(0x80)
_SOFT_RESET = const(0x02)
_WHO_AM_I_VALUES = (0xE9, 0xEE)  # ICM-45686, ICM-45686-S
_PWR_GYRO_ACCEL_LOW_NOISE = const(0x0F)
# +-1000 dps covers any drive base spin with 32.8 LSB/dps; 1.6 kHz output, filtered by the chip.
_GYRO_CONFIG = const((2 << 4) | 5)
_GYRO_FS_DPS = 1000.0
_ACCEL_CONFIG = const((3 << 4) | 5)  # +-4 g, 1.6 kHz
_ACCEL_FS_G = 4.0
_NO_DATA = const(-32768)
_GYRO_STARTUP_MS = const(50)

_NVS_NAMESPACE = "openbricks"
_NVS_KEY = "icm45686_bias"

_EBUSY = const(16)
_ENODEV = const(19)

# Bias learning, matching the C core's defaults.
_STILL_BAND_DPS = 1.5
_SETTLE_US = const(500_000)
_TRACK_TAU_S = 10.0
_MAX_BIAS_DPS = 5.0
_MAX_GAP_US = const(100_000)
# Every this many timer samples the driver checks it still owns its pins (see _on_timer).
_OWNERSHIP_CHECK_SAMPLES = const(20)
_TIMER_ROLE = "ICM-45686 sampling"


class ICM45686(HeadingFrame):
    """ICM-45686 on SPI pins `sck`, `mosi`, `miso`, `cs` (GPIO numbers).

    `scale` turns gyro Z (counter-clockwise-positive about the chip's up axis)
    into clockwise-positive heading: -1.0 for a face-up breakout, +1.0 face
    down, and its magnitude can carry a measured gain correction.
    """

    HEADING_SOURCE = "ICM-45686"

    def __init__(
        self,
        sck,
        mosi,
        miso,
        cs,
        hz=8_000_000,
        mode=3,
        scale=-1.0,
        timer_id=timers.IMU,
        sample_hz=200,
        spi_id=1,
    ):
        if scale == 0:
            raise ValueError("scale must be non-zero: -1.0 for a face-up ICM-45686, +1.0 face-down")
        if mode not in (0, 1, 2, 3):
            raise ValueError("SPI mode is 0..3, got %r" % (mode,))
        pins.claim(sck, "ICM-45686 SPI SCK", owner=self)
        pins.claim(mosi, "ICM-45686 SPI MOSI", owner=self)
        pins.claim(miso, "ICM-45686 SPI MISO", owner=self, output=False)
        pins.claim(cs, "ICM-45686 SPI CS", owner=self)
        self._wiring = "SCK=%d MOSI=%d MISO=%d CS=%d" % (sck, mosi, miso, cs)
        self._pins = (sck, mosi, miso, cs)
        self._timer = None
        self._timer_id = timer_id
        self._chip = None
        hub_chip = _hub_chip()
        if hub_chip is not None:
            self._open_on_the_hard_tick(hub_chip, sck, mosi, miso, cs, hz, mode, scale, spi_id)
            return
        self._cs = Pin(cs, Pin.OUT, value=1)
        self._spi = SPI(
            spi_id,
            baudrate=hz,
            polarity=mode >> 1,
            phase=mode & 1,
            sck=Pin(sck),
            mosi=Pin(mosi),
            miso=Pin(miso),
        )
        self._tx = bytearray(13)
        self._rx = bytearray(13)
        self._gyro = (0.0, 0.0, 0.0)
        self._accel = (0.0, 0.0, 0.0)
        self._reads_ok = 0
        self._read_errors = 0
        self._configured = False
        self._clock_us = 0
        self._last_ticks_us = None
        self._configure()
        self._yaw = _new_integrator(scale)
        self._seed_from_nvs()
        self._until_ownership_check = _OWNERSHIP_CHECK_SAMPLES
        if timer_id is not None:
            timers.claim(timer_id, _TIMER_ROLE, "pass timer_id= to ICM45686() (None samples on each read)")
            self._timer = Timer(timer_id)
            self._timer.init(mode=Timer.PERIODIC, period=max(1, 1000 // sample_hz), callback=self._on_timer)

    def _open_on_the_hard_tick(self, hub_chip, sck, mosi, miso, cs, hz, mode, scale, spi_id):
        """The firmware's C driver: it owns the SPI device and the hard tick samples it."""
        _close_leftover_chips()
        try:
            self._chip = hub_chip(
                sck=sck, mosi=mosi, miso=miso, cs=cs, hz=hz, mode=mode, spi_id=spi_id, scale=scale
            )
        except Exception:
            for pin in self._pins:
                pins.release(pin, self)
            raise
        _ON_THE_HARD_TICK.append(self)
        self._configured = True
        self._yaw = self._chip
        self._seed_from_nvs()

    def _live(self):
        owner = pins.owner_of(self._pins[3])
        return owner is not None and owner[1] is self

    def native_heading(self):
        """The heading source a drive base reads in C with no Python call (the firmware's hard-tick
        driver), or None where this driver samples in Python."""
        return self._chip

    # -- SPI ----------------------------------------------------------------------------------

    def _write(self, reg, value):
        self._cs.value(0)
        try:
            self._spi.write(bytes((reg, value)))
        finally:
            self._cs.value(1)

    def _read(self, reg, n):
        tx = bytearray(n + 1)
        tx[0] = reg | _READ
        rx = bytearray(n + 1)
        self._cs.value(0)
        try:
            self._spi.write_readinto(tx, rx)
        finally:
            self._cs.value(1)
        return rx[1:]

    def _configure(self):
        self._write(_REG_MISC2, _SOFT_RESET)
        time.sleep_ms(2)
        who = self._read(_WHO_AM_I, 1)[0]
        if who not in _WHO_AM_I_VALUES:
            hint = "nothing drives MISO: check wiring and 3V3" if who in (0x00, 0xFF) else "another chip?"
            raise OSError(
                _ENODEV,
                "no ICM-45686 on SPI (%s): WHO_AM_I (0x72) reads 0x%02X, expected 0xE9; %s"
                % (self._wiring, who, hint),
            )
        self._write(_GYRO_CONFIG0, _GYRO_CONFIG)
        self._write(_ACCEL_CONFIG0, _ACCEL_CONFIG)
        self._write(_PWR_MGMT0, _PWR_GYRO_ACCEL_LOW_NOISE)
        time.sleep_ms(_GYRO_STARTUP_MS)
        self._configured = True

    # -- sampling -----------------------------------------------------------------------------

    def _on_timer(self, timer):
        # The launcher takes a finished program's pins back; its IMU is garbage from then on, but
        # a running timer would keep it sampling (and loading the scheduler) until the next reset.
        self._until_ownership_check -= 1
        if self._until_ownership_check <= 0:
            self._until_ownership_check = _OWNERSHIP_CHECK_SAMPLES
            owner = pins.owner_of(self._pins[3])
            if owner is None or owner[1] is not self:
                timer.deinit()
                self._timer = None
                timers.release(self._timer_id, _TIMER_ROLE)
                return
        self._sample()

    def _sample(self):
        """Read one accel+gyro burst and feed gyro Z to the heading integrator."""
        tx, rx = self._tx, self._rx
        tx[0] = _ACCEL_DATA | _READ
        self._cs.value(0)
        try:
            self._spi.write_readinto(tx, rx)
        finally:
            self._cs.value(1)
        now = time.ticks_us()
        ax, ay, az, gx, gy, gz = struct.unpack_from("<6h", rx, 1)
        if gz == _NO_DATA or ax == _NO_DATA:
            self._read_errors += 1
            return
        self._reads_ok += 1
        if self._last_ticks_us is not None:
            self._clock_us += time.ticks_diff(now, self._last_ticks_us)
        self._last_ticks_us = now
        k = _GYRO_FS_DPS / 32768.0
        self._gyro = (gx * k, gy * k, gz * k)
        g = _ACCEL_FS_G / 32768.0
        self._accel = (ax * g, ay * g, az * g)
        # A 32-bit microsecond clock that never jumps at the ticks_us() wrap (2**30 on MicroPython).
        self._yaw.update(self._gyro[2], self._clock_us & 0xFFFFFFFF)

    def _fresh(self):
        if self._timer is None and self._chip is None:
            self._sample()

    # -- the IMU surface ------------------------------------------------------------------------

    def heading(self):
        """Continuous body heading in degrees, clockwise-positive, unwrapped (multi-turn)."""
        self._fresh()
        return self._yaw.heading()

    def reset_heading(self, angle=0):
        """Make the current pose read `angle` degrees; the learned bias is kept.

        Refused while a drive base steers by this gyro: its controller holds a target in the
        current frame, and moving the frame under it makes the next move veer.
        """
        self._check_heading_free()
        self._yaw.reset_heading(angle)

    def gyro(self):
        """(x, y, z) rates in deg/s from the latest sample, in the chip's frame."""
        if self._chip is not None:
            return self._chip.gyro()
        self._fresh()
        return self._gyro

    def acceleration(self):
        """(x, y, z) in g from the latest sample, in the chip's frame."""
        if self._chip is not None:
            return self._chip.acceleration()
        self._fresh()
        return self._accel

    def calibrated(self):
        """True once the gyro bias is known: ~0.5 s of stillness since boot, or a saved calibration."""
        return self._yaw.calibrated()

    def save_calibration(self):
        """Persist the learned gyro bias to NVS so the next construction starts corrected."""
        if not self._yaw.calibrated():
            raise OSError(
                _EBUSY,
                "ICM-45686 has no gyro bias to save yet: keep the robot still until calibrated() is True",
            )
        import esp32

        nvs = esp32.NVS(_NVS_NAMESPACE)
        nvs.set_blob(_NVS_KEY, struct.pack("<f", self._yaw.bias()))
        nvs.commit()

    def stats(self):
        """(reads_ok, read_errors, configured): sampling health."""
        if self._chip is not None:
            return self._chip.stats()
        return (self._reads_ok, self._read_errors, self._configured)

    def close(self):
        """Stop background sampling and hand back the timer (or the SPI device) and the four GPIOs."""
        if self._chip is not None:
            self._chip.close()
            if self in _ON_THE_HARD_TICK:
                _ON_THE_HARD_TICK.remove(self)
        if self._timer is not None:
            self._timer.deinit()
            self._timer = None
            timers.release(self._timer_id, _TIMER_ROLE)
        for pin in self._pins:
            pins.release(pin, self)

    def _seed_from_nvs(self):
        try:
            import esp32

            buf = bytearray(4)
            if esp32.NVS(_NVS_NAMESPACE).get_blob(_NVS_KEY, buf) != 4:
                return
        except (ImportError, OSError):
            return  # nothing stored yet: learn at rest instead
        try:
            self._yaw.seed_bias(struct.unpack("<f", buf)[0])
        except ValueError:
            pass  # implausible stored value: ignore it and learn at rest, as with none

    def __repr__(self):
        return "ICM45686(%s)" % self._wiring


# Drivers whose chip the hard tick samples. A finished program's is closed when the next one builds an
# IMU: the launcher takes its pins back, but its SPI device and hard-tick slot stay taken until then.
_ON_THE_HARD_TICK = []


def _close_leftover_chips():
    for driver in list(_ON_THE_HARD_TICK):
        if not driver._live():
            driver._chip.close()
            _ON_THE_HARD_TICK.remove(driver)


def _hub_chip():
    """The firmware's native ICM45686 when this build reads the SPI with it (the ESP32 image), else None."""
    chip = _native.get("ICM45686")
    return chip if chip is not None and chip.HARDWARE else None


def _new_integrator(scale):
    imu_yaw = _native.get("ImuYaw")
    if imu_yaw is None:
        return _YawIntegrator(scale)
    return imu_yaw(scale=scale)


class _YawIntegrator:
    """Gyro-Z heading with the bias learned in still windows: the C core's algorithm, for
    interpreters without it. Every sample of a window must stay within a band of the reference
    (the bias once known, else the window's first sample); a full window locks the bias at boot
    and nudges it through a slow low-pass later; heading drift accrued during the locking window
    is taken back out."""

    def __init__(self, scale):
        self._scale = scale
        self._heading = 0.0
        self._rate = 0.0
        self._bias = 0.0
        self._calibrated = False
        self._last_us = None
        self._restart_window(None)

    def _restart_window(self, gyro):
        self._window_ref = self._bias if self._calibrated else gyro
        self._window_sum = 0.0  # integral of raw rate, deg
        self._window_us = 0

    def update(self, gyro_z_dps, now_us):
        last = self._last_us
        self._last_us = now_us
        if last is None:
            self._restart_window(gyro_z_dps)
            return
        dt_us = (now_us - last) & 0xFFFFFFFF
        if dt_us == 0:
            return
        if dt_us > _MAX_GAP_US:
            self._restart_window(gyro_z_dps)
            return
        dt = dt_us / 1_000_000
        self._rate = self._scale * (gyro_z_dps - self._bias)
        self._heading += self._rate * dt
        ref = self._window_ref
        if ref is None or abs(gyro_z_dps - ref) > _STILL_BAND_DPS:
            self._restart_window(gyro_z_dps)
            return
        self._window_sum += gyro_z_dps * dt
        self._window_us += dt_us
        if self._window_us < _SETTLE_US:
            return
        mean = self._window_sum * 1_000_000 / self._window_us
        if abs(mean) <= _MAX_BIAS_DPS:
            if self._calibrated:
                self._bias += (mean - self._bias) * min(1.0, self._window_us / 1_000_000 / _TRACK_TAU_S)
            else:
                # The window integrated (mean - old bias) as if it were rotation: it was standing still.
                self._heading -= self._scale * (mean - self._bias) * self._window_us / 1_000_000
                self._bias = mean
                self._calibrated = True
        self._restart_window(gyro_z_dps)

    def heading(self):
        return self._heading

    def rate(self):
        return self._rate

    def bias(self):
        return self._bias

    def calibrated(self):
        return self._calibrated

    def reset_heading(self, heading=0.0):
        self._heading = float(heading)

    def seed_bias(self, bias_dps):
        if not (bias_dps == bias_dps and abs(bias_dps) <= _MAX_BIAS_DPS):  # NaN fails the first test
            raise ValueError(
                "seed_bias(%r): a gyro bias must be finite and within +-%s deg/s" % (bias_dps, _MAX_BIAS_DPS)
            )
        self._bias = bias_dps
        self._calibrated = True
        self._restart_window(None)
