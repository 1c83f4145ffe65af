"""JGB37-520 geared DC motor with a Hall quadrature encoder, on an H-bridge channel (L298N / TB6612).

Six wires: the two motor leads into the bridge, encoder Vcc/GND and channels
A/B. The default 1320 counts per output turn is 11 pulses x 4 edges x 1:30.
The encoder is counted by a free PCNT unit where the runtime has machine.Encoder
(the ESP32 port, and the simulator), else in a pin interrupt, which keeps up
with this motor's few thousand edges a second.

The closed loop runs on the native servo core (`_openbricks_native.Servo`),
ticked by `motor_process` at 1 kHz: this class only builds the bridge and the
encoder and hands the core its motor IO (read the angle, write a duty, release
the bridge). Open-loop commands (dc, brake, coast) and the encoder angle work
on a build without the native core; closed-loop ones need it.

On the firmware both ends of that IO are native (the PCNT encoder core and the
H-bridge core), so it is a MotorIO joined in C (`HBridge.motor_io`): the servo
core, or a drive base's controller, then runs in the hard tick with no Python
call, as the serial-bus wheels do. Elsewhere it is BridgeIO, in Python.

A wheel has one driver at a time. A DriveBase drives the same motor IO with
its own controller after `give_to_drivebase()` stood this motor's core down;
any direct command here (run_speed, run_angle, dc, brake, coast, hold, ...)
first takes the wheel back, which ends the drive base's move and releases its
other wheel too, as Pybricks does when a drive base motor is used directly.
"""

import time

from openbricks import _native, estop
from openbricks.drivers.encoder import make_encoder
from openbricks.drivers.l298n import L298NMotor
from openbricks.interfaces import Motor
from openbricks.parameters import Stop, then_name

_DEFAULT_CPR = 1320
# The core's defaults are tuned for a geared servo with 888 deg/s no-load speed; speed-proportional
# terms are rescaled to this motor's no-load speed (a 12 V JGB37-520 1:30 on a 2S pack, ~205 RPM).
_CORE_NO_LOAD_DPS = 888.0
_DEFAULT_NO_LOAD_DPS = 1230.0
_DEFAULT_KP = 0.25 * _CORE_NO_LOAD_DPS / _DEFAULT_NO_LOAD_DPS  # speed-loop gain, duty % per deg/s
_POLL_MS = 5


class JGB37Motor(Motor):
    """JGB37-520 DC gear motor with quadrature encoder, closed loop on the native servo core.

    `invert` flips the bridge and the encoder together (a motor mounted
    mirror-image); `encoder_invert` flips only the encoder (one that counts
    down while the motor turns forward). `no_load_dps` is the output speed at
    full duty, which the feed-forward is scaled by. `pcnt_unit` pins the
    encoder to one PCNT unit; None (the default) takes the lowest free one.
    """

    def __init__(
        self,
        in1,
        in2,
        pwm,
        encoder_a,
        encoder_b,
        counts_per_output_rev=_DEFAULT_CPR,
        invert=False,
        encoder_invert=False,
        kp=_DEFAULT_KP,
        no_load_dps=_DEFAULT_NO_LOAD_DPS,
        pcnt_unit=None,
    ):
        if counts_per_output_rev <= 0 or no_load_dps <= 0:
            raise ValueError(
                "counts_per_output_rev=%r and no_load_dps=%r must be > 0"
                % (counts_per_output_rev, no_load_dps)
            )
        self.invert = bool(invert)
        self.counts_per_output_rev = counts_per_output_rev
        self.no_load_dps = no_load_dps
        self.pcnt_unit = pcnt_unit
        self._offset_deg = 0.0
        self._bridge = L298NMotor(in1, in2, pwm, invert=invert)
        try:
            self._encoder = self._make_encoder(encoder_a, encoder_b, self.invert != bool(encoder_invert))
        except Exception:
            self._bridge.close()
            raise
        self._io = _motor_io(self._encoder, self._bridge, 360.0 / counts_per_output_rev)
        self._driver = None  # the drive base wheel pair driving this bridge, while one does
        self._servo = self._make_servo(kp)
        estop.on_engage(self.coast)  # through the core, or its next tick would drive the bridge again

    def _make_encoder(self, pin_a, pin_b, invert):
        return make_encoder(
            pin_a,
            pin_b,
            invert=invert,
            name="%s encoder" % type(self).__name__,
            unit=self.pcnt_unit,
            counts_per_rev=self.counts_per_output_rev,
        )

    def _make_servo(self, kp):
        servo_type = _native.get("Servo")
        if servo_type is None:
            return None  # open-loop only on this build; closed-loop calls say so
        io = self._io
        motor_io = _native.get("MotorIO")
        if motor_io is not None and isinstance(io, motor_io):
            wiring = {"io": io}  # read and written in C: the hard tick may run this core
        else:
            wiring = {"read_angle": io.read_angle, "write_duty": io.write_duty, "write_coast": io.coast}
        servo = servo_type(
            counts_per_rev=self.counts_per_output_rev,
            max_speed_dps=self.no_load_dps,
            ff_speed=100.0 / self.no_load_dps,
            speed_kp=kp,
            **wiring,
        )
        return servo

    # --- who drives the wheel -------------------------------------------------------

    @property
    def closed_loop(self):
        """True when this build has the native servo core, so the motor (or a drive base) can close
        the loop over its encoder."""
        return self._servo is not None

    def motor_io(self):
        """The IO a controller drives this wheel through: `read_angle()`, `write_duty(pct)`, `coast()`.

        The same contract as a serial-bus engine slot's motor IO, so a drive base's controller
        connects to either the same way."""
        return self._io

    def give_to_drivebase(self, driver):
        """`driver` (a drive base's wheel pair) drives this bridge from now on; this motor's own core
        stands down. The next direct command calls `driver.let_go()` before it drives the wheel."""
        if self._servo is not None:
            _native.motor_process.unsubscribe(self._servo)
        self._driver = driver

    def forget_drivebase(self, driver):
        """`driver` no longer drives this bridge (it let go, or its drive base was closed)."""
        if self._driver is driver:
            self._driver = None

    def _take_back(self):
        driver = self._driver
        if driver is not None:
            self._driver = None
            driver.let_go()

    def _native(self, method, drive=True):
        """The core, ticking. `drive` (a command) takes the wheel back from a drive base first; a query
        leaves a drive base driving and reads the core's observer as it was last ticked."""
        servo = self._servo
        if servo is None:
            raise NotImplementedError(
                "%s.%s() needs the native servo core (_openbricks_native), which this firmware build lacks; "
                "dc(), brake(), coast() and angle() work without it" % (type(self).__name__, method)
            )
        if drive:
            self._take_back()
        elif self._driver is not None:
            return servo  # ticking it now would make it a second driver of the bridge
        # Idempotent; re-arms the tick after the launcher wiped the previous program's subscribers.
        _native.motor_process.subscribe(servo)
        return servo

    # --- Motor -------------------------------------------------------------------------

    def dc(self, duty):
        """Fixed duty -100..100, open loop (Pybricks Motor.dc). Non-blocking."""
        estop.check("%s dc()" % type(self).__name__)
        duty = max(-100, min(100, duty))
        self._take_back()
        if self._servo is not None:
            self._servo.dc(duty)  # the core must know, or its next tick would overwrite the duty
        else:
            self._bridge.dc(duty)

    def brake(self):
        """Short the winding (active braking). A stop: allowed while the e-stop is engaged."""
        self._take_back()
        if self._servo is not None:
            self._servo.brake()
        else:
            self._bridge.brake()

    def coast(self):
        """Release the bridge; the motor free-wheels. Always allowed, e-stop or not."""
        self._take_back()
        if self._servo is not None:
            self._servo.coast()
        else:
            self._bridge.coast()

    def hold(self):
        """Hold the current angle on the position loop. A stop: allowed while the e-stop is engaged."""
        self._native("hold").hold()

    def _encoder_angle(self):
        angle = self._io.read_angle()
        if angle is None:  # only a native IO says so: its PCNT unit could not be read
            raise OSError("%s: the encoder's PCNT unit could not be read" % type(self).__name__)
        return angle

    def angle(self):
        """Output-shaft angle in degrees, straight from the encoder count."""
        return self._encoder_angle() + self._offset_deg

    def reset_angle(self, angle=0):
        """Make the shaft's current position read as `angle` degrees (0 by default)."""
        self._offset_deg = angle - self._encoder_angle()
        if self._servo is not None:
            self._servo.reset_angle(angle)

    def speed(self):
        """Measured shaft speed in deg/s (the core's encoder observer)."""
        return self._native("speed", drive=False).speed()

    def stalled(self):
        """True once the core has pushed at its duty limit (or far behind) while nearly still for 200 ms."""
        return self._native("stalled", drive=False).stalled()

    def run_speed(self, deg_per_s):
        """Hold `deg_per_s`, ramped at the core's acceleration (closed loop)."""
        estop.check("%s run_speed()" % type(self).__name__)
        self._native("run_speed").run_speed(deg_per_s)

    def run_angle(self, deg_per_s, target_angle, wait=True, accel_dps2=1500.0, then=Stop.COAST):
        """Rotate by `target_angle` degrees (sign = direction) on a trapezoid at up to `deg_per_s`.

        The core samples the profile at 1 kHz; with wait=False poll done().
        """
        name = then_name(then)
        estop.check("%s run_angle()" % type(self).__name__)
        if deg_per_s == 0:
            raise ValueError("run_angle(deg_per_s=0): the move would never finish; give a non-zero speed")
        servo = self._native("run_angle")
        servo.run_angle(abs(deg_per_s), target_angle, then=name, accel_dps2=accel_dps2)
        if wait:
            while not servo.done():
                time.sleep_ms(_POLL_MS)

    def run_target(self, speed, target_angle, then=Stop.HOLD, wait=True):
        """Run to the absolute `target_angle` (reset_angle frame), planned by the core from its reference."""
        name = then_name(then)
        estop.check("%s run_target()" % type(self).__name__)
        if speed == 0:
            raise ValueError("run_target(speed=0): the move would never finish; give a non-zero speed")
        servo = self._native("run_target")
        servo.run_target(abs(speed), target_angle, then=name)
        if wait:
            while not servo.done():
                time.sleep_ms(_POLL_MS)

    def done(self):
        """True unless a run_angle/run_target(wait=False) move is still on its way."""
        return True if self._servo is None else self._servo.done()

    def _duty_limit_push(self, limit_pct):
        servo = self._native("run_until_stalled")
        self._limit_stack = getattr(self, "_limit_stack", [])
        self._limit_stack.append(servo.duty_limit)
        servo.set_duty_limit(limit_pct)

    def _duty_limit_pop(self):
        self._servo.set_duty_limit(self._limit_stack.pop())

    def close(self):
        """Stop ticking, release the bridge and the encoder pins (a drive base driving it lets go)."""
        self._take_back()
        estop.remove(self.coast)
        if self._servo is not None:
            _native.motor_process.unsubscribe(self._servo)
        self._bridge.close()
        self._encoder.close()


def _motor_io(encoder, bridge, deg_per_count):
    """The wheel's IO: joined in C when the encoder and the bridge are both the firmware's cores (the hard
    tick may then drive it), else BridgeIO over the Python objects."""
    native_bridge = bridge.native_bridge()
    native_encoder = encoder.native_counter()
    if native_bridge is not None and native_encoder is not None:
        return native_bridge.motor_io(native_encoder, deg_per_count)
    return BridgeIO(encoder, bridge, deg_per_count)


class BridgeIO:
    """An encoder motor's IO as a controller sees it: the output angle in, a bridge duty or a release out.

    The motor's own servo core and a drive base's controller drive the wheel through this one object,
    so a duty means the same thing whichever of them writes it.
    """

    def __init__(self, encoder, bridge, deg_per_count):
        self._encoder = encoder
        self._bridge = bridge
        self._deg_per_count = deg_per_count

    def read_angle(self):
        return self._encoder.count() * self._deg_per_count

    def write_duty(self, duty_pct):
        # Controllers work in the user frame (the bridge applies `invert`); their duty 0 means
        # "brake": the bridge shorts the winding rather than letting go.
        if duty_pct == 0:
            self._bridge.brake()
        else:
            self._bridge._drive(duty_pct)

    def coast(self):
        self._bridge.coast()
