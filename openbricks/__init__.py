"""openbricks: the hub runtime frozen into the firmware (drivers, interfaces, robotics, services)."""

__version__ = "2.7.1"
