# SPDX-License-Identifier: MIT
"""Run one program on every hub the console holds, wait for each run to end, and print a table.

This runs on your computer, not on a hub: it talks to `openbricks console` over its REST API, the
same API the browser console uses. Give it the console's address and a token (the operator token
the console printed, or one minted with `openbricks console token --role operator`):

    python examples/host/run_on_every_hub.py examples/first_robot.py \\
        --console http://127.0.0.1:8765 --token TOKEN

Every hub gets the program at once (each run starts as soon as its hub has it), and the script then
reads each run's outcome and output from the history. A hub that is busy or offline gets a line that
says why instead of a run.
"""

import argparse
import os
import sys
import time

import httpx

TIMEOUT_S = 120.0


def start_everywhere(api, source, name):
    """{hub name: run id} for every hub that started the program, and one line per hub that did not."""
    started, refused = {}, []
    for hub in api.get("/api/hubs").json()["hubs"]:
        reply = api.post("/api/hubs/%s/run" % hub["hub_id"], json={"source": source, "name": name})
        if reply.status_code == 200:
            started[hub["name"]] = reply.json()["run_id"]
        else:  # every error has the same shape: error, message, hint
            error = reply.json()
            refused.append("%s: %s (%s)" % (hub["name"], error["message"], error["hint"]))
    return started, refused


def wait_for(api, run_id):
    """The run's record once it has ended (outcome finished, error, stopped, ...)."""
    deadline = time.monotonic() + TIMEOUT_S
    while time.monotonic() < deadline:
        run = api.get("/api/runs/%s" % run_id).json()
        if run["outcome"] is not None:
            return run
        time.sleep(0.5)
    sys.exit("run %s did not end within %d s" % (run_id, TIMEOUT_S))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("program")
    parser.add_argument("--console", default=os.environ.get("OPENBRICKS_CONSOLE", "http://127.0.0.1:8765"))
    parser.add_argument("--token", default=os.environ.get("OPENBRICKS_TOKEN"), required=False)
    args = parser.parse_args()
    if not args.token:
        sys.exit("give the console's token with --token or OPENBRICKS_TOKEN")
    with open(args.program, encoding="utf-8") as f:
        source = f.read()

    headers = {"Authorization": "Bearer " + args.token}
    with httpx.Client(base_url=args.console, headers=headers, timeout=30) as api:
        started, refused = start_everywhere(api, source, os.path.basename(args.program))
        for line in refused:
            print("not started - " + line)
        for hub_name, run_id in sorted(started.items()):
            run = wait_for(api, run_id)
            lines = api.get("/api/runs/%s/output" % run_id).json()["lines"]
            last = lines[-1]["text"] if lines else ""
            print("%-12s %-9s %4d lines  last: %s" % (hub_name, run["outcome"], run["line_count"], last))


if __name__ == "__main__":
    main()
