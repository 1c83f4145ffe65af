"""The CLI through a running console daemon: `openbricks run/upload/stop/log/list` as API calls.

When `openbricks console` runs, it owns the hub links (and holds each hub's lock), so the CLI asks it
instead of opening links of its own: the daemon's runtime file gives its URL and a local operator
token. Output, messages and exit statuses are the direct commands'. Imported only when a daemon runs:
httpx and websockets stay out of `openbricks --help`.
"""

from __future__ import annotations

import json
import sys
from urllib.parse import quote

from openbricks_server.errors import EXIT_FAILED, EXIT_INTERRUPTED, EXIT_OK, CliError

REQUEST_TIMEOUT_S = 60.0
EVENT_TIMEOUT_S = 24 * 3600.0
NOTHING_RUNNING = "no program was running"  # openbricks_server.daemon.hubs.actor's word for it
OUTCOME_STATUS = {"finished": EXIT_OK, "error": EXIT_FAILED, "stopped": EXIT_INTERRUPTED}


def running():
    """The running console's RuntimeInfo, or None (then the CLI talks to hubs directly)."""
    from openbricks_server.daemon import runtime_file

    return runtime_file.read()


class Console:
    def __init__(self, info):
        import httpx

        self.info = info
        self.http = httpx.Client(
            base_url=info.url,
            headers={"Authorization": f"Bearer {info.token}"},
            timeout=REQUEST_TIMEOUT_S,
        )

    def call(self, method: str, path: str, **kwargs) -> dict | list:
        import httpx

        try:
            reply = self.http.request(method, "/api" + path, **kwargs)
        except httpx.HTTPError as exc:
            raise CliError(
                f"the console at {self.info.url} does not answer ({exc}); stop it (Ctrl-C where it runs) "
                "or wait until it is up, then retry"
            ) from None
        if reply.status_code >= 400:
            try:
                body = reply.json()
                message = body.get("message") or reply.text
                hint = body.get("hint")
            except ValueError:
                message, hint = reply.text[:200], None
            raise CliError(f"{message}; {hint}" if hint else message)
        return reply.json()

    def events(self):
        from websockets.sync.client import connect

        url = self.info.url.replace("http://", "ws://", 1) + "/api/events"
        ws = connect(url, additional_headers={"Authorization": f"Bearer {self.info.token}"}, max_size=None)
        hello = json.loads(ws.recv(timeout=10))
        if hello.get("type") != "hello":
            ws.close()
            raise CliError(f"the console at {self.info.url} sent {hello.get('type')!r} instead of its hello")
        return ws

    def close(self) -> None:
        self.http.close()


def hub_holding(info, port: str) -> str | None:
    """The name of the console's hub whose link goes through serial port `port`, if it holds one."""
    console = Console(info)
    try:
        ports = console.call("GET", "/serial/ports")["ports"]
    except CliError:
        return None  # an older console without the port list, or one going away: nothing to say
    finally:
        console.close()
    return next((p["hub_name"] for p in ports if p["port"] == port and p["hub_id"]), None)


def refuse_held_port(port: str, instead: str) -> None:
    """Refuse a serial port whose hub a running console holds: two programs writing one port garble
    both. `instead` says how to do the same through the console ("{hub}" is the hub's name)."""
    info = running()
    held = hub_holding(info, port) if info is not None else None
    if held is not None:
        raise CliError(
            f"the console ({info.url}) holds hub {held} on {port}: {instead.format(hub=held)}, "
            "or stop the console first"
        )


def hub_path(name: str) -> str:
    return "/hubs/" + quote(name, safe="")


def _ready_hub(console: Console, name: str) -> dict:
    hub = console.call("GET", hub_path(name))
    if hub["status"] == "offline":
        hub = console.call("POST", hub_path(name) + "/connect")
    return hub


# -- the commands ------------------------------------------------------------------------------------


def list_hubs(info, args) -> int:
    console = Console(info)
    try:
        listed = console.call("GET", "/hubs")
    finally:
        console.close()
    if listed["ble"].startswith("unavailable"):
        print(f"Bluetooth scan {listed['ble']}", file=sys.stderr)
    from openbricks_server.hub_table import HubRow, print_hubs

    rows = []
    for hub in listed["hubs"]:
        if hub["kind"] == "ble":
            signal = f"{hub['rssi']} dBm" if hub["rssi"] is not None else hub["status"]
            rows.append(HubRow(hub["name"], "hub", hub["address"], f"{signal}, {hub['status']}"))
        else:
            state = "running a program" if hub["status"] == "running" else hub["status"]
            rows.append(HubRow(hub["name"], hub["kind"], hub["hub_id"], state))
    print_hubs(rows, args.json, f"no hubs found (the console at {info.url} knows none)")
    return EXIT_OK


def stop(info, args) -> int:
    console = Console(info)
    try:
        _ready_hub(console, args.name)
        report = console.call("POST", hub_path(args.name) + "/stop")
    finally:
        console.close()
    if not report["stopped"] and report["detail"] != NOTHING_RUNNING:
        raise CliError(f"{args.name} still reports a running program after Ctrl-C; press its program button")
    print(f"{args.name}: {report['detail']}")
    return EXIT_OK


def upload(info, args, program) -> int:
    console = Console(info)
    try:
        _ready_hub(console, args.name)
        body = {"source": program.source, "name": program.filename, "path": args.path}
        done = console.call("POST", hub_path(args.name) + "/upload", json=body)
    finally:
        console.close()
    if args.path is None:
        where = f"{done['path']} on {args.name}"
        print(f"staged {program.filename} at {where}: press the program button to start it")
    else:
        print(f"stored {program.filename} at {done['path']} on {args.name}, as it is")
    return EXIT_OK


def log(info, args) -> int:
    from openbricks_server.logview import LogRenderer, print_runs

    console = Console(info)
    try:
        _ready_hub(console, args.name)
        runs = console.call("GET", hub_path(args.name) + "/logs")
        if args.list:
            print_runs(args.name, runs, args.json)
            return EXIT_OK
        indices = [entry["index"] for entry in runs]
        if not indices:
            raise CliError(f"{args.name} has no run logs yet: runs are logged when a program runs")
        index = indices[-1] if args.run is None else args.run
        if index not in indices:
            raise CliError(
                f"{args.name} has no log of run {index} (kept: {', '.join(str(i) for i in indices)}); older "
                "runs were overwritten"
            )
        text = console.call("GET", hub_path(args.name) + f"/logs/{index}")["text"]
    finally:
        console.close()
    renderer = LogRenderer(sys.stdout.write)
    renderer.feed(text)
    renderer.finish()
    sys.stdout.flush()
    return EXIT_OK


def _stored_name(filename: str) -> str:
    """The console's name for a program: `run -c` code (`<code>`) is `code.py` there."""
    from openbricks_server.compile import CODE_FILENAME

    return "code.py" if filename == CODE_FILENAME else filename


def _value(value: float) -> str:
    return json.dumps(int(value) if float(value).is_integer() else value)


class _RunFollower:
    """Prints one run's events as the direct command prints the hub's output."""

    def __init__(self, console: Console, name: str):
        self.console = console
        self.name = name
        self.run_id: str | None = None
        self.last_line = 0
        self.buffered: list[dict] = []
        self.outcome: str | None = None

    def handle(self, event: dict) -> None:
        if event.get("run") != self.run_id:
            if self.run_id is None and event.get("run"):
                self.buffered.append(event)  # ours, perhaps, before the run id is known
            return
        kind, data = event["type"], event.get("data") or {}
        if kind == "output" and not data.get("from_run_log"):
            self._lines(data["lines"])
        elif kind == "telemetry":
            for sample in data["samples"]:
                print(f"plot: {sample['name']} = {_value(sample['value'])}", flush=True)
        elif kind == "run_gap":
            print(f"\nlink to {self.name} dropped ({data['reason']}); reconnecting ...", file=sys.stderr)
            if data.get("until_ms") is not None:
                print(f"reconnected to {self.name}; output continues", file=sys.stderr, flush=True)
        elif kind == "run_ended":
            self.outcome = data.get("outcome") or "error"

    def _lines(self, lines: list[dict]) -> None:
        for line in lines:
            if line["line_no"] > self.last_line:
                print(line["text"], flush=True)
                self.last_line = line["line_no"]

    def started(self, run_id: str) -> None:
        self.run_id = run_id
        waiting, self.buffered = self.buffered, []
        for event in waiting:
            self.handle(event)

    def catch_up(self) -> None:
        """After a resync or gap notice: the run's lines from the store."""
        page = self.console.call("GET", f"/runs/{self.run_id}/output", params={"after": self.last_line})
        self._lines(page["lines"])


def run(info, args, program) -> int:
    console = Console(info)
    try:
        hub = _ready_hub(console, args.name)
        print(f"{args.name}: firmware {hub['firmware']}", file=sys.stderr, flush=True)
        ws = console.events()
        follower = _RunFollower(console, args.name)
        try:
            body = {"source": program.source, "name": _stored_name(program.filename)}
            started = console.call("POST", hub_path(args.name) + "/run", json=body)
            follower.started(started["run_id"])
            _follow(console, ws, follower, args.name)
        finally:
            ws.close()
    finally:
        console.close()
    outcome = follower.outcome
    if outcome == "stopped":
        print(f"stopped: {args.name} confirmed the program ended (run {follower.run_id})", file=sys.stderr)
    elif outcome == "error":
        print(f"the program ended with an error (run {follower.run_id})", file=sys.stderr)
    elif outcome == "dropped":
        raise CliError(
            f"the link to {args.name} was lost; what arrived before is shown above. If a program was running "
            f"it may still run: `openbricks log -n {args.name}` shows its output later"
        )
    return OUTCOME_STATUS.get(outcome, EXIT_FAILED)


class _StopSignal(KeyboardInterrupt):
    """SIGTERM or SIGHUP, handled as Ctrl-C is (openbricks_server.commands.run.STOP_SIGNALS)."""


def _follow(console: Console, ws, follower: _RunFollower, name: str) -> None:
    """The run's events until it ends. The first Ctrl-C (or SIGTERM, SIGHUP) asks the console to stop
    it and keeps following until the hub confirms; a second one leaves without the confirmation."""
    import signal

    from openbricks_server.commands.run import STOP_SIGNALS, say

    def on_signal(number, _frame):
        raise _StopSignal(STOP_SIGNALS[number])

    previous = {
        number: signal.signal(number, on_signal) for number in STOP_SIGNALS if number != signal.SIGINT
    }
    stopping = False
    try:
        while follower.outcome is None:
            try:
                event = json.loads(ws.recv(timeout=EVENT_TIMEOUT_S))
                if event.get("type") in ("resync", "gap"):
                    follower.catch_up()
                    continue
                follower.handle(event)
            except KeyboardInterrupt as exc:
                if stopping:
                    raise CliError(
                        f"left without waiting for {name} to confirm the stop; check it with "
                        f"`openbricks stop -n {name}`",
                        EXIT_INTERRUPTED,
                    ) from None
                stopping = True
                what = exc.args[0] if isinstance(exc, _StopSignal) else "^C"
                say(f"\n{what}: stopping the program on {name} ...")
                console.call("POST", hub_path(name) + "/stop")
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)
