"""The running hub's endpoint record: where a host reaches it, kept in the hub's own directory.

`endpoint.json` holds the process id, the pty its REPL is served on and the path of its control
socket. The socket is not always in the hub directory: a Unix socket path is capped near 108 bytes,
so a hub under a deep data dir puts it in a temp folder (control.py). Discovery reads this record
instead of guessing the socket's place, and trusts it only while its pid matches the one in the
directory's held lock, so a record left by a killed hub is never followed.

The record is written once the hub is up (atomically: a reader sees the old record or the new one,
never half of one) and removed when the hub stops.
"""

import json
import os

# The hub directory as discovery (openbricks_server.link.discovery) reads it: the record, the lock a
# running hub holds (hub.py), and its control socket's usual place (control.py).
FILE_NAME = "endpoint.json"
LOCK_FILE = "hub.lock"
CONTROL_SOCKET = "control.sock"
FORMAT = 1


def write(directory, *, name, pid, pty, control):
    """Publish how to reach the hub that runs in `directory`."""
    record = {"format": FORMAT, "name": name, "pid": pid, "pty": pty, "control": control}
    path = os.path.join(directory, FILE_NAME)
    part = path + ".part"
    with open(part, "w") as f:
        json.dump(record, f)
        f.write("\n")
    os.replace(part, path)
    return path


def remove(directory):
    """Withdraw the record as the hub stops (only the lock holder ever writes it)."""
    try:
        os.remove(os.path.join(directory, FILE_NAME))
    except OSError:
        pass
