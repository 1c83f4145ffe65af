"""python -m openbricks_sim.virtual_hub --name RobotA [--pty] [--dir DIR] [--world W] ...

Runs one virtual hub in this process until it is stopped (SIGTERM, SIGINT, or the end of stdin in
stdio mode; SIGHUP switches it off once the program running has ended). With --pty the first line
on stdout is the path of the pseudo-terminal to connect to (`mpremote connect <path>`), the second
`control <path>` names the control socket; without it the hub talks over stdin/stdout. Once up, the
hub also records both in `endpoint.json` in its directory,
which is how `openbricks` finds it (endpoint.py).

The process is the hub's sandbox: user code runs here, under an address-space limit (--memory-mb)
and per-run time limits, never in the process that started it.
"""

import argparse
import faulthandler
import os
import re
import signal
import sys
import threading

from ..job import CHASSIS_NAMES, add_seed_argument
from ..limits import DEFAULT_MEMORY_MB, contain
from . import endpoint
from .control import ControlServer
from .hub import HubBusyError, HubConfig, VirtualHub
from .hub_fs import DEFAULT_CAPACITY_BYTES
from .repl import DEFAULT_PASTE_WINDOW
from .transport import PtyPort, StdioPort

DATA_DIR_ENV = "OPENBRICKS_DATA_DIR"
HUBS_SUBDIR = "virtual-hubs"
NAME_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9_-]{0,28}")


def hubs_dir():
    """Where virtual hubs keep their flash and NVS: <data dir>/virtual-hubs (OPENBRICKS_DATA_DIR or
    the user data dir, ~/.local/share/openbricks on Linux)."""
    root = os.environ.get(DATA_DIR_ENV)
    if root:
        return os.path.join(os.path.expanduser(root), HUBS_SUBDIR)
    import platformdirs

    return os.path.join(platformdirs.user_data_dir("openbricks", appauthor=False), HUBS_SUBDIR)


def _hub_name(text):
    if not NAME_PATTERN.fullmatch(text):
        raise argparse.ArgumentTypeError(
            f"{text!r}: a hub name is 1-29 letters, digits, '-' or '_', starting with a letter or digit "
            "(it is advertised over BLE and names the hub's directory)"
        )
    return text


def _speed(text):
    if text in ("max", "0"):
        return None
    value = float(text)
    if not value > 0:
        raise argparse.ArgumentTypeError("--speed is a positive real-time factor, or 'max'")
    return value


def parse_args(argv=None):
    parser = argparse.ArgumentParser(
        prog="python -m openbricks_sim.virtual_hub",
        description="Run a simulated openbricks hub that speaks MicroPython's REPL over a pty or stdio.",
    )
    parser.add_argument("--name", "-n", required=True, type=_hub_name, help="the hub's name (NVS hub_name)")
    parser.add_argument("--pty", action="store_true", help="serve on a new pseudo-terminal (else stdio)")
    parser.add_argument("--dir", help="the hub's directory (default: <data dir>/virtual-hubs/NAME)")
    parser.add_argument(
        "--world", default="empty", help="world alias, world file (.toml) or MJCF file (default: empty)"
    )
    parser.add_argument("--chassis", default="st3032", choices=CHASSIS_NAMES, help="default: st3032")
    add_seed_argument(parser)
    parser.add_argument(
        "--speed",
        type=_speed,
        default=1.0,
        help="program runs at this real-time factor, or 'max' (default: 1); idle time is real time",
    )
    parser.add_argument(
        "--paste-window",
        type=int,
        default=DEFAULT_PASTE_WINDOW,
        help=f"raw-paste flow-control window in bytes (default: {DEFAULT_PASTE_WINDOW})",
    )
    parser.add_argument(
        "--flash-kb", type=int, default=DEFAULT_CAPACITY_BYTES // 1024, help="flash filesystem size"
    )
    parser.add_argument("--run-limit-ms", type=int, help="simulated-time limit of each program run")
    parser.add_argument("--run-wall-limit-s", type=float, help="wall-clock limit of each program run")
    parser.add_argument(
        "--memory-mb",
        type=int,
        default=DEFAULT_MEMORY_MB,
        help=f"address-space limit of the process, 0 for none (default: {DEFAULT_MEMORY_MB})",
    )
    args = parser.parse_args(argv)
    if not 1 <= args.paste_window <= 0xFFFF:
        parser.error("--paste-window must be 1..65535 bytes")
    if args.flash_kb < 64:
        parser.error("--flash-kb must be at least 64")
    return args


def main(argv=None):
    args = parse_args(argv)
    directory = os.path.abspath(args.dir or os.path.join(hubs_dir(), args.name))
    config = HubConfig(
        name=args.name,
        directory=directory,
        world=args.world,
        chassis=args.chassis,
        seed=args.seed,
        speed=args.speed,
        paste_window=args.paste_window,
        flash_bytes=args.flash_kb * 1024,
        run_sim_limit_ms=args.run_limit_ms,
        run_wall_limit_s=args.run_wall_limit_s,
    )
    announce = sys.stdout
    port = PtyPort() if args.pty else StdioPort()
    try:
        hub = VirtualHub(config, port)
    except (HubBusyError, ValueError, OSError) as exc:
        port.close()
        print(f"virtual hub {args.name}: {exc}", file=sys.stderr)
        return 2
    control = ControlServer(hub, os.path.join(directory, endpoint.CONTROL_SOCKET)).start()
    hub.control_path = control.path
    contain(memory_mb=args.memory_mb)

    def ready():
        pty = port.path if args.pty else None
        endpoint.write(directory, name=args.name, pid=os.getpid(), pty=pty, control=control.path)
        if args.pty:
            announce.write(f"{port.path}\ncontrol {control.path}\n")
            announce.flush()

    def stop(_signum, _frame):
        # Not here: a signal handler runs on the main thread, possibly inside the gate's lock.
        threading.Thread(target=hub.shutdown, daemon=True).start()

    faulthandler.register(signal.SIGUSR1)  # `kill -USR1 <pid>`: every thread's stack to stderr
    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    # SIGHUP: the host hung up (the console that started this hub died, or its terminal closed).
    signal.signal(signal.SIGHUP, lambda _signum, _frame: hub.power_off_when_idle())
    try:
        hub.serve(on_ready=ready)
    finally:
        endpoint.remove(directory)
        control.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
