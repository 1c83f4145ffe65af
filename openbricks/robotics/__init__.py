"""Robotics on top of the motor and sensor interfaces: `DriveBase` (manual 7.1)."""

from openbricks.robotics.drivebase import DriveBase

__all__ = ["DriveBase"]
