"""The console daemon with many hubs: output latency to many browsers, uploads to many BLE hubs, and
what the daemon costs at idle.

1. Latency and loss: `openbricks console --virtual 10` (a real daemon process with 10 real virtual hub
   processes), 20 WebSocket clients on its event stream, every hub running a program that prints 100
   lines/s for DURATION_S. Each line carries the hub's clock (its RTC, set from this computer's at
   connect) and the event its daemon receive time: hub print -> client and daemon -> client
   percentiles over every line every client got, and the lines any client missed (target: p99 < 50 ms,
   0 lost). A virtual hub's clock is simulated time paced to real time: on a starved CPU it falls
   behind the wall clock, which shows up as hub -> client latency. The clients run in
   CLIENT_PROCESSES processes; on a small machine they compete with the daemon and the hubs for the
   same cores.
2. Uploads: 1, 2, 4 and 8 BLE hubs on the emulated radio (tests/server/link/fake_ble_backend.py,
   bleak's real client; a real virtual hub process behind each peripheral), a 16 KB program uploaded
   to all of them at once through their hub actors (take the hub from its launcher, stage, verify,
   hand it back), UPLOAD_ROUNDS times; the slowest hub's median rate against the single hub's
   (target >= 80 %). The link is 7.5 ms / 4 packets (130 KB/s); code compresses (zlib) on the way.
   The virtual hubs take source (their runtime is CPython): 16 KB of real example code.
3. Idle: `openbricks console --virtual 6` settled, then its resident memory and CPU over IDLE_S (the
   daemon process alone; its virtual hubs separately).
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from benchmarks import Row
from benchmarks._proc import children, load_average, proc_stat

REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))  # the emulated radio lives with the tests

HUBS = 10
CLIENTS = 20
CLIENT_PROCESSES = 4
LINES_PER_S = 100
DURATION_S = 10
UPLOAD_HUBS = (1, 2, 4, 8)
UPLOAD_BYTES = 16 * 1024
UPLOAD_ROUNDS = 5
IDLE_HUBS = 6
IDLE_S = 10
START_TIMEOUT_S = 180

PRINTER = (
    "from openbricks import log\n"
    "from openbricks.tools import wait\n"
    "for i in range({lines}):\n"
    "    print('L', i, log.epoch_ms())\n"
    "    wait({period_ms})\n"
)


# -- a console daemon process -----------------------------------------------------------------------


class ConsoleProcess:
    def __init__(self, virtual: int):
        self.root = Path(tempfile.mkdtemp(prefix="ob-bench-console-"))
        self.env = dict(
            os.environ,
            OPENBRICKS_RUNTIME_DIR=str(self.root / "run"),
            OPENBRICKS_DATA_DIR=str(self.root / "data"),
        )
        self.process = subprocess.Popen(
            [sys.executable, "-m", "openbricks_server.cli", "console", "--port", "0", "--no-ble"]
            + ["--virtual", str(virtual)],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            env=self.env,
            text=True,
        )
        runtime = self.root / "run" / "console.json"
        deadline = time.monotonic() + START_TIMEOUT_S
        while not runtime.exists():
            if self.process.poll() is not None or time.monotonic() > deadline:
                self.stop()
                raise RuntimeError(f"the console did not start: {self.process.stderr.read()[-500:]}")
            time.sleep(0.1)
        info = json.loads(runtime.read_text())
        self.url, self.token = info["url"], info["token"]
        self.headers = {"Authorization": f"Bearer {self.token}"}
        self.wait_idle(virtual, deadline)

    def get(self, path):
        import httpx

        return httpx.get(self.url + path, headers=self.headers, timeout=30).json()

    def post(self, path, body=None):
        import httpx

        reply = httpx.post(self.url + path, headers=self.headers, json=body, timeout=60)
        if reply.status_code != 200:
            raise RuntimeError(f"POST {path}: {reply.status_code} {reply.text}")
        return reply.json()

    def wait_idle(self, count: int, deadline: float) -> list[dict]:
        while time.monotonic() < deadline:
            hubs = self.get("/api/hubs")["hubs"]
            if len(hubs) >= count and all(h["status"] == "idle" for h in hubs):
                return hubs
            time.sleep(0.2)
        raise RuntimeError(f"the console's {count} hubs did not come up")

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
            try:
                self.process.wait(60)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()


# -- 1. latency and loss --------------------------------------------------------------------------


async def _client(url: str, headers: dict, lines: int, hubs: int, ready, out: dict) -> None:
    from websockets.asyncio.client import connect

    hub_lat, daemon_lat, seen = out["hub"], out["daemon"], out["seen"]
    async with connect(url, additional_headers=headers, max_size=None, compression=None) as ws:
        ready()
        # One deadline for the whole stream, not a wait_for() (a new task) per message: the clients
        # share the machine with the daemon and the hubs, and must cost as little as a browser's.
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(DURATION_S * 6 + 60):
                async for raw in ws:
                    now = time.time() * 1000
                    event = json.loads(raw)
                    if event.get("type") == "resync":
                        out["resyncs"] += 1
                    if event.get("type") != "output" or event["data"].get("from_run_log"):
                        continue
                    numbers = seen.setdefault(event["run"], set())
                    for line in event["data"]["lines"]:
                        parts = line["text"].split()
                        if len(parts) == 3 and parts[0] == "L":
                            numbers.add(int(parts[1]))
                            hub_lat.append(now - int(parts[2]))
                            daemon_lat.append(now - line["recv_ms"])
                    if sum(len(numbers) >= lines for numbers in seen.values()) >= hubs:
                        return


def _client_group(url: str, headers: dict, count: int, lines: int, hubs: int, ready, conn) -> None:
    """`count` WebSocket clients in one process (several processes: the clients do not share a GIL)."""

    async def main():
        outs = [{"hub": [], "daemon": [], "seen": {}, "resyncs": 0} for _ in range(count)]
        connected = []

        def one_ready():
            connected.append(1)
            if len(connected) == count:
                ready.set()

        await asyncio.gather(*(_client(url, headers, lines, hubs, one_ready, out) for out in outs))
        return outs

    outs = asyncio.run(main())
    conn.send(
        {
            "hub": [v for out in outs for v in out["hub"]],
            "daemon": [v for out in outs for v in out["daemon"]],
            "got": sum(min(len(n), lines) for out in outs for n in out["seen"].values()),
            "resyncs": sum(out["resyncs"] for out in outs),
        }
    )
    conn.close()


def _percentile(values: list[float], q: float) -> float:
    values = sorted(values)
    return values[min(len(values) - 1, int(q * len(values)))]


def _latency(console: ConsoleProcess) -> dict:
    import multiprocessing

    lines = LINES_PER_S * DURATION_S
    program = PRINTER.format(lines=lines, period_ms=1000 // LINES_PER_S)
    hubs = console.get("/api/hubs")["hubs"]
    url = console.url.replace("http://", "ws://") + "/api/events"
    context = multiprocessing.get_context("spawn")
    groups = []
    for _ in range(CLIENT_PROCESSES):
        ready = context.Event()
        receive, send = context.Pipe(duplex=False)
        count = CLIENTS // CLIENT_PROCESSES
        process = context.Process(
            target=_client_group, args=(url, console.headers, count, lines, len(hubs), ready, send)
        )
        process.start()
        groups.append((process, ready, receive))
    for _process, ready, _receive in groups:
        if not ready.wait(120):
            raise RuntimeError("the WebSocket clients did not connect")
    for hub in hubs:
        console.post(f"/api/hubs/{hub['hub_id']}/run", {"source": program})
    results = []
    for process, _ready, receive in groups:
        results.append(receive.recv())
        process.join(30)
    return {
        "hub": [v for r in results for v in r["hub"]],
        "daemon": [v for r in results for v in r["daemon"]],
        "lost": lines * len(hubs) * CLIENTS - sum(r["got"] for r in results),
        "expected": lines * len(hubs) * CLIENTS,
        "resyncs": sum(r["resyncs"] for r in results),
        "hubs": len(hubs),
    }


def latency_rows() -> list[Row]:
    console = ConsoleProcess(HUBS)
    try:
        cpu_before, wall_before = proc_stat(console.process.pid)[0], time.monotonic()
        figures = _latency(console)
        daemon_cpu = (proc_stat(console.process.pid)[0] - cpu_before) / (time.monotonic() - wall_before)
    finally:
        console.stop()
    setup = f"{figures['hubs']} hubs x {LINES_PER_S} lines/s x {DURATION_S} s, {CLIENTS} clients"
    rows = []
    for key, what in (("hub", "hub print -> client"), ("daemon", "daemon receive -> client")):
        values = figures[key]
        rows.append(Row(f"{what}, p50", _percentile(values, 0.5), "ms", setup))
        rows.append(Row(f"{what}, p99", _percentile(values, 0.99), "ms", "target < 50 ms"))
    rows.append(
        Row("daemon CPU while streaming", 100 * daemon_cpu, "% of a core", f"load average {load_average()}")
    )
    rows.append(
        Row(
            "lines lost (all clients)",
            figures["lost"],
            "lines",
            f"of {figures['expected']:,} deliveries; {figures['resyncs']} resyncs; target 0",
        )
    )
    return rows


# -- 2. uploads to BLE hubs -------------------------------------------------------------------------


def _upload_source() -> str:
    """16 KB of real code: example programs as functions, the last one's lines as comments to fit."""
    text = ""
    for i, path in enumerate(sorted((REPO / "examples").glob("*.py"))):
        lines = path.read_text().splitlines(keepends=True)
        part = (
            f"def part_{i}():\n" + "".join("    " + line if line.strip() else line for line in lines) + "\n"
        )
        if len((text + part).encode()) <= UPLOAD_BYTES:
            text += part
            continue
        for line in lines:
            comment = "# " + line
            if len((text + comment).encode()) > UPLOAD_BYTES:
                return text + "#" * (UPLOAD_BYTES - len(text.encode()) - 1) + "\n"
            text += comment
    raise RuntimeError("the examples hold less than 16 KB of code")


async def _uploads(count: int, source: str) -> list[float]:
    import types

    from openbricks_server.compile import Program, compile_program
    from openbricks_server.daemon.hubs.backend import start_virtual_hub
    from openbricks_server.daemon.hubs.manager import HubManager
    from tests.server.daemon.hubs.recording_events import RecordingEvents
    from tests.server.link.fake_ble_backend import FakeRadio, LinkTiming
    from tests.server.link.pty_bridge import PtyHubBridge

    root = Path(tempfile.mkdtemp(prefix="ob-bench-ble-"))
    os.environ["OPENBRICKS_DATA_DIR"] = str(root)
    radio = FakeRadio()
    names = [f"BleBot{i}" for i in range(1, count + 1)]
    # Outside the data directory's virtual-hubs/, or the manager would also find each hub there and
    # list it a second time, as a local virtual hub on its pty.
    processes = await asyncio.gather(
        *(start_virtual_hub(name, hub_dir=str(root / "on-the-radio" / name)) for name in names)
    )
    for name, hub in zip(names, processes, strict=True):
        radio.add_hub(PtyHubBridge(name, hub.pty), timing=LinkTiming(mtu=247, interval_ms=7.5))
    manager = HubManager(
        types.SimpleNamespace(virtual=0, ble=True, data_dir=root),
        RecordingEvents(),
        None,
        ble_client_backend=radio.client_backend,
        ble_scanner_backend=radio.scanner_backend,
    )
    manager.scan_s, manager.scan_pause_s = 0.5, 3600
    try:
        program = compile_program(Program("mission.py", source))
        await manager.start()
        async with asyncio.timeout(30):
            while len(actors := [a for a in manager.list() if a.state.kind == "ble"]) < count:
                await asyncio.sleep(0.1)
        await asyncio.gather(*(actor.connect(60) for actor in actors))

        async def timed(actor) -> float:
            start = time.perf_counter()
            await actor.upload(program, who="bench")
            return time.perf_counter() - start

        await asyncio.gather(*(timed(actor) for actor in actors))  # warm: the first upload of a process
        rounds = [await asyncio.gather(*(timed(actor) for actor in actors)) for _ in range(UPLOAD_ROUNDS)]
        return [statistics.median(times) for times in zip(*rounds, strict=True)]  # per hub
    finally:
        await manager.close()
        for peripheral in radio.peripherals.values():
            peripheral.hub.close()
        await asyncio.gather(*(hub.close() for hub in processes))


def upload_rows() -> list[Row]:
    source = _upload_source()
    rows = []
    single = None
    for count in UPLOAD_HUBS:
        times = asyncio.run(_uploads(count, source))
        rates = [UPLOAD_BYTES / 1024 / t for t in times]
        worst = min(rates)
        if single is None:
            single = worst
        rows.append(
            Row(
                f"16 KB upload, {count} BLE hub(s) at once, slowest hub's median",
                worst,
                "KB/s",
                f"{max(times) * 1000:.0f} ms; {100 * worst / single:.0f} % of 1 hub's rate (target >= 80 %)",
            )
        )
    return rows


# -- 3. idle cost -----------------------------------------------------------------------------------


def idle_rows() -> list[Row]:
    console = ConsoleProcess(IDLE_HUBS)
    try:
        time.sleep(3)  # the connects' log pulls and hand-backs are done
        pid = console.process.pid
        kids = children(pid)
        before = {p: proc_stat(p) for p in [pid, *kids]}
        time.sleep(IDLE_S)
        after = {p: proc_stat(p) for p in [pid, *kids]}
    finally:
        console.stop()
    daemon_cpu = 100 * (after[pid][0] - before[pid][0]) / IDLE_S
    hubs_cpu = 100 * sum(after[p][0] - before[p][0] for p in kids) / IDLE_S
    return [
        Row(
            f"daemon RSS, {IDLE_HUBS} virtual hubs connected",
            after[pid][1] / 2**20,
            "MB",
            "the daemon process",
        ),
        Row("daemon CPU at idle", daemon_cpu, "% of a core", f"over {IDLE_S} s"),
        Row(
            f"{len(kids)} virtual hub processes at idle",
            hubs_cpu,
            "% of a core",
            f"together; {sum(after[p][1] for p in kids) / 2**20:.0f} MB resident together",
        ),
    ]


def run() -> list[Row]:
    return latency_rows() + upload_rows() + idle_rows()
