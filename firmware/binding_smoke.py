"""Exercise `_openbricks_native` the way the hub runtime does, on whichever build imports it.

Run by tests/firmware/test_micropython_bindings.py under a unix MicroPython built with our user C
module, and under CPython against the host extension: the same script must pass on both, which is
what "the hub binding mirrors the host binding" means in practice. Prints one JSON line of computed
values (compared across the two builds by the test) and then SMOKE OK.
"""

# It runs under MicroPython too, which has no f-string `!r`: keep %-formatting.
# ruff: noqa: UP031

import json

import _openbricks_native as native


def expect_error(exc_type, text, fn, *args, **kwargs):
    try:
        fn(*args, **kwargs)
    except exc_type as err:
        assert text in str(err), "%r does not mention %r" % (str(err), text)
        return
    raise AssertionError("%s(%r) did not raise %s" % (fn, args, exc_type.__name__))


results = {}

# Trajectory: a move that lands at rest on its target, sampled along the way.
profile = native.TrapezoidalProfile(0, 360, 360, 720)
end = profile.sample(profile.duration_s)
assert abs(end[0] - 360) < 1e-3 and abs(end[1]) < 1e-3, end
results["profile"] = [profile.sample(t / 10)[0] for t in range(16)]
results["profile_scaled"] = profile.scaled(0.5, 10).sample(0.5)[0]
results["speed_ramp"] = native.TrapezoidalProfile.speed_ramp(0, 0, 500, 1000).sample(1.0)[1]
expect_error(ValueError, "speed_dps must be > 0", native.TrapezoidalProfile, 0, 10, 0, 100)

# Observer.
observer = native.Observer(x_deg=5)
for i in range(50):
    observer.update(5 + i, 0.001)
results["observer"] = [observer.x_deg, observer.v_dps]

# Servo with IO callables, ticked through a MotorProcess as the runtime's encoder motors are.
angle = [0.0]
written = []


def read_angle():
    return angle[0]


def write_duty(duty):
    written.append(duty)


def write_coast():
    written.append(None)


servo = native.Servo(read_angle=read_angle, write_duty=write_duty, write_coast=write_coast)
process = native.MotorProcess()
process.subscribe(servo)
process.subscribe(servo)  # idempotent
assert process.count == 1 and process.is_subscribed(servo)
servo.dc(50)
process.tick(1)
assert written[-1] == 50.0, written

# A failing IO callable: the other subscriber is still controlled, then the error is raised.


def unplugged():
    raise OSError("encoder unplugged")


broken = native.Servo(read_angle=unplugged, write_duty=write_duty, write_coast=write_coast)
process.subscribe(broken)
servo.dc(20)
expect_error(OSError, "encoder unplugged", process.tick, 2)
assert written[-1] is None or written[-1] == 20.0
assert 20.0 in written
process.unsubscribe(broken)

# Python callables are subscribers too (called with the tick time).
seen = []
process.subscribe(seen.append)
process.tick(7)
assert seen == [7], seen
assert process.now_ms() == 7 and process.tick_count == 3
process.reset()
assert not process.is_running()

# Servo settings and validation, with the manual's then= strings.
assert servo.settings(kp=2.5)["kp"] == 2.5
expect_error(TypeError, "unknown setting", servo.settings, kpp=1)


def refusal(fn, *args, **kwargs):
    """The exception's type and words: the core writes them, so both builds must say the same."""
    try:
        fn(*args, **kwargs)
    except (TypeError, ValueError) as err:
        return [type(err).__name__, str(err)]
    raise AssertionError("%s(%r, %r) was accepted" % (fn, args, kwargs))


results["settings_refused"] = [
    refusal(servo.settings, **{name: value})
    for name, value in (
        ("kpp", 1),
        ("stall_time_ms", 1.5),
        ("kp", -1),
        ("accel_dps2", 0),
        ("silent_timeout_ms", 0),
        ("observer_alpha", 2.0),
    )
] + [refusal(native.Servo, duty_limit=0), refusal(servo.set_duty_limit, 120)]
expect_error(ValueError, "then must be one of", servo.run_target, 100, 90, "sideways")
servo.run_target(100, 90, then="brake")
expect_error(ValueError, "speed_dps must not be 0", servo.run_angle, 0, 90)

# The direct path: one control step from a reading, no callables.
direct = native.Servo()
direct.run_speed(200)
results["servo_update"] = [direct.update(t, t * 0.2) for t in range(0, 50, 10)]
expect_error(ValueError, "no IO to tick", native.MotorProcess().subscribe, direct)

# DriveBase, direct path.
drivebase = native.DriveBase(56, 114)
drivebase.straight(100, then="hold")
outputs = [drivebase.update(t, t * 0.3, t * 0.3) for t in range(0, 40, 5)]
results["drivebase"] = outputs[-1]
assert drivebase.settings() == drivebase.settings()
expect_error(ValueError, "wheel_diameter_mm must be > 0", native.DriveBase, 0, 114)

# Gyro heading.
yaw = native.ImuYaw(scale=-1.0)
for i in range(10):
    yaw.update(10.0, i * 1000)
results["imu_heading"] = yaw.heading()
expect_error(ValueError, "seed_bias", yaw.seed_bias, 100.0)

# PCNT encoder core, fed what a PCNT unit (wrapping at +-32767) reads while an MG370 turns 5 turns back.
encoder = native.PCNTEncoder(68028, invert=True)
raw = 0
encoder.sample(raw)
for _ in range(5 * 68028 // 10000):
    raw -= 10000
    if raw <= -32767:
        raw += 32767
    encoder.sample(raw)
results["encoder"] = [encoder.count(), encoder.angle(), encoder.direction(), encoder.max_step()]
encoder.reset(-5)
results["encoder_reset"] = encoder.count()
assert native.PCNTEncoder.HARDWARE is False
expect_error(ValueError, "counts_per_rev must be > 0", native.PCNTEncoder, 0)
expect_error(TypeError, "raw must be an int", encoder.sample, 1.5)
expect_error(OSError, "no PCNT peripheral", native.PCNTEncoder, 1320, pin_a=7, pin_b=8)
encoder.close()
expect_error(ValueError, "was closed", encoder.count)


# ICM-45686 core over a register model of the chip: setup, bursts, the heading, and a DriveBase that reads
# it in C (heading=imu) with no Python call per tick.
class ChipModel:
    def __init__(self):
        self.regs = bytearray(128)
        self.regs[0x72] = 0xE9
        self.gz = 0
        self.bursts = 0

    def transfer(self, data):
        if data[0] & 0x80:
            reg = data[0] & 0x7F
            if reg == 0:
                self.bursts += 1
                block = bytes((0, 0, 0, 0, 0, 0x20, 0, 0, 0, 0, self.gz & 0xFF, (self.gz >> 8) & 0xFF))
                return b"\x00" + block[: len(data) - 1]
            return b"\x00" + bytes(self.regs[reg : reg + len(data) - 1])
        if data[0] != 0x7F:
            self.regs[data[0]] = data[1]
        return bytes(len(data))


chip = ChipModel()
imu = native.ICM45686(chip.transfer, scale=-1.0)
assert imu.stats() == (0, 0, True) and chip.regs[0x1C] == 0x25 and chip.regs[0x10] == 0x0F
chip.gz = -2949  # a face-up chip turning clockwise at ~90 deg/s
for i in range(101):
    imu.sample(i * 1000)
results["icm_heading"] = imu.heading()
results["icm_gyro"] = list(imu.gyro())
results["icm_accel"] = list(imu.acceleration())
assert chip.bursts == 101 and imu.stats()[0] == 101
assert native.ICM45686.HARDWARE is False
expect_error(OSError, "no SPI peripheral", native.ICM45686, chip.transfer, sck=12, mosi=13, miso=11, cs=17)
expect_error(OSError, "reads 0x00, expected 0xE9", native.ICM45686, lambda data: bytes(len(data)))
db = native.DriveBase(56, 114, heading=imu)
db.use_gyro(True)
expect_error(TypeError, "or a native IMU", native.DriveBase, 56, 114, heading=42)

# Serial-bus codec.
scs = native.scs
assert scs.ping(1) == bytes([0xFF, 0xFF, 0x01, 0x02, 0x01, 0xFB])
reply = scs.decode_status(scs.status(3, scs.FLAG_OVERLOAD, b"\x10\x20"))
assert reply.result == "ok" and reply.id == 3 and reply.params == b"\x10\x20" and reply[0] == "ok"
assert scs.flag_names(reply.error) == ("overload",)
assert scs.decode_speed(scs.encode_speed(-300)) == -300
results["sync_write"] = list(scs.sync_write(scs.REG_GOAL_SPEED, [(1, b"\x01\x02"), (2, b"\x03\x04")]))
expect_error(ValueError, "out of range", scs.read, 254, 0x38, 2)
assert scs.decode_frame(b"\xff\xff\x01").result == "need_more"

print(json.dumps(results))
print("SMOKE OK")
