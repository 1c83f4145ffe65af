"""`openbricks sim ...`: everything after `sim` goes to the simulator's own command line."""

from __future__ import annotations


def main(argv: list[str]) -> int:
    from openbricks_sim.cli import main as sim_main

    return sim_main(argv)
