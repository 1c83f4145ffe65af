"""DriveBase: two motors driven as one chassis, in millimetres and body degrees (manual 7.1).

There is one drive base class and no Python control loop. The controller is the native 2-DOF
drivebase core (`_openbricks_native.DriveBase`), subscribed to `motor_process` and ticked at 1 kHz
below the user program: by the firmware's hard tick on the hub, by the physics step in the
simulator, by a machine.Timer where nothing else ticks (see `tick`). This class arms its commands,
supervises blocking moves and turns the core's faults into errors that name the motor.

Sign conventions (Pybricks): positive distance is forward, positive turn is clockwise seen from
above, the sign of a curve's radius picks the travel direction. Speeds in `settings()` are in
wheel-deg/s and accelerations in wheel-deg/s^2, as the native core takes them.
"""

import math
import time

from micropython import const

from openbricks import _native, estop
from openbricks.parameters import then_name
from openbricks.robotics import tick
from openbricks.robotics.wheels import pair_for

_POLL_MS = const(10)
# stop(wait=True): both wheels slower than this (wheel-deg/s) for a few polls in a row is "at rest".
_REST_DPS = 3.0
_REST_POLLS = const(3)
_SETTLE_TIMEOUT_MS = const(5000)
# A blocking move that makes no measurable progress for this long is stuck (a wall, a jammed wheel).
_STALL_MS = const(2000)
_STALL_DPS = 2.0
# Open loop has no speed sensor: wheel-deg/s become duty through the motor's no-load speed.
DEFAULT_NO_LOAD_DPS = 1000.0


class DriveBase:
    """A two-wheel differential drive robot: two motors, one chassis.

    `left` and `right` are two motors of one family: serial-bus servos (adopted onto the bus
    engine), encoder motors (on the native controller), or open-loop bridges (drive()/stop() only).
    `imu` is a heading source for use_gyro(True). `drive` selects how adopted serial-bus wheels are
    actuated: "duty" (default: open-loop duty, every layer of the drive loop is openbricks code) or
    "wheel" (the servos' own speed controller in wheel mode, asked for the controller's share of
    each motor's max_dps).
    """

    def __init__(self, left, right, wheel_diameter_mm, axle_track_mm, imu=None, drive="duty"):
        for name, value in (("wheel_diameter_mm", wheel_diameter_mm), ("axle_track_mm", axle_track_mm)):
            if (
                not isinstance(value, (int, float))
                or not value > 0
                or value != value
                or value == float("inf")
            ):
                raise ValueError("DriveBase(%s=%r): give the measured size in mm, > 0" % (name, value))
        if drive not in ("duty", "wheel"):
            raise ValueError(
                "DriveBase(drive=%r): give 'duty' (the default: the engine closes the loop over raw duty) "
                "or 'wheel' (the servos' own speed controller)" % (drive,)
            )
        if imu is not None and not callable(getattr(imu, "heading", None)):
            raise TypeError("DriveBase(imu=%r): an IMU needs a heading() method" % (imu,))
        self.left = left
        self.right = right
        self.wheel_diameter_mm = float(wheel_diameter_mm)
        self.axle_track_mm = float(axle_track_mm)
        self.imu = imu
        self._pair = pair_for(left, right, drive)
        self._gyro = False
        self._heading = _UnwrappedHeading(imu) if imu is not None else None
        self._controller = None
        if self._pair.closed_loop:
            kwargs = self._pair.controller_io()
            if self._heading is not None:
                # An IMU the firmware samples in C is read in C, so the controller stays on the hard
                # tick; any other heading() is called from Python (continuous across +-180).
                native_heading = getattr(imu, "native_heading", None)
                source = native_heading() if native_heading is not None else None
                kwargs["heading"] = source if source is not None else self._heading
            self._controller = _native.DriveBase(self.wheel_diameter_mm, self.axle_track_mm, **kwargs)
            tick.ensure_running()
        # An open-loop pair has no controller to hold the settings; they are kept for settings() to
        # report, and apply to nothing until the motors have feedback.
        self._open_settings = [360.0, 360.0, 1500.0, 1500.0]
        estop.on_engage(self._halt)

    # --- helpers -------------------------------------------------------------------------------

    def _closed(self, what):
        """The native controller; RuntimeError naming the motors when the pair has no feedback."""
        if self._controller is None:
            raise RuntimeError(
                "DriveBase.%s needs wheel feedback and %s / %s are open-loop motors; use drive() and "
                "stop(), or motors with encoders (JGB37Motor) or serial-bus servos (ST3032Motor)"
                % (what, type(self.left).__name__, type(self.right).__name__)
            )
        return self._controller

    def _command(self, what):
        """Everything a motion command does before it arms the controller."""
        estop.check("DriveBase." + what)
        controller = self._closed(what)
        self._pair.check()
        self._pair.take(controller)
        return controller

    def _halt(self):
        """The e-stop's halt: both wheels released at once."""
        if self._controller is not None:
            self._controller.stop("coast")
        else:
            self.left.coast()
            self.right.coast()

    def _raise_if_halted(self):
        """Raise the controller's watchdog halt as the error that names the silent motor (or gyro)."""
        sides = self._controller.fault()
        if sides is None:
            return
        try:
            self._controller.done()  # raises the core's own description of the halt
        except OSError as native_error:
            raise self._pair.fault_error(sides, native_error) from None

    def _wheel_speeds_dps(self):
        """Measured (left, right) wheel speeds, wheel-deg/s, from the controller's observer."""
        _distance, speed_mm_s, _angle, rate_dps = self._controller.state()
        sum_dps = speed_mm_s * 360.0 / (math.pi * self.wheel_diameter_mm)
        diff_dps = rate_dps * self.axle_track_mm / self.wheel_diameter_mm
        return sum_dps + diff_dps, sum_dps - diff_dps

    def _wait(self, what):
        """Block until the armed move is done; e-stop, a silent wheel and a stuck robot all raise."""
        controller = self._controller
        still_since = None
        while True:
            if estop.engaged():
                estop.check("DriveBase." + what)
            if controller.fault() is not None:
                self._raise_if_halted()
            if controller.done():
                return
            time.sleep_ms(_POLL_MS)
            left, right = self._wheel_speeds_dps()
            now = time.ticks_ms()
            if abs(left) > _STALL_DPS or abs(right) > _STALL_DPS:
                still_since = None
            elif still_since is None:
                still_since = now
            elif time.ticks_diff(now, still_since) >= _STALL_MS and not controller.done():
                controller.stop("coast")
                distance_mm, _speed, angle_deg, _rate = controller.state()
                raise RuntimeError(
                    "DriveBase.%s is stuck: no wheel has moved for %d ms and the move is not done "
                    "(at %.1f mm, %.1f deg since reset()); both wheels were released. Is the robot "
                    "against an obstacle or a wheel jammed?" % (what, _STALL_MS, distance_mm, angle_deg)
                )

    def _move(self, what, arm, then, wait):
        name = then_name(then)
        controller = self._command(what)
        arm(controller, name)
        if wait:
            self._wait(what)

    # --- moves ---------------------------------------------------------------------------------

    def straight(self, distance_mm, then="coast", wait=True):
        """Drive `distance_mm` forward (negative: backward), heading held.

        then= "coast" (alias "stop"), "brake", "hold", or "continue" (end at cruise speed and keep
        it). wait=False returns at once; poll done().
        """
        self._move("straight", lambda c, name: c.straight(distance_mm, then=name), then, wait)

    def turn(self, angle_deg, then="coast", wait=True):
        """Turn in place by `angle_deg` of body heading, clockwise positive.

        then="continue" has no speed to carry on a spot turn: it ends at rest, holding the heading.
        """
        self._move("turn", lambda c, name: c.turn(angle_deg, then=name), then, wait)

    def curve(self, radius, angle, then="coast", wait=True):
        """Drive along a circle of abs(`radius`) mm, turning the heading by `angle` degrees.

        Positive angle curves right; a negative radius drives the arc backward; radius 0 turns in
        place. The outer wheel never exceeds the straight_speed setting.
        """
        self._move("curve", lambda c, name: c.curve(radius, angle, then=name), then, wait)

    def drive(self, speed_mm_s, turn_rate_dps):
        """Drive at `speed_mm_s` forward and `turn_rate_dps` (clockwise positive) until told otherwise.

        Speed changes ramp at the acceleration setting. On an open-loop pair the speeds are mapped
        straight to duty, with no ramp and no feedback.
        """
        if self._controller is None:
            wheel_dps = speed_mm_s * 360.0 / (math.pi * self.wheel_diameter_mm)
            diff_dps = turn_rate_dps * self.axle_track_mm / self.wheel_diameter_mm
            self._open_loop_wheels("drive", wheel_dps + diff_dps, wheel_dps - diff_dps)
            return
        self._command("drive").drive(speed_mm_s, turn_rate_dps)

    def move_wheels(self, left_wheel_speed, right_wheel_speed):
        """Run each wheel at its own speed (wheel-deg/s, positive = forward on both sides).

        Continuous like drive(); verifies both wheels first, so a loop of move_wheels() calls notices a
        wheel that stopped answering.
        """
        if self._controller is None:
            self._open_loop_wheels("move_wheels", left_wheel_speed, right_wheel_speed)
            return
        self._command("move_wheels").move_wheels(left_wheel_speed, right_wheel_speed)

    def _open_loop_wheels(self, what, left_dps, right_dps):
        estop.check("DriveBase." + what)
        for motor, dps in ((self.left, left_dps), (self.right, right_dps)):
            no_load_dps = getattr(motor, "no_load_dps", None) or DEFAULT_NO_LOAD_DPS
            motor.dc(max(-100.0, min(100.0, 100.0 * dps / no_load_dps)))

    def stop(self, then="coast", wait=False):
        """Halt both wheels together: "coast" releases them now, "brake" / "hold" decelerate at the
        acceleration setting and then brake or hold where the robot came to rest.

        Returns at once unless wait=True, which blocks until both wheels' measured speeds read ~0
        (RuntimeError naming them if that takes over 5 s; ValueError on an open-loop pair, which
        has no measured speed, after stopping it).
        """
        name = then_name(then)
        if self._controller is None:
            if name == "hold":
                raise NotImplementedError(
                    "stop(then='hold') needs position feedback and %s / %s are open-loop motors; "
                    "use 'coast' or 'brake'" % (type(self.left).__name__, type(self.right).__name__)
                )
            for motor in (self.left, self.right):
                if name == "brake":
                    motor.brake()
                else:
                    motor.coast()
            if wait:
                raise ValueError(
                    "stop(wait=True) waits for the measured wheel speeds to reach ~0, and open-loop "
                    "motors have no speed feedback; the wheels were stopped, call stop() without wait"
                )
            return
        if name == "continue":
            name = "hold"  # a stop has no cruise to carry
        self._pair.take(self._controller)
        self._controller.stop(name)
        if wait:
            self._wait_at_rest()

    def _wait_at_rest(self):
        start = time.ticks_ms()
        calm = 0
        while True:
            self._raise_if_halted()
            left, right = self._wheel_speeds_dps()
            calm = calm + 1 if abs(left) < _REST_DPS and abs(right) < _REST_DPS else 0
            if calm >= _REST_POLLS:
                return
            if time.ticks_diff(time.ticks_ms(), start) >= _SETTLE_TIMEOUT_MS:
                raise RuntimeError(
                    "DriveBase.stop(wait=True): the wheels are still moving %d ms after the stop "
                    "(left %.1f, right %.1f wheel-deg/s); a stopped robot that keeps moving is being "
                    "pushed, is rolling downhill, or a wheel is not under control"
                    % (_SETTLE_TIMEOUT_MS, left, right)
                )
            time.sleep_ms(_POLL_MS)

    def done(self):
        """True when no move is pending or the last one reached its target (then= applied).

        OSError naming the motor if the controller halted because a wheel (or the gyro) went silent.
        """
        if self._controller is None:
            return True
        self._raise_if_halted()
        return self._controller.done()

    # --- settings and state --------------------------------------------------------------------

    def settings(self, straight_speed=None, turn_rate=None, acceleration=None, turn_acceleration=None):
        """Cruise speeds (wheel-deg/s) and accelerations (wheel-deg/s^2) for the moves that follow.

        With no arguments, returns (straight_speed, turn_rate, acceleration, turn_acceleration).
        turn_acceleration is the serial-bus drive base's own ramp for turn(); on encoder motors
        turns ramp at `acceleration`, so passing it there raises.
        """
        if turn_acceleration is not None and self._pair.kind != "serial-bus":
            raise ValueError(
                "settings(turn_acceleration=...) applies to serial-bus drive bases only, and these are "
                "%s motors (on encoder motors turn() ramps at `acceleration`)" % self._pair.kind
            )
        values = (straight_speed, turn_rate, acceleration, turn_acceleration)
        for i, name in enumerate(("straight_speed", "turn_rate", "acceleration", "turn_acceleration")):
            value = values[i]
            if value is not None and (not isinstance(value, (int, float)) or not 0 < value < float("inf")):
                unit = "wheel-deg/s" if "speed" in name or "rate" in name else "wheel-deg/s^2"
                raise ValueError("settings(%s=%r): give a positive number in %s" % (name, value, unit))
        if self._controller is None:
            current = self._open_settings
            if all(value is None for value in values):
                return tuple(current)
            for i, value in enumerate(values):
                if value is not None:
                    current[i] = float(value)
            return None
        if all(value is None for value in values):
            return self._controller.settings()
        if acceleration is not None and self._pair.kind != "serial-bus":
            turn_acceleration = acceleration  # one ramp for both on encoder motors
        self._controller.settings(
            straight_speed=straight_speed,
            turn_rate=turn_rate,
            acceleration=acceleration,
            turn_acceleration=turn_acceleration,
        )
        return None

    def distance(self):
        """Distance driven since the last reset(), mm (the average of both wheels)."""
        return self._closed("distance()").distance()

    def angle(self):
        """Body heading since the last reset(), degrees clockwise (gyro or encoders, as steered)."""
        return self._closed("angle()").angle()

    def state(self):
        """(distance_mm, drive_speed_mm_s, angle_deg, turn_rate_dps), measured (Pybricks state())."""
        return self._closed("state()").state()

    # --- heading frame -------------------------------------------------------------------------

    def use_gyro(self, enable):
        """Steer by the IMU's measured body rotation (True) or by the encoder difference (False)."""
        controller = self._closed("use_gyro()")
        if not enable:
            controller.use_gyro(False)
            if self._gyro:
                self._unlock_imu()
            self._gyro = False
            return
        if self.imu is None:
            raise ValueError("use_gyro(True) needs an IMU: construct the DriveBase with imu=<your IMU>")
        if not self._gyro:
            lock = getattr(self.imu, "lock_heading", None)
            if lock is not None:
                lock(self)
            self._heading.restart()
            controller.use_gyro(True)
            self._gyro = True

    def _unlock_imu(self):
        unlock = getattr(self.imu, "unlock_heading", None)
        if unlock is not None:
            unlock(self)

    def reset(self):
        """Make the robot's current pose distance 0 and heading 0, for this drive base and for
        imu.heading() together. Call it between moves: it raises while a move is in progress."""
        if self._controller is None:
            if self.imu is not None:
                self.imu.reset_heading(0)
            return
        controller = self._controller
        self._raise_if_halted()
        if not controller.done():
            raise RuntimeError(
                "DriveBase.reset() refused: a move is in progress; stop() or wait for done() first"
            )
        if not self._gyro:
            controller.reset()
            if self.imu is not None:
                self.imu.reset_heading(0)
                self._heading.restart()
            return
        # Hand the heading to the encoders, zero them, zero the IMU, and hand it back: the gyro frame
        # re-anchors at its first reading, so the held heading does not jump and both read 0.
        controller.use_gyro(False)
        controller.reset()
        self._unlock_imu()
        try:
            self.imu.reset_heading(0)
        finally:
            self._heading.restart()
            lock = getattr(self.imu, "lock_heading", None)
            if lock is not None:
                lock(self)
            controller.use_gyro(True)

    def check_motors(self):
        """Raise OSError naming the motor (side, bus id, slot, UART and pins) if a wheel has stopped
        answering the bus. Serial-bus wheels are also checked at construction and before every move."""
        self._pair.check()

    def close(self):
        """Stop driving and leave the wheels to their motors (the scheduler forgets the controller)."""
        self._halt()
        if self._controller is not None:
            self._pair.release(self._controller)
        if self._gyro:
            self._unlock_imu()
            self._gyro = False
        estop.remove(self._halt)

    def __repr__(self):
        return "DriveBase(%s %s + %s, wheel %g mm, track %g mm)" % (
            self._pair.kind,
            type(self.left).__name__,
            type(self.right).__name__,
            self.wheel_diameter_mm,
            self.axle_track_mm,
        )


class _UnwrappedHeading:
    """The IMU's heading as the controller needs it: continuous across +-180 (a BNO055 wraps), and
    None for a missed sample (a bus error), which the controller bridges with the encoders."""

    def __init__(self, imu):
        self._imu = imu
        self.restart()

    def restart(self):
        self._last = None
        self._total = 0.0

    def __call__(self):
        try:
            raw = self._imu.heading()
        except OSError:
            return None
        if raw is None:
            return None
        if self._last is None:
            self._total = raw
        else:
            step = (raw - self._last + 180.0) % 360.0 - 180.0
            self._total += step
        self._last = raw
        return self._total
