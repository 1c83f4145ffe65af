"""The range-sensor contract (HC-SR04, VL53L0X, VL53L1X).

Kept out of interfaces.py on purpose: `import openbricks` pulls the core
interfaces into every program's heap, and only programs with a range sensor
should pay for this one.
"""


class DistanceSensor:
    """A forward-facing range sensor."""

    def distance_mm(self):
        """Distance to the nearest target ahead in mm; -1 when there is no echo or it is out of range."""
        raise NotImplementedError("%s does not support distance_mm()" % type(self).__name__)
