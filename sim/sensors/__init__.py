"""Sensor device models that read the simulated world: colour and reflectance from the mat under
the robot, range by ray cast, rotation from the chassis body.

Each model answers on the same electrical interface the hub driver uses (I2C
registers, SPI frames, ADC counts, an echo pulse), computing its registers
from the MuJoCo state at the moment they are read, so the unchanged drivers
in openbricks.drivers run against them. Nothing here runs per physics step:
a model does work only when the program reads it, and at most once per
simulated instant.
"""
