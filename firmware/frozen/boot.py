"""Frozen boot.py: runs once after every reset, before main.py (openbricks.power_up says what it does;
a user's /boot.py still runs, since a frozen boot.py would otherwise hide it)."""

from openbricks import power_up

power_up.boot(globals())
