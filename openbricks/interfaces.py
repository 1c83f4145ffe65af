"""The contracts every driver implements; higher layers (robotics, user code) see only these.

MicroPython has no `abc` or `typing.Protocol`, so these are plain base classes:
a method a driver cannot provide raises NotImplementedError naming the driver
and the method, and the Pybricks conveniences that can be expressed with the
primitives (run, stop, run_time, run_target, run_until_stalled) are written
once here so every motor gets the same behaviour.

Units follow the manual: duty -100..100 percent, speeds in degrees per second
at the output shaft, angles in degrees, torque in mNm, times in milliseconds.
"""

import time

from openbricks.parameters import Stop, then_name

_EBUSY = 16  # errno EBUSY, as MicroPython's OSError carries it


def _unsupported(obj, method, hint=""):
    message = "%s does not support %s()" % (type(obj).__name__, method)
    if hint:
        message += "; " + hint
    return NotImplementedError(message)


class Motor:
    """A bidirectional motor, from an open-loop H-bridge to a serial-bus servo.

    Method names and semantics follow the Pybricks Motor API: `run(speed)` is
    closed-loop deg/s and `dc(duty)` is raw duty; `run_speed` and `coast` are
    the openbricks names the concrete conveniences build on.
    """

    # How long stalled() must read True before run_until_stalled believes it:
    # a motor starting from rest briefly looks "pushing hard, not moving".
    STALL_CONFIRM_MS = 200
    _STALL_POLL_MS = 10

    # --- primitives each driver provides -------------------------------------

    def dc(self, duty):
        """Drive at a fixed duty cycle (-100..100), open loop. Non-blocking."""
        raise _unsupported(self, "dc")

    def brake(self):
        """Stop with active braking."""
        raise _unsupported(self, "brake")

    def coast(self):
        """Cut drive power; the shaft free-wheels."""
        raise _unsupported(self, "coast")

    def hold(self):
        """Stop and actively hold the current shaft angle."""
        raise _unsupported(self, "hold", "it has no position control; use brake() or coast()")

    def angle(self):
        """Shaft angle in degrees, in the reset_angle() frame."""
        raise _unsupported(self, "angle", "it has no encoder")

    def reset_angle(self, angle=0):
        """Declare the current shaft angle to be `angle` degrees."""
        raise _unsupported(self, "reset_angle", "it has no encoder")

    def run_speed(self, deg_per_s):
        """Hold `deg_per_s` at the shaft, closed loop. Non-blocking."""
        raise _unsupported(self, "run_speed", "it has no speed feedback; use dc(duty)")

    def run_angle(self, deg_per_s, target_angle, wait=True, then=Stop.COAST):
        """Rotate by `target_angle` degrees (relative; sign picks the direction) at up to `deg_per_s`.

        With wait=False it returns at once and the caller polls done().
        """
        raise _unsupported(self, "run_angle", "it has no encoder")

    def done(self):
        """True unless a run_angle(wait=False) move is still on its way."""
        return True

    def speed(self):
        """Measured shaft speed in deg/s."""
        raise _unsupported(self, "speed", "it has no speed feedback")

    def load(self):
        """Estimated shaft torque in mNm."""
        raise _unsupported(self, "load", "it has no load feedback")

    def stalled(self):
        """True while the motor pushes as hard as it may but cannot reach its commanded speed."""
        raise _unsupported(self, "stalled", "it has no load feedback")

    def _duty_limit_push(self, limit_pct):
        """Cap the output at `limit_pct` percent until _duty_limit_pop()."""
        raise _unsupported(self, "run_until_stalled(duty_limit=...)", "call it without duty_limit")

    def _duty_limit_pop(self):
        """Restore the output cap that was in force before _duty_limit_push()."""

    # --- Pybricks conveniences built on the primitives -----------------------

    def run(self, speed):
        """Run at `speed` deg/s, closed loop (Pybricks Motor.run). Non-blocking."""
        self.run_speed(speed)

    def stop(self):
        """Stop and free-wheel (Pybricks Motor.stop)."""
        self.coast()

    def _finish(self, then):
        """Apply a `then=` end state; "continue" leaves the motor doing what it was doing."""
        name = then_name(then)
        if name == Stop.COAST:
            self.coast()
        elif name == Stop.BRAKE:
            self.brake()
        elif name == Stop.HOLD:
            self.hold()

    def run_time(self, speed, time_ms, then=Stop.HOLD, wait=True):
        """Run at `speed` deg/s for `time_ms`, then end with `then` (Pybricks Motor.run_time)."""
        then_name(then)
        if not wait:
            raise ValueError(
                "run_time(wait=False) is not supported: no background timer is kept for it; "
                "call run(speed), then stop it yourself after time_ms"
            )
        if time_ms < 0:
            raise ValueError("run_time(time_ms=%r): the duration must be >= 0 ms" % (time_ms,))
        self.run(speed)
        time.sleep_ms(int(time_ms))
        self._finish(then)

    def run_target(self, speed, target_angle, then=Stop.HOLD, wait=True):
        """Run to the absolute `target_angle` (reset_angle frame) at up to `speed` deg/s."""
        then_name(then)
        here = self.angle()
        if here is None:
            raise OSError("%s: cannot read the shaft angle to plan run_target()" % type(self).__name__)
        self.run_angle(abs(speed), target_angle - here, wait=wait, then=then)

    def run_until_stalled(self, speed, then=Stop.COAST, duty_limit=None):
        """Run at `speed` deg/s until the shaft stalls, end with `then`, return the angle there.

        `duty_limit` (0 < percent <= 100) caps the torque for the run so a
        gripper or arm homes gently against its end stop; the previous cap is
        restored afterwards whether the run stalled or was interrupted.
        """
        then_name(then)
        if duty_limit is not None and not 0 < duty_limit <= 100:
            raise ValueError("duty_limit=%r: give a percentage with 0 < duty_limit <= 100" % (duty_limit,))
        if duty_limit is not None:
            self._duty_limit_push(duty_limit)
        try:
            self.run(speed)
            stalled_since = None
            while True:
                time.sleep_ms(self._STALL_POLL_MS)
                now = time.ticks_ms()
                if not self.stalled():
                    stalled_since = None
                elif stalled_since is None:
                    stalled_since = now
                elif time.ticks_diff(now, stalled_since) >= self.STALL_CONFIRM_MS:
                    break
            stall_angle = self.angle()
            self._finish(then)
        finally:
            if duty_limit is not None:
                self._duty_limit_pop()
        return stall_angle


class Servo:
    """A position-controlled servo, addressed by absolute angle."""

    def move_to(self, angle_deg, speed=None, wait=True):
        """Move to `angle_deg` degrees."""
        raise _unsupported(self, "move_to")

    def angle(self):
        """Current angle in degrees."""
        raise _unsupported(self, "angle")


class IMU:
    """A 3-axis inertial unit: degrees, degrees per second, metres per second squared."""

    def heading(self):
        """Heading (yaw) in degrees, wrapped to [-180, 180)."""
        raise _unsupported(self, "heading")

    def reset_heading(self, angle=0):
        """Declare the current heading to be `angle` degrees."""
        raise _unsupported(self, "reset_heading")

    def angular_velocity(self):
        """(wx, wy, wz) in deg/s."""
        raise _unsupported(self, "angular_velocity")

    def acceleration(self):
        """(ax, ay, az) in m/s^2."""
        raise _unsupported(self, "acceleration")


class HeadingFrame:
    """The claim a drive base takes on an IMU's heading frame while it steers by it.

    While claimed, reset_heading() must refuse (Pybricks: "can't reset heading while gyro in use"):
    the drive base's controller holds a target in the current frame, and moving the frame under it
    makes the next move veer. The drive base's own reset() re-zeroes both together. A driver mixes
    this in, names itself in HEADING_SOURCE, and calls _check_heading_free() in reset_heading().
    """

    HEADING_SOURCE = "IMU"
    _steering_owner = None

    def lock_heading(self, owner):
        """Called by a drive base when it starts steering by this IMU (use_gyro(True))."""
        if self._steering_owner is not None and self._steering_owner is not owner:
            raise OSError(
                _EBUSY,
                "this %s already steers a %s; one IMU can hold one drive base's heading"
                % (self.HEADING_SOURCE, type(self._steering_owner).__name__),
            )
        self._steering_owner = owner

    def unlock_heading(self, owner):
        """Release the frame taken by lock_heading(owner) (use_gyro(False), or around db.reset())."""
        if self._steering_owner is owner:
            self._steering_owner = None

    def heading_locked_by(self):
        """The drive base steering by this IMU, or None."""
        return self._steering_owner

    def _check_heading_free(self):
        if self._steering_owner is not None:
            raise OSError(
                _EBUSY,
                "can't reset heading while gyro in use: %s steers by this %s; use its reset() "
                "(re-zeroes the drive base and this IMU together) or use_gyro(False) first"
                % (type(self._steering_owner).__name__, self.HEADING_SOURCE),
            )


class ColorSensor:
    """An RGB colour sensor."""

    def rgb(self):
        """(r, g, b), each 0..255."""
        raise _unsupported(self, "rgb")

    def ambient(self):
        """Clear-channel intensity, 0..100."""
        raise _unsupported(self, "ambient")

    def reflection(self):
        """Reflected light, 0..100 (Pybricks' ColorSensor.reflection()).

        A colour breakout lights the surface with its own white LED (manual 2.4.1: leave it on), so
        what its clear channel sees is the light the surface reflects: ambient() on that scale."""
        return self.ambient()
