"""The fault harness: whole host sessions (enter the raw REPL, info, upload by raw-paste host calls,
run with streamed output, read the run log back) over a `FaultyLink`, one seeded fault each, on
the emulated BLE radio (bleak's real client, the scripted hub) and on a real virtual hub's pty.

Each session ends one of three ways: "ok" (it completed; the lines the host showed and read back
are compared with the hub's own run log), "failed" (a named `LinkError` within its timeout, the
way a user sees it), or "hang" (still going when every timeout it has should have fired). Lines
lost are lines of the hub's run log that a session which reported the run as done did not show
(or read back) intact. `python -m benchmarks fault_injection` runs 10,000 seeds; the test suite
a small sample (tests/server/link/test_fault_harness.py).
"""

from __future__ import annotations

import asyncio
import os
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

from openbricks_server.link import LinkError
from openbricks_server.link.ble import BleLink
from openbricks_server.link.raw_repl import RawRepl
from openbricks_server.link.virtual import spawn_pty_hub
from tests.server.link.fake_ble_backend import HubBench, LinkTiming
from tests.server.link.faults import FaultyLink, seeded_faults

STEP_TIMEOUT_S = 0.6  # every wait of a session (the hubs answer in milliseconds)
RUN_TIMEOUT_S = 1.5
# Longer than every wait a session makes, one after another (a reconnect included): past this, a
# session that still runs is a hang.
HANG_S = 30.0
LINES = 12
PROGRAMS = {
    "ble": f"for i in range({LINES}):\n    print('line', i, 'of the run')\n    sleep_ms(2)\n",
    "pty": (
        f"import time\nfor i in range({LINES}):\n    print('line', i, 'of the run')\n    time.sleep_ms(2)\n"
    ),
}


@dataclass
class Outcome:
    seed: int
    transport: str
    result: str  # "ok", "failed" or "hang"
    error: str | None = None  # the named error of a failed session
    faults: list[str] = field(default_factory=list)
    lines_logged: int = 0
    lines_lost: int = 0
    seconds: float = 0.0


@dataclass
class Tally:
    sessions: int = 0
    ok: int = 0
    hangs: int = 0
    failures: Counter = field(default_factory=Counter)
    unnamed: Counter = field(default_factory=Counter)  # errors that are not LinkErrors: bugs
    lines_logged: int = 0
    lines_lost: int = 0
    slowest_failure_s: float = 0.0
    examples: dict = field(default_factory=dict)  # one seed per failure kind, to reproduce it

    def add(self, outcome: Outcome) -> None:
        self.sessions += 1
        self.lines_logged += outcome.lines_logged
        self.lines_lost += outcome.lines_lost
        if outcome.lines_lost:
            self.examples.setdefault("lines lost", (outcome.transport, outcome.seed, outcome.faults))
        if outcome.result == "ok":
            self.ok += 1
        elif outcome.result == "hang":
            self.hangs += 1
            self.examples.setdefault("hang", (outcome.transport, outcome.seed, outcome.faults))
        else:
            kind = outcome.error or "?"
            target = self.failures if not kind.startswith("unnamed ") else self.unnamed
            target[kind] += 1
            self.examples.setdefault(kind, (outcome.transport, outcome.seed, outcome.faults))
            self.slowest_failure_s = max(self.slowest_failure_s, outcome.seconds)


def _program_lines(text: str) -> list[str]:
    """The program's own lines in console output or a run log (whose lines carry a stamp first)."""
    lines = []
    for line in text.replace("\r\n", "\n").split("\n"):
        stamp, _, rest = line.partition(" ")
        if stamp.isdigit() and rest.startswith("line "):
            line = rest
        if line.startswith("line "):
            lines.append(line)
    return lines


def _error_kind(exc: BaseException) -> str:
    if isinstance(exc, LinkError):
        what = getattr(exc, "what", None)
        return f"{type(exc).__name__} ({what})" if what else type(exc).__name__
    return f"unnamed {type(exc).__name__}: {exc}"[:160]


class Bench:
    """One hub and its inner link, reused by every session on this transport."""

    transport = ""

    async def start(self) -> None:
        raise NotImplementedError

    async def stop(self) -> None:
        await self.inner.close()

    def runs_started(self) -> int:
        raise NotImplementedError

    def log_lines(self, run: int | None) -> list[str]:
        """The program lines of the hub's newest run log, read straight from the hub's side."""
        raise NotImplementedError


class BleBench(Bench):
    transport = "ble"

    async def start(self) -> None:
        self.bench = HubBench()
        timing = LinkTiming(interval_ms=1.0, supervision_timeout_ms=50.0, connect_grace_ms=20.0)
        self.peripheral = self.bench.add("FaultBle", timing=timing, stdin_buffer_max=4096)
        self.hub = self.peripheral.hub
        self.inner = BleLink(
            "FaultBle",
            client_backend=self.bench.radio.client_backend,
            scanner_backend=self.bench.radio.scanner_backend,
            scan_timeout_s=1.0,
            connect_timeout_s=STEP_TIMEOUT_S * 3,
        )

    def runs_started(self) -> int:
        return self.hub.runs

    def log_lines(self, run: int | None) -> list[str]:
        return _program_lines(self.hub.run_logs.get(self.hub.runs, ""))


class PtyBench(Bench):
    transport = "pty"

    def __init__(self, directory: Path):
        self.directory = directory

    async def start(self) -> None:
        self.pty = await spawn_pty_hub("FaultPty", hub_dir=str(self.directory), extra_args=["--speed", "max"])
        self.inner = self.pty.link

    async def stop(self) -> None:
        await self.pty.stop()

    def _slots(self) -> list[Path]:
        return sorted((self.directory / "flash" / "openbricks_logs").glob("slot_*.log"), key=os.path.getmtime)

    def runs_started(self) -> int:
        slots = self._slots()
        if not slots:
            return -1
        header = slots[-1].read_text(errors="replace").split("\n", 1)[0]
        return int(header.rsplit("run_", 1)[-1].split()[0])

    def log_lines(self, run: int | None) -> list[str]:
        slots = self._slots()
        if not slots:
            return []
        return _program_lines(slots[-1].read_text(errors="replace"))


async def _read_log(repl: RawRepl, run: int) -> str:
    text, offset = "", 0
    while offset is not None:
        page, offset = await repl.read_run_page(run, offset)
        text += page
    return text


async def session(bench: Bench, seed: int, sizes: tuple[int, int], faults_per_session: int = 1) -> Outcome:
    faults = seeded_faults(seed, *sizes, count=faults_per_session) if seed >= 0 else []
    outcome = Outcome(seed, bench.transport, "ok")
    link = FaultyLink(bench.inner, faults)
    shown = bytearray()
    result = log_text = None
    before = bench.runs_started()
    started = time.perf_counter()
    try:
        async with asyncio.timeout(HANG_S):
            try:
                await link.connect(STEP_TIMEOUT_S * 3)
                repl = RawRepl(link, timeout_s=STEP_TIMEOUT_S)
                await repl.enter(timeout_s=STEP_TIMEOUT_S * 2, retry_s=0.3)
                await repl.info()
                await repl.put("/program.py", PROGRAMS[bench.transport].encode())
                result = await repl.run("/program.py", on_output=shown.extend, timeout_s=RUN_TIMEOUT_S)
                if result.get("outcome") != "finished" or result.get("run") is None:
                    outcome.result, outcome.error = "failed", f"run ended {result.get('outcome')}"
                else:
                    log_text = await _read_log(repl, result["run"])
            except Exception as exc:  # noqa: BLE001 - the kind is the finding
                outcome.result, outcome.error = "failed", _error_kind(exc)
    except TimeoutError:
        outcome.result = "hang"
    finally:
        try:
            async with asyncio.timeout(5):
                await link.close()
        except (TimeoutError, LinkError, OSError):
            pass
    outcome.seconds = time.perf_counter() - started
    outcome.faults = [f.describe() for f in link.fired]
    if result is not None and bench.runs_started() != before:
        truth = bench.log_lines(result.get("run"))
        outcome.lines_logged = len(truth)
        # What the host showed: the streamed output, and the lines it restored from the run log.
        restored = "\n".join(result.get("damaged_lines") or [])
        lost = Counter(truth) - Counter(_program_lines(shown.decode("utf-8", "replace") + "\n" + restored))
        if log_text is not None:
            lost |= Counter(truth) - Counter(_program_lines(log_text))
        outcome.lines_lost = sum(lost.values())
    return outcome


async def measure_sizes(bench: Bench) -> tuple[int, int]:
    """Bytes each way in a clean session: where the seeded faults are spread."""
    link = FaultyLink(bench.inner, [])
    repl = RawRepl(link, timeout_s=STEP_TIMEOUT_S * 5)
    await link.connect()
    await repl.enter()
    await repl.info()
    await repl.put("/program.py", PROGRAMS[bench.transport].encode())
    result = await repl.run("/program.py", timeout_s=RUN_TIMEOUT_S * 5)
    await _read_log(repl, result["run"])
    sizes = (link._seen["to_hub"], link._seen["to_host"])
    await link.close()
    return sizes


async def run_seeds(bench: Bench, seeds, tally: Tally, on_outcome=None) -> Tally:
    sizes = await measure_sizes(bench)
    for seed in seeds:
        outcome = await session(bench, seed, sizes)
        tally.add(outcome)
        if on_outcome is not None:
            on_outcome(outcome)
    return tally
