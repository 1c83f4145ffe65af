"""The robot a program describes: the simulator builds it from the drivers the program constructs.

A real robot is wired the way its program says. So the simulated one is too:

- before the run, `infer_chassis(source)` picks the build from the motor drivers the program's
  source constructs (JGB37Motor / MG370Motor: the DC build; otherwise the ST-3032 serial-bus one);
  `--chassis` stays an override;
- while it runs, `ProgramRobot` watches the runtime's driver constructors (an import hook on the
  program's fresh copy of `openbricks`, installed after the shim and the hub's own finder): the
  motors passed to `DriveBase` are mounted on the wheels they name (robot.py `place_wheels`), a
  DC motor's leads are wired to suit the driver built on its bridge channel (robot.py
  `build_motor`), and a TCS34725 built on the bare I2C bus gets one wired there (sensors/rig.py
  `wire_bare_colour_sensor`) unless the rig was told otherwise.

Where the program and the build disagree (JGB37 motors on the servo chassis, say), one line tells
the user, once, in the program's output. So does a `DriveBase.straight()` that turned the robot
in place: the encoders say it drove, so the program cannot tell, and on the serial-bus build it
is what a mirrored servo without invert=True does.
"""

import ast
import functools
import inspect
import math
import sys
import weakref

SERIAL_BUS_MOTORS = ("ST3032Motor", "ST3215Motor")
ENCODER_MOTORS = ("JGB37Motor", "MG370Motor")
CHASSIS_OF = {"st3032": SERIAL_BUS_MOTORS, "jgb37": ENCODER_MOTORS}
DEFAULT_CHASSIS = "st3032"
# A straight() whose wheels turned the body this far while carrying it less than this share of the
# distance asked for turned in place. A straight that drives holds its heading within a degree or
# two, and a wheel that slips turns less, so neither comes near.
SPIN_DEG = 45.0
SPIN_TRAVEL_SHARE = 0.25


def constructed_names(source):
    """Names of everything the source calls (`Foo(...)` and `module.Foo(...)`); empty if it does not
    parse (the run reports the syntax error itself)."""
    try:
        tree = ast.parse(source)
    except (SyntaxError, ValueError):
        return set()
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            func = node.func
            if isinstance(func, ast.Name):
                names.add(func.id)
            elif isinstance(func, ast.Attribute):
                names.add(func.attr)
    return names


def infer_chassis(source):
    """The build whose motors the program constructs: "jgb37" for encoder DC motors only, else the
    serial-bus "st3032" (also when it constructs both kinds, or no motor at all)."""
    names = constructed_names(source)
    if names & set(ENCODER_MOTORS) and not names & set(SERIAL_BUS_MOTORS):
        return "jgb37"
    return DEFAULT_CHASSIS


def _build_phrase(chassis):
    motors = CHASSIS_OF.get(chassis)
    return f"the {chassis} build ({' / '.join(motors)})" if motors else f"the {chassis} build"


class ProgramRobot:
    """Learns the robot from the drivers the program constructs, and builds it in `simulation`.

    install() puts an import hook in front of the program's imports of the hub runtime; every
    constructor it wraps calls the real one after telling the simulation what it learned.
    """

    def __init__(self, simulation, note=None):
        self._sim = simulation
        self._note = note if note is not None else _print_note
        self._noted = set()
        self._encoder_pins = weakref.WeakKeyDictionary()  # JGB37Motor -> its encoder A pin
        self._finder = _ConstructorWatch(
            {
                "openbricks.robotics.drivebase": ("DriveBase", self._drivebase, {"straight": self._straight}),
                "openbricks.drivers.jgb37_520": ("JGB37Motor", self._encoder_motor),
                "openbricks.drivers.l298n": ("L298NMotor", self._bridge_motor),
                "openbricks.drivers.st3215": ("ST3215Motor", self._serial_bus_motor),
                "openbricks.drivers.tcs34725": ("TCS34725", self._colour_sensor),
            }
        )

    def install(self):
        """Watch from now on: first on sys.meta_path, ahead of the hub's own finder (install after it)."""
        self.uninstall()
        sys.meta_path.insert(0, self._finder)
        return self

    def uninstall(self):
        if self._finder in sys.meta_path:
            sys.meta_path.remove(self._finder)

    def __enter__(self):
        return self.install()

    def __exit__(self, *exc):
        self.uninstall()
        return False

    # --- what the constructors say ---------------------------------------------------------

    def _drivebase(self, _drivebase, left, right, *_args, **_kwargs):
        sides = [self._wheel_key(motor) for motor in (left, right)]
        if None not in sides:
            self._sim.wiring.place_wheels(*sides)

    def _wheel_key(self, motor):
        """(what identifies the motor on the robot's wiring, invert), or None for a motor it cannot
        place (an open-loop bridge, something not a motor)."""
        invert = bool(getattr(motor, "invert", False))
        servo_id = getattr(motor, "servo_id", None)
        bus = getattr(motor, "bus", None)
        if servo_id is not None and bus is not None:
            return (getattr(bus, "uart_id", None), servo_id), invert
        pin = self._encoder_pins.get(motor)
        return None if pin is None else (pin, invert)

    def _encoder_motor(self, motor, in1, in2, pwm, encoder_a, *_args, **_kwargs):
        self._encoder_pins[motor] = encoder_a
        self._check_build(type(motor).__name__, "jgb37")

    def _bridge_motor(self, _motor, in1, in2, pwm, invert=False, *_args, **_kwargs):
        self._sim.wiring.build_motor(in1, in2, pwm, invert)

    def _straight(self, straight, drivebase, distance_mm, *args, **kwargs):
        """Runs the program's straight(); a blocking one that turned the robot in place says so."""
        physics = self._sim.physics
        wait = kwargs.get("wait", args[1] if len(args) > 1 else True)
        before = [physics.wheel_angle_deg(wheel) for wheel in (0, 1)]
        straight(drivebase, distance_mm, *args, **kwargs)
        if not wait or "spin" in self._noted:
            return
        mm_per_deg = math.pi * physics.chassis.wheel_diameter_mm / 360.0
        left, right = ((physics.wheel_angle_deg(w) - before[w]) * mm_per_deg for w in (0, 1))
        turned_deg = math.degrees((left - right) / physics.chassis.axle_track_mm)
        if abs(turned_deg) < SPIN_DEG or abs(left + right) / 2 >= SPIN_TRAVEL_SHARE * abs(distance_mm):
            return
        self._noted.add("spin")
        self._note(
            f"sim: straight({distance_mm:g}) turned the robot in place ({abs(turned_deg):.0f} deg) "
            "instead of driving it: a motor mounted mirrored is likely not inverted; build the right-hand "
            "motor with invert=True (and only that one)"
        )

    def _serial_bus_motor(self, motor, *_args, **_kwargs):
        self._check_build(type(motor).__name__, "st3032")

    def _colour_sensor(self, sensor, i2c, *_args, **_kwargs):
        key = getattr(i2c, "_key", None)  # the shim's machine.I2C; a mux channel has none
        if key is None or self._sim.wire_bare_colour_sensor(key) or "bare" in self._noted:
            return
        self._noted.add("bare")
        self._note(
            f"sim: the program builds a TCS34725 straight on I2C{key} but the simulated robot has another "
            "0x29 part there (--bare-0x29); drop --bare-0x29 to let the program choose"
        )

    def _check_build(self, driver, wants):
        chassis = self._sim.physics.chassis.name
        if chassis == wants or (driver, chassis) in self._noted:
            return
        self._noted.add((driver, chassis))
        self._note(
            f"sim: the program builds {driver} motors but the simulated robot is {_build_phrase(chassis)}; "
            f"run it with --chassis {wants} (or without --chassis, to let the program choose)"
        )


def _print_note(line):
    print(line)


class _ConstructorWatch:  # a meta path finder (find_spec is all the import system asks of one)
    """Loads the watched runtime modules normally, then wraps one class's __init__ in each (and any
    methods named with it)."""

    def __init__(self, watched):
        # module name -> (class name, before(instance, *args, **kwargs)[, {method: around}]); around
        # is called as around(method, instance, *args, **kwargs) and calls the method itself.
        self._watched = watched

    def find_spec(self, name, path=None, target=None):
        if name not in self._watched:
            return None
        for finder in sys.meta_path:  # whoever would load it without us (the hub's finder, first)
            if finder is self or not hasattr(finder, "find_spec"):
                continue
            spec = finder.find_spec(name, path, target)
            if spec is not None:
                break
        else:
            return None
        if spec.loader is not None:
            spec.loader = _WrappingLoader(spec.loader, *self._watched[name])
        return spec


class _WrappingLoader:  # a loader: create_module() and exec_module()
    def __init__(self, loader, class_name, before, around=None):
        self._loader = loader
        self._class_name = class_name
        self._before = before
        self._around = around or {}

    def __getattr__(self, name):  # get_source, is_package, ...: the real loader's
        return getattr(self._loader, name)

    def create_module(self, spec):
        return self._loader.create_module(spec)

    def exec_module(self, module):
        self._loader.exec_module(module)
        cls = getattr(module, self._class_name, None)
        if cls is not None:
            _watch(cls, self._before)
            for name, around in self._around.items():
                _wrap(cls, name, around)


def _watch(cls, before):
    init = cls.__init__
    signature = inspect.signature(init)

    def __init__(self, *args, **kwargs):
        try:
            bound = signature.bind(self, *args, **kwargs)
        except TypeError:
            bound = None  # the real constructor says what is wrong with the call
        if bound is not None:
            before(*bound.args, **bound.kwargs)
        init(self, *args, **kwargs)

    __init__.__doc__ = init.__doc__
    cls.__init__ = __init__


def _wrap(cls, name, around):
    method = getattr(cls, name, None)
    if method is None:
        return

    @functools.wraps(method)
    def wrapped(self, *args, **kwargs):
        return around(method, self, *args, **kwargs)

    setattr(cls, name, wrapped)
