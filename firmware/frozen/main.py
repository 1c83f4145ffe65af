"""Frozen main.py: what a hub does at power-up (openbricks.power_up says what; a user's /main.py
replaces it)."""

from openbricks import power_up

power_up.main(globals())
