"""Sim runs as daemon jobs: one child process each, steered over its stdin, heard over its stdout.

User code never runs in the daemon. A run's child (`openbricks_sim.console_job`) fences itself in
(memory, CPU time, no new processes), serves the run's 3D view on 127.0.0.1 and records it. It is
forked by the daemon's warm fork server (warm.py), so its imports are already done; spawned cold
where that cannot be. This side:

- starts it in a session of its own with the program's stored text written into the run's directory
  under the data dir (`sim/RUN_ID/`), where the recording and the child's own log land too;
- turns its events into the daemon's: output lines and telemetry (pose, wheel speeds) through the
  same `HubEvents` seam hub runs use (so they are in the history, searchable and replayed to
  reconnecting clients), and `job` events for the Jobs the console pages follow; the program's output
  goes through a hub's `OutputParser` with the nonce the child tags plot() frames with, so its
  samples are telemetry (stamped with the simulated clock), never output lines, exactly as on a hub;
- pauses, resumes, changes speed and stops it; a child that does not end STOP_GRACE_S after a stop,
  or is still alive WALL_GRACE_S past its wall-clock limit, is killed (its whole session);
- records how it ended: the child's result, or, when it died without one, what ended it.

A run in the history is a row of `runs` (hub SIM_HUB, origin "sim", the exit reason as its outcome)
and one of `sim_runs` (world, chassis, seed, limits, state, score, final pose, recording).
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import os
import secrets
import signal
import sys
import time
from pathlib import Path

from openbricks_server.daemon.hub_events import OutputLine, RunStart, TelemetrySample
from openbricks_server.daemon.hubs.output import OutputParser
from openbricks_server.daemon.sim.proxy import ViewRelay, http_client
from openbricks_server.daemon.sim.warm import WarmServer
from openbricks_server.daemon.store import now_ms
from openbricks_sim.console_job import CHILD_MAIN
from openbricks_sim.job import SimJob
from openbricks_sim.limits import default_wall_s

log = logging.getLogger("openbricks.console")

SIM_HUB = "sim"  # the hub id sim runs have in the history
MAX_LIVE_RUNS = 4  # sim runs at once; more would only share the same cores slower
START_TIMEOUT_S = 60.0  # the child's imports and world build, on a busy machine
STOP_GRACE_S = 5.0
WALL_GRACE_S = 15.0
PROGRESS_EVERY_S = 0.5  # job progress events at most this often
LINE_MAX_CHARS = 4000  # longer output lines are cut (a hub's terminal would wrap them anyway)
EVENT_LINE_LIMIT = 16 * 1024 * 1024  # the longest event line read from the child
RECORDING_NAME = "recording.viser"
DONE_EXITS = ("finished", "time_limit")


def job_state(exit_reason: str) -> str:
    if exit_reason in DONE_EXITS:
        return "done"
    return "cancelled" if exit_reason == "stopped" else "failed"


class SimRunJob:
    """One sim run's child process, from start to its recorded end."""

    def __init__(self, jobs: SimJobs, run_id: str, job: SimJob, run_dir: Path, started_ms: int):
        self.jobs = jobs
        self.run_id = run_id
        self.job = job
        self.run_dir = run_dir
        self.started_ms = started_ms
        self.ready = asyncio.Event()  # the 3D view answers (its port is known)
        self.ended = asyncio.Event()
        self.port: int | None = None
        self.relay: ViewRelay | None = None  # the browsers' shared connection to the view
        self.paused = False
        self.speed: float | None = job.speed
        self.sim_ms = 0
        self._process: asyncio.subprocess.Process | None = None
        self._result: dict | None = None
        self._killed_for: str | None = None  # "stop", "wall", "start": why we killed it, if we did
        self._partial = ""
        self.plot_tag = secrets.token_hex(4)  # as a hub's: a program cannot forge a sample by printing
        self._parser = OutputParser(
            self.plot_tag, self._emit_lines, self._emit_samples, lambda kind, data: None
        )
        self._line_no = 0
        self._progress_due = 0.0
        self._state_seen = asyncio.Event()  # the child answered a control with its new state

    # --- life cycle ------------------------------------------------------------------------------------

    async def start(self) -> None:
        spec_path = self.run_dir / "job.json"
        spec = {
            "job": self.job.to_dict(),
            "recording": str(self.run_dir / RECORDING_NAME),
            "plot_tag": self.plot_tag,
        }
        spec_path.write_text(json.dumps(spec), encoding="utf-8")
        with open(self.run_dir / "child.log", "wb") as child_log:
            self._process = await self.jobs.warm.start(
                "console_job",
                [str(spec_path)],
                cwd=str(self.run_dir),
                stderr=child_log.fileno(),
                limit=EVENT_LINE_LIMIT,
            ) or await asyncio.create_subprocess_exec(
                sys.executable,
                "-c",
                CHILD_MAIN,
                str(spec_path),
                stdin=asyncio.subprocess.PIPE,
                stdout=asyncio.subprocess.PIPE,
                stderr=child_log,
                cwd=self.run_dir,
                start_new_session=True,
                limit=EVENT_LINE_LIMIT,
            )
        loop = asyncio.get_running_loop()
        self._watchers = [
            loop.call_later(START_TIMEOUT_S, self._start_timed_out),
            loop.call_later(self.job.wall_limit_s + START_TIMEOUT_S + WALL_GRACE_S, self._kill, "wall"),
        ]
        self._task = asyncio.create_task(self._watch(), name=f"sim-run-{self.run_id}")

    async def _watch(self) -> None:
        try:
            while True:
                try:
                    line = await self._process.stdout.readline()
                except ValueError:  # one event line beyond EVENT_LINE_LIMIT: skip it
                    continue
                if not line:
                    break
                try:
                    self._handle(json.loads(line))
                except (ValueError, KeyError, TypeError):
                    log.warning("sim run %s: unreadable event %r", self.run_id, line[:200])
            await self._process.wait()
        finally:
            for watcher in self._watchers:
                watcher.cancel()
            self._finish()

    def _handle(self, event: dict) -> None:
        kind = event["type"]
        if kind == "output":
            self._output(event["text"])
        elif kind == "telemetry":
            self._telemetry(event)
        elif kind == "ready":
            self.port = int(event["port"])
            self.relay = ViewRelay(self.port)
            self.jobs.ctx.store.sim_runs.update(self.run_id, state="running", chassis=event.get("chassis"))
            self.ready.set()
            self.jobs.publish(self.run_id)
        elif kind == "state":
            self._state_seen.set()
            self.paused = bool(event["paused"])
            self.speed = event["speed"]
            self.jobs.publish(self.run_id)
        elif kind == "result":
            self._result = event["result"]

    def _output(self, text: str) -> None:
        self._partial += text
        if "\n" not in self._partial:
            if len(self._partial) > LINE_MAX_CHARS:
                self._parse(self._partial)
                self._partial = ""
            return
        complete, _, self._partial = self._partial.rpartition("\n")
        self._parse(complete)

    def _parse(self, lines: str) -> None:
        self._parser.feed((lines + "\n").encode("utf-8", "surrogateescape"))

    def _emit_lines(self, texts: list[tuple[str, int | None]]) -> None:
        received = now_ms()
        lines = []
        for text, _ in texts:
            self._line_no += 1
            lines.append(OutputLine(self._line_no, text[:LINE_MAX_CHARS], None, received))
        self.jobs.ctx.hub_events.run_output(self.run_id, lines)

    def _emit_samples(self, samples: list[TelemetrySample]) -> None:
        hub_ms = self.started_ms + self.sim_ms  # the simulated clock, as the pose samples have it
        for sample in samples:
            sample.hub_ms = hub_ms
        self.jobs.ctx.hub_events.run_telemetry(self.run_id, samples)

    def _telemetry(self, event: dict) -> None:
        self.sim_ms = int(event["sim_ms"])
        received = now_ms()
        hub_ms = self.started_ms + self.sim_ms  # the simulated hub's clock starts with the run
        samples = [
            TelemetrySample(name, float(event[name]), hub_ms, received)
            for name in ("x_mm", "y_mm", "heading_deg", "left_dps", "right_dps")
        ]
        self.jobs.ctx.hub_events.run_telemetry(self.run_id, samples)
        now = time.monotonic()
        if now >= self._progress_due:
            self._progress_due = now + PROGRESS_EVERY_S
            self.jobs.publish(self.run_id, "job_progress")

    def _finish(self) -> None:
        if self._partial:
            self._parse(self._partial)
            self._partial = ""
        result = self._result or self._lost_result()
        recording = self.run_dir / RECORDING_NAME
        exit_reason = result["exit"]
        error = result.get("error")
        store = self.jobs.ctx.store
        store.sim_runs.update(
            self.run_id,
            state=job_state(exit_reason),
            exit=exit_reason,
            sim_ms=result.get("sim_ms"),
            pose=result.get("pose") or None,
            score=result.get("score"),
            error=error,
            recording=(
                str(recording.relative_to(self.jobs.data_dir))
                if self._result is not None and recording.is_file()
                else None
            ),
        )
        detail = error.strip().splitlines()[-1] if error and error.strip() else None
        self.jobs.ctx.hub_events.run_ended(self.run_id, exit_reason, detail, now_ms())
        self.jobs.live.pop(self.run_id, None)
        if self.relay is not None:
            asyncio.get_running_loop().create_task(self.relay.close())
        self.ended.set()
        self.ready.set()  # nobody waits for a view that will never come
        self.jobs.publish(self.run_id)

    def _lost_result(self) -> dict:
        """What ended a child that sent no result, in one line."""
        code = self._process.returncode if self._process else None
        limits = f"{self.job.wall_limit_s:g} s"
        if self._killed_for == "stop":
            exit_reason, error = "stopped", "stopped: the run's process was ended before it could report"
        elif self._killed_for == "start":
            exit_reason = "error"
            error = f"the simulator did not start within {START_TIMEOUT_S:g} s; its log: {self._log_tail()}"
        elif self._killed_for == "wall":
            exit_reason = "wall_limit"
            error = (
                f"wall-clock limit: the run was still going {limits} (wall_limit_s) plus {WALL_GRACE_S:g} s "
                "after it should have stopped, and its process was killed: a loop that never sleeps and "
                "catches every interrupt"
            )
        elif code in (-signal.SIGKILL, -signal.SIGXCPU):
            exit_reason = "cpu_limit"
            cpu_s = self.job.cpu_limit(watched=True)
            error = (
                f"CPU-time limit: the run's process used its {cpu_s:g} s of processor "
                "time and was killed: a loop that never lets simulated time pass, or a very long run"
            )
        else:
            exit_reason = "error"
            how = f"was killed by signal {-code}" if code and code < 0 else f"exited with status {code}"
            error = f"the simulator's process {how} without a result; its log: {self._log_tail()}"
        return {"exit": exit_reason, "sim_ms": self.sim_ms, "pose": {}, "score": None, "error": error}

    def _log_tail(self, lines: int = 3) -> str:
        try:
            text = (self.run_dir / "child.log").read_text(encoding="utf-8", errors="replace")
        except OSError:
            return "(none)"
        return " | ".join(text.strip().splitlines()[-lines:]) or "(empty)"

    def _start_timed_out(self) -> None:
        if not self.ready.is_set():
            self._kill("start")

    def _kill(self, why: str) -> None:
        process = self._process
        if process is None or process.returncode is not None:
            return
        self._killed_for = self._killed_for or why
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(process.pid, signal.SIGKILL)

    # --- controls ---------------------------------------------------------------------------------------

    def send(self, command: dict) -> None:
        process = self._process
        if process is None or process.returncode is not None or process.stdin.is_closing():
            return
        self._state_seen.clear()
        process.stdin.write((json.dumps(command) + "\n").encode())

    async def acknowledged(self, timeout_s: float) -> bool:
        """Wait (up to timeout_s) for the child to report the state a control left it in."""
        try:
            await asyncio.wait_for(self._state_seen.wait(), timeout_s)
        except TimeoutError:
            return False
        return True

    async def stop(self) -> None:
        """Stop the run and wait for its end; a child that does not end in STOP_GRACE_S is killed. A run
        whose program has not started yet is ended at once."""
        if not self.ready.is_set():
            self._kill("stop")
        else:
            self.send({"cmd": "stop"})
        try:
            await asyncio.wait_for(self.ended.wait(), STOP_GRACE_S)
        except TimeoutError:
            self._kill("stop")
            await self.ended.wait()


class SimJobs:
    """The daemon's sim runs: the live ones by id, and how to start one."""

    def __init__(self, ctx):
        self.ctx = ctx
        self.data_dir = ctx.config.resolved_data_dir
        self.live: dict[str, SimRunJob] = {}
        self.max_live = MAX_LIVE_RUNS
        self.http = http_client()  # the live views' pages are fetched through this
        self.warm = WarmServer()  # forks each run's child, MuJoCo and the 3D view already imported

    async def start(
        self,
        *,
        program_name: str,
        source: str,
        world: str,
        chassis: str | None,
        seed: int,
        start_mm_deg: list[float] | None,
        speed: float | None,
        limit_ms: int,
        wall_limit_s: float | None,
        memory_mb: int,
        who: str,
    ) -> str:
        started_ms = now_ms()
        run_id = self.ctx.hub_events.run_started(
            RunStart(SIM_HUB, "sim", started_ms, program_name=program_name, source=source, who=who)
        )
        run_dir = self.data_dir / "sim" / run_id
        run_dir.mkdir(parents=True, exist_ok=True)
        (run_dir / program_name).write_text(source, encoding="utf-8")
        job = SimJob(
            program=str(run_dir / program_name),
            world=world,
            chassis=chassis,
            seed=seed,
            start_mm_deg=start_mm_deg,
            speed=speed,
            limit_ms=limit_ms,
            # A watched run has no wall-clock limit of its own; the console's always have one.
            wall_limit_s=wall_limit_s or default_wall_s(limit_ms, speed),
            memory_mb=memory_mb,
            hub_dir=str(run_dir / "flash"),
        )
        self.ctx.store.sim_runs.insert(run_id, job.to_dict())
        running = SimRunJob(self, run_id, job, run_dir, started_ms)
        self.live[run_id] = running
        try:
            await running.start()
        except OSError as exc:
            self.live.pop(run_id, None)
            self.ctx.store.sim_runs.update(run_id, state="failed", exit="error", error=str(exc))
            self.ctx.hub_events.run_ended(run_id, "error", f"could not start the simulator: {exc}", now_ms())
            raise
        self.publish(run_id)
        return run_id

    def view(self, run_id: str) -> dict | None:
        """The run as a Job (what the pages follow) and its sim fields, or None if there is no such run."""
        row = self.ctx.store.sim_runs.get(run_id)
        if row is None:
            return None
        live = self.live.get(run_id)
        limit_ms = row["limit_ms"]
        sim_ms = live.sim_ms if live is not None else (row["sim_ms"] or 0)
        recorded = row["recording"] is not None
        return {
            **row,
            "job_id": run_id,
            "kind": "sim",
            "label": row["program_name"],
            "progress": min(100.0, 100.0 * sim_ms / limit_ms) if row["state"] != "done" else 100.0,
            "message": row["error"].strip().splitlines()[-1] if row["error"] else row["exit"],
            "result": (
                None
                if row["exit"] is None
                else {
                    "exit": row["exit"],
                    "sim_ms": row["sim_ms"],
                    "pose": row["pose"],
                    "score": row["score"],
                }
            ),
            "sim_ms": sim_ms,
            "live": live is not None,
            "paused": live.paused if live is not None else False,
            "speed": live.speed if live is not None else row["speed"],
            "view_url": f"/sim/runs/{run_id}/view/",
            "replay_url": f"/sim/runs/{run_id}/replay/" if recorded else None,
            "recording_url": f"/api/sim/runs/{run_id}/recording" if recorded else None,
        }

    def publish(self, run_id: str, type_: str = "job") -> None:
        view = self.view(run_id)
        if view is not None:
            self.ctx.events.publish(type_, {"job": view}, run=run_id, persist=type_ == "job")

    async def close(self) -> None:
        """The daemon stops: every live run is stopped (killed if it does not end) and recorded."""
        live = list(self.live.values())
        if live:
            await asyncio.gather(*(job.stop() for job in live), return_exceptions=True)
        await self.warm.close()
        await self.http.aclose()
