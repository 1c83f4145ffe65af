# SPDX-License-Identifier: MIT
"""Run one program over many seeds of a world and tabulate the scores: a sweep before a competition.

Each seed gives the world another random layout and the sensors other noise, and one seed always
gives one run, so a seed that fails can be run again alone to see why. This runs on your computer
(not on a hub): it starts `openbricks sim run --json` once per seed and reads the one JSON object
each run prints.

    python examples/host/seed_sweep.py examples/full_robot.py --world zones --seeds 1-10
"""

import argparse
import json
import statistics
import subprocess
import sys


def seed_range(text):
    first, _, last = text.partition("-")
    return range(int(first), int(last or first) + 1)


def run(program, world, seed):
    done = subprocess.run(
        ["openbricks", "sim", "run", program, "--world", world, "--seed", str(seed), "--json"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    if not done.stdout.strip():  # a wrong argument: the reason is on stderr
        sys.exit(done.stderr.strip())
    return json.loads(done.stdout.strip().splitlines()[-1])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("program")
    parser.add_argument("--world", default="zones")
    parser.add_argument("--seeds", type=seed_range, default=seed_range("1-5"), help="e.g. 1-20")
    args = parser.parse_args()

    print("seed  exit        sim_s  x_mm    y_mm    score")
    finished = []
    for seed in args.seeds:
        result = run(args.program, args.world, seed)
        pose = result["pose"]
        print(
            "%4d  %-10s %6.1f %7.1f %7.1f  %s"
            % (seed, result["exit"], result["sim_s"], pose["x_mm"], pose["y_mm"], json.dumps(result["score"]))
        )
        finished.append(result["exit"] == "finished")
    print("finished: %d of %d (%.0f %%)" % (sum(finished), len(finished), 100 * statistics.mean(finished)))


if __name__ == "__main__":
    main()
