"""The simulated robot's sensors, wired to the hub the way the manual's baseline build wires them.

  I2C0 (SDA 15, SCL 16)  TCA9548A at 0x70; a TCS34725 on channel n for each chassis colour
                         site color_n (channel 0 = left, 1 = right); the laser range finder
                         (a VL53L0X, or a VL53L1X) on channel 7; a BNO055 at 0x28; a 128x64
                         SSD1306 OLED at 0x3C
  SPI (SCK 12, MOSI 13, MISO 11, CS 17)  ICM-45686; on the DC build (jgb37) SCK 4, MOSI 5, MISO 6,
                         CS 21 instead, because that build's motors take 11, 12, 13 and 17
  ADC GPIO 1..10         the QTRLineSensor window over the `qtr` site
  GPIO 18 / 40           HC-SR04 TRIG / ECHO (pins the manual's map leaves free)

The DC build's motors (manual 2.7) also sit on ADC pins 1, 2 and 7..10: the QTR window stays there,
so a program can use the bar or the motors on that chassis but not both, as on the real robot (the
pins guard names the pin).

Every 0x29 part sits behind the mux because that is the only way they can
share one bus: a chip wired straight to the bus at 0x29 collides with any
connected mux channel that has one, as on a real robot. A build with a
single 0x29 part and no mux (the manual's one-colour-sensor robot, or a bare
range finder) is `attach_sensors(..., bare_0x29="tcs34725" | "vl53l0x" |
"vl53l1x")`, which wires that part straight to the bus instead.

A chip answers only when the program talks to it, so carrying every sensor
costs nothing for a program that uses none. Every model draws its noise from
the run's seed, so one (program, world, chassis, seed) job always reads the
same numbers.
"""

from dataclasses import dataclass

import mujoco

from ..chassis import color_site
from ..display import SSD1306Model
from .color import TCS34725Model
from .distance import ForwardRay, HCSR04Model, VL53L0XModel, VL53L1XModel, sonar_ray
from .imu import BNO055Model, BodyMotion, ICM45686Model
from .mat import GroundProbe
from .mux import TCA9548AModel
from .qtr import QTRBarModel

I2C_BUS = 0
MUX_ADDRESS = 0x70
BNO055_ADDRESS = 0x28
OLED_ADDRESS = 0x3C
SHARED_ADDRESS = 0x29  # every TCS34725 and both VL53 parts
RANGE_FINDER_CHANNEL = 7
HCSR04_TRIG, HCSR04_ECHO = 18, 40
RANGE_FINDERS = ("vl53l0x", "vl53l1x")
BARE_0X29 = ("vl53l0x", "vl53l1x", "tcs34725", None)


@dataclass(frozen=True)
class SpiPins:
    sck: int
    mosi: int
    miso: int
    cs: int


# The IMU's SPI pins per chassis: the baseline build's, and on the DC build four pins its motor map
# (manual 2.7: PWM 17 and 11, right encoder 12/13) leaves free.
ICM45686_SPI = {"st3032": SpiPins(12, 13, 11, 17), "jgb37": SpiPins(4, 5, 6, 21)}
ICM45686_CS = ICM45686_SPI["st3032"].cs


@dataclass
class Sensors:
    """The attached models, for tests and for a front end that wants to show what the robot sees."""

    colours: list
    mux: TCA9548AModel
    qtr: QTRBarModel
    icm45686: ICM45686Model
    bno055: BNO055Model
    range_finder: object  # the laser ranger: on mux channel 7, or on the bare bus
    bare_0x29: object  # what is wired straight to the bus at 0x29, if anything
    hcsr04: HCSR04Model
    oled: SSD1306Model
    imu_spi: SpiPins = ICM45686_SPI["st3032"]  # where this chassis wires the ICM-45686


def icm45686_spi(chassis_name) -> SpiPins:
    """The ICM-45686's SPI pins on chassis `chassis_name` (the baseline's for a chassis not listed)."""
    return ICM45686_SPI.get(chassis_name, ICM45686_SPI["st3032"])


def attach_sensors(physics, board, seed: int = 0, range_finder="vl53l0x", bare_0x29=None) -> Sensors:
    """Build the sensor models over physics' world and attach them to the simulated hub's board.

    range_finder: "vl53l0x" or "vl53l1x", on mux channel 7. bare_0x29: None (every 0x29 part behind
    the mux), or the one part wired straight to the bus without a mux: "tcs34725" (over color_0),
    "vl53l0x" or "vl53l1x" (the range finder itself moves to the bare bus).
    """
    if range_finder not in RANGE_FINDERS:
        raise ValueError(f"range_finder must be one of {RANGE_FINDERS}, got {range_finder!r}")
    if bare_0x29 not in BARE_0X29:
        raise ValueError(f"bare_0x29 must be one of {BARE_0X29}, got {bare_0x29!r}")
    model, data = physics.model, physics.data
    now_us = board.clock.now_us
    probe = GroundProbe(model, data)
    bus = board.i2c_devices.setdefault(I2C_BUS, {})

    bare = None
    if bare_0x29 in RANGE_FINDERS:
        range_finder = bare_0x29
    elif bare_0x29 == "tcs34725":
        bare = _bare_colour_sensor(probe, now_us, seed)
    ray = ForwardRay(model, data)
    if range_finder == "vl53l0x":
        ranger = VL53L0XModel(ray, now_us, seed=seed * 101 + 30)
    else:
        ranger = VL53L1XModel(ray, now_us, seed=seed * 101 + 30)
    if bare_0x29 in RANGE_FINDERS:
        bare = ranger
    if bare is not None:
        bus[SHARED_ADDRESS] = bare

    colours = []
    mux = TCA9548AModel(bus, MUX_ADDRESS)
    for index in range(_colour_sites(model)):
        chip = TCS34725Model(probe, color_site(index), now_us, seed=seed * 101 + index)
        mux.attach(index, SHARED_ADDRESS, chip)
        colours.append(chip)
    if bare is not ranger:
        mux.attach(RANGE_FINDER_CHANNEL, SHARED_ADDRESS, ranger)

    motion = BodyMotion(model, data)
    bno = BNO055Model(motion, now_us, seed=seed * 101 + 20)
    bus[BNO055_ADDRESS] = bno
    oled = bus[OLED_ADDRESS] = SSD1306Model()
    icm = ICM45686Model(motion, now_us, seed=seed * 101 + 21)
    imu_spi = icm45686_spi(physics.chassis.name)
    board.attach_spi(imu_spi.cs, icm)

    sonar = HCSR04Model(sonar_ray(model, data), seed=seed * 101 + 31)
    board.watch_output(HCSR04_TRIG, sonar.trig_driven)
    board.set_pulse(HCSR04_ECHO, sonar.echo_pulse_us)

    qtr = QTRBarModel(probe, now_us, seed=seed * 101 + 40)
    for pin in qtr.pins:
        board.set_analog(pin, qtr.channel(pin).read)

    return Sensors(colours, mux, qtr, icm, bno, ranger, bare, sonar, oled, imu_spi)


def _bare_colour_sensor(probe, now_us, seed):
    return TCS34725Model(probe, color_site(0), now_us, seed=seed * 101 + 9)


def wire_bare_colour_sensor(sensors, physics, board, seed=0) -> bool:
    """Wire a TCS34725 straight to the I2C bus at 0x29, over color_0, as a program that builds one
    on the bare bus describes (the manual's one-colour-sensor robot). False, changing nothing, when
    a part already sits there (the rig was told what is bare)."""
    bus = board.i2c_devices.setdefault(I2C_BUS, {})
    if sensors.bare_0x29 is not None or SHARED_ADDRESS in bus:
        return isinstance(sensors.bare_0x29, TCS34725Model)
    sensors.bare_0x29 = bus[SHARED_ADDRESS] = _bare_colour_sensor(
        GroundProbe(physics.model, physics.data), board.clock.now_us, seed
    )
    return True


def _colour_sites(model) -> int:
    count = 0
    while mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, color_site(count)) >= 0:
        count += 1
    return count
