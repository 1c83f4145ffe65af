# SPDX-License-Identifier: MIT
"""Flash a box of hubs at once through the console: one job per USB port, a table of results.

This runs on your computer, not on a hub. `openbricks console` does the flashing (esptool, the
chip and offset checks, writing each hub's name); the script uploads the image, starts one job per
port and waits for each job's own result:

    python examples/host/flash_many.py firmware.bin --console http://127.0.0.1:8765 --token TOKEN

Without --ports it flashes every ESP32 board the console sees on USB (GET /api/serial/ports). Hubs
are named PREFIX01, PREFIX02, ... in port order (--prefix, default Robot). A board that fails does
not stop the others: its row says why.
"""

import argparse
import os
import sys

import httpx

JOB_WAIT_S = 300


def esp_ports(api):
    return [p["port"] for p in api.get("/api/serial/ports").json()["ports"] if p["esp"]]


def upload(api, path):
    """The console's id for the image; it checks the image (chip, partition table) as it arrives."""
    with open(path, "rb") as f:
        reply = api.post(
            "/api/flash/firmware",
            params={"filename": os.path.basename(path)},
            content=f.read(),
            headers={"Content-Type": "application/octet-stream"},
        )
    if reply.status_code != 200:
        sys.exit("%s: %s" % (path, reply.json()["message"]))
    image = reply.json()
    print("image %s: %s %s at 0x%x" % (image["filename"], image["chip"], image["version"], image["offset"]))
    return image["firmware_id"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("firmware", help="the firmware .bin to write")
    parser.add_argument("--ports", nargs="+", help="serial ports; default: every ESP board on USB")
    parser.add_argument("--prefix", default="Robot", help="hub names: PREFIX01, PREFIX02, ...")
    parser.add_argument("--console", default=os.environ.get("OPENBRICKS_CONSOLE", "http://127.0.0.1:8765"))
    parser.add_argument("--token", default=os.environ.get("OPENBRICKS_TOKEN"))
    args = parser.parse_args()
    if not args.token:
        sys.exit("give the console's operator token with --token or OPENBRICKS_TOKEN")

    headers = {"Authorization": "Bearer " + args.token}
    with httpx.Client(base_url=args.console, headers=headers, timeout=30) as api:
        ports = args.ports or esp_ports(api)
        if not ports:
            sys.exit("no ESP32 board on USB: plug them in, or name the ports with --ports")
        firmware = upload(api, args.firmware)
        targets = [{"port": port, "name": "%s%02d" % (args.prefix, i)} for i, port in enumerate(ports, 1)]
        reply = api.post("/api/flash", json={"targets": targets, "firmware": firmware})
        if reply.status_code != 200:
            error = reply.json()
            sys.exit("%s (%s)" % (error["message"], error["hint"]))
        failed = 0
        for started in reply.json()["jobs"]:  # the console holds each request until that job has ended
            wait = {"wait_s": JOB_WAIT_S}
            job = api.get("/api/flash/" + started["job_id"], params=wait, timeout=JOB_WAIT_S + 30).json()
            name = job["params"].get("name", "")
            if job["state"] == "done":
                print("%-20s %-10s flashed" % (job["label"], name))
            else:
                failed += 1
                print("%-20s %-10s %s: %s" % (job["label"], name, job["state"], job["message"]))
        print("%d of %d flashed" % (len(targets) - failed, len(targets)))
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
