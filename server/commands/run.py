"""`openbricks run`: compile, stage as the button program, run it and stream its output.

Ctrl-C sends the hub a stop (Ctrl-C over the REPL); the output keeps streaming until the hub reports
the run as stopped, which is the confirmation. A second Ctrl-C leaves without waiting for it. SIGTERM
(what `timeout` and process managers send) and SIGHUP (the terminal closed) do the same as Ctrl-C,
so the program never keeps running on the hub behind a CLI that was told to end. The exit status
is the program's outcome: 0 finished, 1 error, 130 stopped.
"""

from __future__ import annotations

import asyncio
import signal
import sys

from openbricks_server.compile import code_program, read_program
from openbricks_server.errors import EXIT_FAILED, EXIT_INTERRUPTED, EXIT_OK, CliError
from openbricks_server.hub_session import with_hub
from openbricks_server.link import HubException
from openbricks_server.staging import prepare, stage

RUN_TIMEOUT_S = 24 * 3600.0  # a mission may run long; the link's own drop detection catches dead hubs
OUTCOME_STATUS = {"finished": EXIT_OK, "error": EXIT_FAILED, "stopped": EXIT_INTERRUPTED}


STOP_SIGNALS = {signal.SIGINT: "^C", signal.SIGTERM: "SIGTERM", signal.SIGHUP: "SIGHUP"}


def say(text: str) -> None:
    """A line on stderr; a terminal that hung up (SIGHUP) takes nothing more, and that is fine."""
    try:
        print(text, file=sys.stderr, flush=True)
    except OSError:
        pass


class TerminalOutput:
    """The hub's output on our stdout as it arrives, with its CRLF line ends made plain newlines.

    A stdout that went away (a closed terminal, a reader that quit) stops the showing, not the run:
    the run still ends as the hub reports it."""

    def __init__(self, stream=None):
        self.stream = stream or sys.stdout.buffer
        self._held_cr = False
        self._gone = False

    def __call__(self, data: bytes) -> None:
        if self._held_cr:
            data = b"\r" + data
            self._held_cr = False
        if data.endswith(b"\r"):
            data, self._held_cr = data[:-1], True
        if self._gone:
            return
        try:
            self.stream.write(data.replace(b"\r\n", b"\n"))
            self.stream.flush()
        except OSError:
            self._gone = True


class StopOnSignal:
    """First Ctrl-C (or SIGTERM, SIGHUP): ask the hub to stop and keep streaming until it confirms;
    a second one: leave without the confirmation."""

    def __init__(self, session, task: asyncio.Task):
        self.session = session
        self.task = task
        self.requested = False
        self.abandoned = False

    def __call__(self, name: str = "^C") -> None:
        if not self.requested:
            self.requested = True
            say(f"\n{name}: stopping the program on {self.session.name} ...")
            asyncio.ensure_future(self.session.repl.interrupt())
            return
        self.abandoned = True
        self.task.cancel()


def _link_event(event) -> None:
    if event.kind == "dropped":
        print(
            f"\nlink to {event.hub} dropped ({event.detail}); reconnecting ...", file=sys.stderr, flush=True
        )
    else:
        print(f"reconnected to {event.hub}; output continues", file=sys.stderr, flush=True)


async def _talk(session, program):
    print(f"{session.name}: firmware {session.info.firmware}", file=sys.stderr, flush=True)
    path = await stage(session, program)
    loop = asyncio.get_running_loop()
    stopper = StopOnSignal(session, asyncio.current_task())
    for number, name in STOP_SIGNALS.items():
        loop.add_signal_handler(number, stopper, name)
    try:
        result = await session.repl.run(
            path,
            name=program.filename,
            on_output=TerminalOutput(),
            on_link_event=_link_event,
            timeout_s=RUN_TIMEOUT_S,
        )
    except HubException as exc:
        # A stop that lands mid-print can end the run before its result line is out: the hub's
        # KeyboardInterrupt after our Ctrl-C is then the confirmation.
        if not (stopper.requested and "KeyboardInterrupt" in exc.traceback):
            raise
        result = {"outcome": "stopped", "run": None}
    except asyncio.CancelledError:
        if stopper.abandoned:
            raise CliError(
                f"left without waiting for {session.name} to confirm the stop; check it with "
                f"`openbricks stop -n {session.name}`",
                EXIT_INTERRUPTED,
            ) from None
        raise
    finally:
        for number in STOP_SIGNALS:
            loop.remove_signal_handler(number)
    _report_damage(session.name, result)
    outcome = result.get("outcome", "error")
    which = "before it started" if result.get("run") is None else f"(run {result['run']})"
    if outcome == "stopped":
        say(f"stopped: {session.name} confirmed the program ended {which}")
    elif outcome == "error":
        say(f"the program ended with an error {which}")
    return outcome


def _report_damage(name: str, result: dict) -> None:
    """Output that did not arrive intact (a damaged or dropped link): the lines from the run log."""
    damaged = result.get("damaged_lines")
    if damaged:
        say(f"\n{len(damaged)} line(s) of the output above did not arrive intact; from {name}'s run log:")
        TerminalOutput()("".join(line + "\n" for line in damaged).encode())
    elif result.get("unverified"):
        say(
            f"\nthe output above may be incomplete, and {name}'s run log could not be read to check it "
            f"({result['unverified']}); read it with `openbricks log -n {name} --run {result.get('run')}`"
        )


def main(args) -> int:
    program = code_program(args.code) if args.code is not None else read_program(args.script)
    program = prepare(program)
    from openbricks_server import console_client

    console = console_client.running()
    if console is not None:  # the console owns the hub links: through it, same output and status
        return console_client.run(console, args, program)
    outcome = asyncio.run(
        with_hub(args.name, args.scan_timeout, lambda session: _talk(session, program), debug=args.debug)
    )
    return OUTCOME_STATUS.get(outcome, EXIT_FAILED)
