"""One actor per hub: an asyncio task that owns the hub's link and serves operations one at a time.

States (every change reported through `HubEvents.hub_changed`):

    offline -> connecting -> idle <-> busy / running -> (dropped) -> connecting -> ...
    any state but busy / running -> flashing (a flash job holds the hub's USB port) -> offline -> ...

An operation (run, upload, log list/read, identify, the automatic log pull) claims the hub; a second
caller is refused at once with `HubBusyError` naming the holder (operation, who, since when), never
queued behind a long run. `stop` goes around that: it interrupts whatever holds the hub (Ctrl-C) and
waits for the hub to confirm.

Between operations the hub is handed back to its launcher (`idle(watch=<nonce>)`), so its program
button works, and the actor keeps reading the link: a run started with the button is announced by
the hub (run-begin / run-end frames with the actor's nonce) and captured live as a run of origin
"button". After every run, and on every connect, the hub's run-log slots are read back and reported
(`run_log_read`), so a run made while nobody was connected reaches the history too.

A link that drops unexpectedly is reconnected with backoff; a run in progress keeps going on the hub,
its output resumes where it stopped (the hub holds it meanwhile) and the gap is reported with
`run_gap`. The daemon holds the hub's file lock (hub_lock) while it holds the link, so a direct
`openbricks` command cannot talk over it.
"""

from __future__ import annotations

import ast
import asyncio
import contextlib
import dataclasses
import logging
import secrets
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any

from openbricks_server.compile import Program, ProgramError
from openbricks_server.daemon.hub_events import HubEvents, HubState, RunStart
from openbricks_server.daemon.hubs.backend import HubBackend
from openbricks_server.daemon.hubs.errors import (
    HubBusyError,
    HubLinkError,
    HubOfflineError,
    HubOperationError,
    HubRefusedError,
    LogNotFoundError,
    ProgramRejectedError,
)
from openbricks_server.daemon.hubs.output import LineCounter, OutputParser, RunLog, now_ms, parse_run_log
from openbricks_server.errors import CliError, UsageError
from openbricks_server.link import (
    HubCallError,
    HubException,
    LinkDropped,
    LinkError,
    LinkTimeout,
    ProtocolError,
)
from openbricks_server.link.base import Link
from openbricks_server.link.host_call import HubInfo, call_source
from openbricks_server.link.raw_repl import RawRepl
from openbricks_server.logview import missing_run
from openbricks_server.staging import StorageError

log = logging.getLogger(__name__)

ENTER_TIMEOUT_S = 10.0
HAND_BACK_TIMEOUT_S = 3.0
RUN_TIMEOUT_S = 24 * 3600.0
REPL_TIMEOUT_S = 600.0  # a REPL entry that loops ends with Stop (Ctrl-C) long before this
STOP_CONFIRM_S = 5.0
STOP_RESEND_S = 1.0
IDLE_READ_S = 3600.0
BACKOFF_S = (0.5, 1.0, 2.0, 5.0, 10.0, 30.0)
CONNECT_WAIT_S = 60.0
NOTHING_RUNNING = "no program was running"
CAPABILITY_KEYS = (
    "version",
    "runtime",
    "chip",
    "accepts_mpy",
    "mpy_version",
    "compression",
    "max_program_bytes",
    "log_slots",
    "log_max_bytes",
    "protocol",
    "battery_mv",  # reported by hubs that measure their supply; the dashboard's tile shows it
)


@dataclass
class Holder:
    operation: str
    who: str
    since_ms: int

    def as_dict(self) -> dict:
        return {"operation": self.operation, "who": self.who, "since_ms": self.since_ms}


@dataclass
class _Job:
    status: str  # what the hub shows while the job runs: busy or running
    work: Callable[[], Awaitable[Any]]
    future: asyncio.Future


_DISCONNECT = object()


class _LiveRun:
    """One run being captured: its id once the hub announced it, numbered lines, the open gap."""

    def __init__(self, actor: HubActor, origin: str, program_name: str | None, source: str | None, who: str):
        self.actor = actor
        self.origin = origin
        self.program_name = program_name
        self.source = source
        self.who = who
        self.run_id: str | None = None
        self.index: int | None = None
        self.started_ms: int | None = None
        self.counter = LineCounter()
        self.pending: list[tuple[str, int | None]] = []  # output before the announcement (none expected)
        self.gap_since: int | None = None
        self.gap_reason = ""
        self.started = asyncio.get_running_loop().create_future()

    def begin(self, data: dict) -> None:
        events = self.actor.events
        self.index = int(data.get("run", -1))
        self.started_ms = int(data.get("started_ms", now_ms()))
        self.run_id = events.run_started(
            RunStart(
                hub_id=self.actor.state.hub_id,
                origin=self.origin,  # type: ignore[arg-type]
                started_ms=self.started_ms,
                program_name=self.program_name,
                source=self.source,
                slot=data.get("slot"),
                who=self.who,
            )
        )
        self.actor._run_began(self)
        if self.pending:
            self.lines(self.pending)
            self.pending = []
        if not self.started.done():
            self.started.set_result(self.run_id)

    def lines(self, stamped: list[tuple[str, int | None]]) -> None:
        if self.run_id is None:
            self.pending.extend(stamped)
            return
        self.actor.events.run_output(self.run_id, self.counter.number(stamped))

    def samples(self, samples) -> None:
        if self.run_id is not None:
            self.actor.events.run_telemetry(self.run_id, samples)

    def dropped(self, reason: str) -> None:
        if self.gap_since is None:
            self.gap_since, self.gap_reason = now_ms(), reason

    def reconnected(self) -> None:
        if self.gap_since is not None and self.run_id is not None:
            self.actor.events.run_gap(self.run_id, self.gap_reason, self.gap_since, now_ms())
        self.gap_since = None

    def end(self, outcome: str, detail: str | None) -> None:
        if self.run_id is None:
            return
        if self.gap_since is not None:
            self.actor.events.run_gap(self.run_id, self.gap_reason, self.gap_since, None)
            self.gap_since = None
        if outcome == "error" and detail is None:
            detail = self.counter.last_text
        self.actor.events.run_ended(self.run_id, outcome, detail, now_ms())  # type: ignore[arg-type]


class HubActor:
    """The one owner of a hub's link. Methods are called from the daemon's event loop."""

    def __init__(self, backend: HubBackend, events: HubEvents, *, auto_connect: bool = False):
        self.backend = backend
        self.events = events
        self.state = HubState(backend.hub_id, backend.name, backend.kind, backend.address)
        self.last_error: str | None = None
        self._holder: Holder | None = None
        self._holder_changed = asyncio.Event()
        self._link: Link | None = None
        self._repl: RawRepl | None = None
        self._info: HubInfo | None = None
        self._want = asyncio.Event()
        if auto_connect:
            self._want.set()
        self._closing = False
        self._jobs: asyncio.Queue = asyncio.Queue()
        self._task: asyncio.Task | None = None
        self._lock = contextlib.ExitStack()
        self._nonce = secrets.token_hex(4)
        self._watch_parser: OutputParser | None = None
        self._button_run: _LiveRun | None = None
        self._current_run: _LiveRun | None = None
        self._pulled: dict[int, int] = {}  # run index -> bytes already reported
        self._pull_wanted = False
        self._connect_waiters: list[asyncio.Future] = []
        self._wake = asyncio.Event()
        self._flashing = False

    # -- lifecycle ----------------------------------------------------------------------------------

    @property
    def name(self) -> str:
        return self.state.name

    @property
    def hub_id(self) -> str:
        return self.state.hub_id

    @property
    def connected(self) -> bool:
        return self._link is not None and self._link.is_open

    def start(self) -> None:
        self._report()
        self._task = asyncio.create_task(self._supervise(), name=f"hub {self.name}")

    async def close(self) -> None:
        """Stop whatever runs, hand the hub back to its launcher, close the link, end the backend."""
        self._closing = True
        self._want.clear()
        if self._holder is not None and self.connected:
            with contextlib.suppress(LinkError, HubOperationError):
                await self.stop("daemon shutdown")
        try:
            if self._task is not None:
                self._jobs.put_nowait(_DISCONNECT)
                self._wake.set()
                try:
                    async with asyncio.timeout(HAND_BACK_TIMEOUT_S + 2):
                        await asyncio.shield(self._task)
                except (TimeoutError, asyncio.CancelledError):
                    self._task.cancel()
                    await asyncio.gather(self._task, return_exceptions=True)
            await self._close_link()
        finally:
            await self.backend.close()  # a virtual hub's process ends with the daemon, whatever happened
            self._set_status("offline")

    def rename(self, name: str) -> None:
        """The hub advertises another name now (a BLE rescan): same id, new name."""
        if name != self.state.name:
            self.state.name = name
            self.backend.name = name
            self._report()

    def seen(self, rssi: int | None) -> None:
        self.state.rssi = rssi
        self.state.last_seen_ms = now_ms()

    async def connect(self, wait_s: float = CONNECT_WAIT_S) -> HubState:
        """Connect (and keep reconnecting after drops) until `disconnect()`; returns once connected."""
        if self.connected and self.state.status in ("idle", "busy", "running"):
            return self.state
        if self._flashing:
            raise self._busy_error()
        waiter = asyncio.get_running_loop().create_future()
        self._connect_waiters.append(waiter)
        self._want.set()
        self._wake.set()
        try:
            async with asyncio.timeout(wait_s):
                await waiter
        except TimeoutError:
            raise HubLinkError(
                f"{self.name} did not connect within {wait_s:g} s ({self.last_error or 'no answer'})",
                "check that it is powered and in range; the daemon keeps trying",
            ) from None
        return self.state

    async def disconnect(self, who: str) -> HubState:
        """Close the link and stop reconnecting; the hub is left to its launcher (button works)."""
        if self._holder is not None:
            raise self._busy_error()
        self._want.clear()
        self._wake.set()
        if self.connected:
            done = asyncio.get_running_loop().create_future()
            self._jobs.put_nowait(_Job("busy", _DISCONNECT_WORK, done))
            with contextlib.suppress(Exception):
                async with asyncio.timeout(HAND_BACK_TIMEOUT_S + 2):
                    await done
        return self.state

    @contextlib.asynccontextmanager
    async def handed_over(self, operation: str, who: str):
        """The hub's port for someone else (a flash job) for the block: the link is closed and not
        reopened, the hub shows `flashing` and every operation is refused naming the holder. Afterwards
        the hub reconnects if it was meant to be connected."""
        if self._holder is not None:
            raise self._busy_error()
        wanted = self._want.is_set()
        self._flashing = True
        self._set_holder(Holder(operation, who, now_ms()))
        self._want.clear()
        self._wake.set()
        try:
            await self._let_go()
            self._set_status("flashing")
            yield
        finally:
            self._flashing = False
            self._drop_queued_disconnects()
            self._set_holder(None)
            self._set_status("offline")
            if wanted and not self._closing:
                self._want.set()
                self._wake.set()

    async def _let_go(self) -> None:
        """Until the supervisor has closed the link (asking it to, if it is serving)."""
        loop = asyncio.get_running_loop()
        deadline = loop.time() + HAND_BACK_TIMEOUT_S + ENTER_TIMEOUT_S
        asked = False
        while self._link is not None:
            if not asked and self.connected:
                self._jobs.put_nowait(_Job("busy", _DISCONNECT_WORK, loop.create_future()))
                asked = True
            if loop.time() > deadline:
                raise HubLinkError(
                    f"{self.name} did not let go of its port in time",
                    "stop what it is doing (POST /api/hubs/{hub}/stop) and retry",
                )
            await asyncio.sleep(0.05)

    def _drop_queued_disconnects(self) -> None:
        kept = []
        while not self._jobs.empty():
            job = self._jobs.get_nowait()
            if isinstance(job, _Job) and job.work is _DISCONNECT_WORK:
                _settle(job.future, None, None)
            else:
                kept.append(job)
        for job in kept:
            self._jobs.put_nowait(job)

    # -- state ----------------------------------------------------------------------------------------

    def _report(self) -> None:
        self.state.holder = None if self._holder is None else self._holder.as_dict()
        self.events.hub_changed(dataclasses.replace(self.state, capabilities=dict(self.state.capabilities)))

    def _set_status(self, status: str) -> None:
        if self.state.status != status:
            self.state.status = status  # type: ignore[assignment]
            self._report()

    def _unlinked_status(self) -> str:
        return "flashing" if self._flashing else "offline"

    def _set_holder(self, holder: Holder | None) -> None:
        self._holder = holder
        self._holder_changed.set()
        self._holder_changed = asyncio.Event()

    def _busy_error(self) -> HubBusyError:
        holder = self._holder
        since = datetime.fromtimestamp(holder.since_ms / 1000, UTC).isoformat(timespec="seconds")
        return HubBusyError(
            f"{self.name} is busy: {holder.operation} by {holder.who} since {since}",
            "wait for it to end, or stop it first (POST .../stop), then retry",
            holder=holder.as_dict(),
        )

    def _claim(self, operation: str, who: str) -> None:
        if self._holder is not None:
            raise self._busy_error()
        if not self.connected or self.state.status != "idle":
            status = self.state.status
            if not self.connected and status not in ("offline", "connecting"):
                status = "reconnecting"  # the link just went; the status catches up in a moment
            raise HubOfflineError(
                f"{self.name} is {status}"
                + (f" ({self.last_error})" if self.last_error and status == "offline" else ""),
                "connect it first (POST /api/hubs/{hub}/connect) and wait until it is idle",
            )
        self._set_holder(Holder(operation, who, now_ms()))

    def _release(self) -> None:
        self._set_holder(None)
        self.state.run_id = None
        self.state.run_started_ms = None
        if self.connected:
            self.state.status = "idle"
        self._report()

    def _run_began(self, run: _LiveRun) -> None:
        self.state.run_id = run.run_id
        self.state.run_started_ms = run.started_ms
        self.state.status = "running"
        self._report()

    # -- the supervisor: the task that owns the link -------------------------------------------------

    async def _supervise(self) -> None:
        attempt = 0
        while not self._closing:
            if not self._want.is_set():
                self._set_status(self._unlinked_status())
                self._wake.clear()
                await self._wake.wait()
                continue
            try:
                await self._open()
            except (LinkError, OSError, CliError, HubOperationError) as exc:
                self.last_error = str(exc)
                await self._close_link()
                self._set_status("offline")
                self._fail_waiters(exc)
                await self._pause(BACKOFF_S[min(attempt, len(BACKOFF_S) - 1)])
                attempt += 1
                continue
            attempt = 0
            self.last_error = None
            self._resolve_waiters()
            try:
                await self._serve()
            except LinkError as exc:
                self.last_error = str(exc)
                if self._button_run is not None:
                    self._button_run.dropped(str(exc))
            except Exception as exc:  # noqa: BLE001 - a bug must cost one connection, not the hub
                log.exception("hub %s: unexpected error; reconnecting", self.name)
                self.last_error = f"{type(exc).__name__}: {exc}"
            await self._close_link()
            if self._want.is_set() and not self._closing:
                self._set_status("connecting")
                await self._pause(BACKOFF_S[0])

    async def _pause(self, seconds: float) -> None:
        self._wake.clear()
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(seconds):
                await self._wake.wait()

    def _resolve_waiters(self) -> None:
        for waiter in self._connect_waiters:
            if not waiter.done():
                waiter.set_result(None)
        self._connect_waiters.clear()

    def _fail_waiters(self, exc: Exception) -> None:
        for waiter in self._connect_waiters:
            if not waiter.done():
                waiter.set_exception(
                    HubLinkError(f"{self.name}: {exc}", "check that it is powered and in range")
                )
        self._connect_waiters.clear()

    async def _open(self) -> None:
        self._set_status("connecting")
        if not self._lock_held():
            from openbricks_server.hub_lock import hub_lock

            self._lock.enter_context(hub_lock(self.backend.name))
        link = self.backend.make_link()
        self._link = link
        await link.connect()
        repl = RawRepl(link, timeout_s=ENTER_TIMEOUT_S)
        self._repl = repl
        if self._button_run is not None:
            # A button run was on when the link dropped: keep watching it (entering the raw REPL
            # would stop it); the hub is still in its launcher with our nonce.
            self._button_run.reconnected()
            self._watch_parser = self._new_watch_parser()
            self.state.status = "running"
            self._report()
            return
        await repl.enter(timeout_s=ENTER_TIMEOUT_S)
        self._info = await repl.info()
        await repl.set_rtc(now_ms())
        self.state.firmware = self._info.firmware
        self.state.capabilities = {k: self._info.raw[k] for k in CAPABILITY_KEYS if k in self._info.raw}
        self._report()
        await self._pull_logs()
        await self._hand_back()
        self._set_status("idle")

    def _lock_held(self) -> bool:
        return bool(self._lock._exit_callbacks)  # noqa: SLF001 - ExitStack has no public "is empty"

    async def _close_link(self) -> None:
        link, self._link, self._repl = self._link, None, None
        if link is not None:
            await link.close()
        if not self._want.is_set() or self._closing:
            self._lock.close()

    async def _serve(self) -> None:
        """While connected: watch the idle hub and run the jobs that come in, one at a time."""
        while True:
            if self._pull_wanted and self._holder is None and self._button_run is None:
                await self._run_internal("log pull", self._pull_logs)
            watch = asyncio.create_task(self._watch_idle())
            job_get = asyncio.create_task(self._jobs.get())
            done, _ = await asyncio.wait({watch, job_get}, return_when=asyncio.FIRST_COMPLETED)
            if job_get not in done:
                job_get.cancel()
                await asyncio.gather(job_get, return_exceptions=True)
                watch.result()  # raises the drop
                continue
            watch.cancel()
            await asyncio.gather(watch, return_exceptions=True)
            job = job_get.result()
            if job is _DISCONNECT or (isinstance(job, _Job) and job.work is _DISCONNECT_WORK):
                await self._close_link()
                self._set_status(self._unlinked_status())
                if isinstance(job, _Job) and not job.future.done():
                    job.future.set_result(None)
                return
            await self._run_job(job)

    async def _run_internal(self, operation: str, work: Callable[[], Awaitable[Any]]) -> None:
        try:
            self._claim(operation, "daemon")
        except HubOperationError:
            return
        future = asyncio.get_running_loop().create_future()
        await self._run_job(_Job("busy", work, future))
        if future.done() and not future.cancelled():
            future.exception()  # retrieved: a failed pull is retried on the next connect

    async def _run_job(self, job: _Job) -> None:
        """Take the hub from its launcher, do the job, give it back; the caller hears after that, so
        the hub is ready for the next operation (or the button) when the answer arrives."""
        self._set_status(job.status)
        result = error = None
        try:
            await self._take_back()
            result = await job.work()
        except HubOperationError as exc:
            error = exc
        except ProgramError as exc:
            error = ProgramRejectedError(str(exc), "fix the program and send it again")
        except (StorageError, UsageError) as exc:  # where the file was to go: the hub cannot, or must not
            error = HubRefusedError(str(exc), "check the path given for the file")
        except HubCallError as exc:
            error = HubRefusedError(f"{self.name}: {exc.error}", "see the message")
        except HubException as exc:
            from openbricks_server.hub_session import hub_exception_message

            error = HubRefusedError(hub_exception_message(self.name, exc))
        except CliError as exc:  # a rule the shared host code applies (a servo re-ID's old id): its words
            error = exc
        except LinkError as exc:
            _settle(job.future, None, self._link_error(exc))
            self._release()
            raise
        try:
            if self._pull_wanted:
                await self._pull_logs()
            await self._hand_back()
        finally:
            self._release()
            _settle(job.future, result, error)

    def _link_error(self, exc: LinkError) -> HubLinkError:
        if isinstance(exc, LinkDropped):
            return HubLinkError(
                f"the link to {self.name} dropped ({exc.reason})",
                "the daemon reconnects by itself; retry once the hub is idle again",
            )
        if isinstance(exc, LinkTimeout):
            return HubLinkError(
                f"{self.name} stopped answering: {exc}", "check that it is powered and in range"
            )
        return HubLinkError(f"{self.name}: {exc}", "retry once the hub is idle again")

    # -- the hub between operations ------------------------------------------------------------------

    def _new_watch_parser(self) -> OutputParser:
        return OutputParser(self._nonce, self._watch_lines, self._watch_samples, self._watch_frame)

    async def _hand_back(self) -> None:
        """Back to the launcher's idle loop (the button works again), watched with our nonce."""
        repl = self._repl
        await repl.exit()
        await repl.link.write(call_source("idle", {"watch": self._nonce}).encode() + b"\r")
        await repl.link.read_until(b'"idle": true', "the hub's return to its launcher", HAND_BACK_TIMEOUT_S)
        await repl.link.read_until(b"\n", "the end of the hand-back reply", HAND_BACK_TIMEOUT_S)
        self._watch_parser = self._new_watch_parser()

    async def _take_back(self) -> None:
        """Out of the launcher's loop into the raw REPL, for an operation."""
        if self._watch_parser is not None:
            self._watch_parser = None
            await self._repl.enter(timeout_s=ENTER_TIMEOUT_S)

    async def _watch_idle(self) -> None:
        link = self._link
        while True:
            try:
                data = await link.read_some("the idle hub's output", IDLE_READ_S)
            except LinkTimeout:
                continue
            if self._watch_parser is not None:
                self._watch_parser.feed(data)
            if self._pull_wanted and self._button_run is None:
                return  # a button run ended: read its log back (the serve loop does it now)

    def _watch_lines(self, stamped: list[tuple[str, int | None]]) -> None:
        if self._button_run is not None:
            self._button_run.lines(stamped)

    def _watch_samples(self, samples) -> None:
        if self._button_run is not None:
            self._button_run.samples(samples)

    def _watch_frame(self, kind: str, data: dict) -> None:
        if kind == "run-begin" and self._button_run is None:
            if self._holder is None:
                self._set_holder(Holder("run", "button", now_ms()))
            run = _LiveRun(self, "button", self.state.staged_program, None, "button")
            self._button_run = run
            run.begin(data)
        elif kind == "run-end" and self._button_run is not None:
            run, self._button_run = self._button_run, None
            outcome = str(data.get("outcome", "finished"))
            detail = "stopped" if outcome == "stopped" else None
            run.end(outcome, detail)
            self._pulled.pop(run.index, None)
            self._pull_wanted = True
            self._release()

    # -- operations ----------------------------------------------------------------------------------

    async def _submit(self, operation: str, who: str, work, status: str = "busy"):
        self._claim(operation, who)
        future = asyncio.get_running_loop().create_future()
        self._jobs.put_nowait(_Job(status, work, future))
        return future

    async def run(self, program: Program, *, who: str, program_name: str | None = None) -> str:
        """Stage and start `program` (already compiled); returns the run id once the hub started it.

        The run goes on in the actor; its output, telemetry and end arrive through HubEvents.
        """
        live = None

        async def work():
            nonlocal live
            live = _LiveRun(self, "daemon", program_name or program.filename, program.source, who)
            self._current_run = live
            try:
                return await self._run_work(live, program)
            finally:
                self._current_run = None

        future = await self._submit("run", who, work)
        while live is None and not future.done():
            await asyncio.sleep(0.005)
        if live is None:
            return await future  # failed before the work began: raises
        started = live.started
        done, _ = await asyncio.wait({started, future}, return_when=asyncio.FIRST_COMPLETED)
        if started in done:
            return started.result()
        result = future.result()  # raises what failed before the run began
        return result["run_id"]

    async def _run_work(self, live: _LiveRun, program: Program) -> dict:
        from openbricks_server.staging import stage

        path = await stage(self._session(), program, notice=log.debug)
        self.state.staged_program = live.program_name
        nonce = secrets.token_hex(4)

        def frame(kind: str, data: dict) -> None:
            if kind == "run-begin" and live.run_id is None:
                live.begin(data)

        parser = OutputParser(nonce, live.lines, live.samples, frame)

        def link_event(event) -> None:
            if event.kind == "dropped":
                live.dropped(event.detail)
                self.last_error = event.detail
                self.state.status = "connecting"
                self._report()
            else:
                live.reconnected()
                self.state.status = "running"
                self._report()

        try:
            result = await self._repl.run(
                path,
                name=program.filename,  # a source staged as /program.py: tracebacks name the program
                on_output=parser.feed,
                on_link_event=link_event,
                timeout_s=RUN_TIMEOUT_S,
                watch=nonce,
            )
        except LinkError as exc:
            parser.flush()
            live.end("dropped", f"the link was lost and did not come back: {exc}")
            raise
        except HubException as exc:
            parser.flush()
            if "KeyboardInterrupt" not in exc.traceback or live.run_id is None:
                raise
            result = {"outcome": "stopped", "run": live.index}
        parser.flush()
        if live.run_id is None:
            raise HubRefusedError(f"{self.name} did not start the program", "see the hub's output")
        outcome = str(result.get("outcome", "error"))
        live.end(outcome, "stopped" if outcome == "stopped" else None)
        if live.index is not None:
            self._pulled.pop(live.index, None)
        self._pull_wanted = True
        return {"run_id": live.run_id, "outcome": outcome}

    def _session(self):
        from openbricks_server.hub_session import HubSession

        return HubSession(self.name, self._repl, self._info, self.state.kind == "virtual")

    async def upload(self, program: Program, *, who: str, path: str | None = None) -> dict:
        from openbricks_server.staging import stage

        async def work():
            target = await stage(self._session(), program, path, notice=log.debug)
            if path is None:
                self.state.staged_program = program.filename
            return {"path": target, "bytes": len(program.mpy or program.source_bytes)}

        return await (await self._submit("upload", who, work))

    async def identify(self, *, who: str, duration_ms: int = 3000) -> dict:
        async def work():
            return await self._repl.call("identify", duration_ms=duration_ms)

        reply = await (await self._submit("identify", who, work))
        return {"identify_ms": reply["identify_ms"]}

    async def repl(self, code: str, *, who: str, timeout_s: float = REPL_TIMEOUT_S) -> dict:
        """Run `code` in the hub's raw REPL as one operation, as its interactive prompt would: an
        expression's value is printed (and kept in `_`). A traceback is the answer, not a failure."""
        source = repl_source(code)

        async def work():
            try:
                result = await self._repl.exec(source, timeout_s=timeout_s)
            except HubException as exc:
                return {"output": _text(exc.stdout), "error": exc.traceback.rstrip("\n")}
            return {"output": _text(result.stdout), "error": None}

        return await (await self._submit("repl", who, work))

    async def host_calls(self, operation: str, who: str, work: Callable[[Callable], Awaitable[Any]]) -> Any:
        """`work(call)` as one operation (`call(name, timeout_s=..., **args)` makes a host call on the
        hub): a servo scan or re-ID, the same code the CLI runs with its own session's `call`."""

        async def job():
            return await work(self._repl.call)

        return await (await self._submit(operation, who, job))

    async def list_logs(self, *, who: str) -> list[dict]:
        async def work():
            return (await self._repl.call("runs"))["runs"]

        return await (await self._submit("log list", who, work))

    async def read_log(self, index: int, *, who: str) -> RunLog:
        async def work():
            return await self._read_run(index)

        return await (await self._submit("log read", who, work))

    async def _read_run(self, index: int) -> RunLog:
        parts = []
        offset = 0
        while offset is not None:
            try:
                page, offset = await self._repl.read_run_page(index, offset)
            except HubCallError:
                if offset == 0:
                    await self._refuse_missing_log(index)
                raise
            parts.append(page)
        parsed = parse_run_log("".join(parts))
        if parsed is None:
            raise HubRefusedError(f"run log {index} on {self.name} is not a run log", "")
        return parsed

    async def _refuse_missing_log(self, index: int) -> None:
        """LogNotFoundError saying why run `index` is not on the hub, if it is not."""
        reply = await self._repl.call("runs")
        indices = [int(entry["index"]) for entry in reply["runs"]]
        if index not in indices:
            message = missing_run(self.name, index, indices, int(reply.get("slots", 10)))
            raise LogNotFoundError(message, "GET /api/hubs/{hub}/logs lists the runs kept")

    async def _pull_logs(self) -> None:
        """Report every run-log slot not reported yet (the store matches it to a live run)."""
        self._pull_wanted = False
        reply = await self._repl.call("runs")
        slots = int(reply.get("slots", 10))
        for entry in reply["runs"]:
            index, size = int(entry["index"]), int(entry["bytes"])
            if self._pulled.get(index) == size:
                continue
            if self._button_run is not None and self._button_run.index == index:
                continue
            try:
                parsed = await self._read_run(index)
            except (HubCallError, HubRefusedError, ProtocolError):
                continue  # overwritten meanwhile, or damaged on the way: read again next time
            self.events.run_log_read(
                self.hub_id,
                index % slots,
                parsed.started_ms,
                parsed.lines,
                parsed.outcome or "interrupted",
                parsed.detail if parsed.outcome else "the log has no end: the hub reset or lost power",
            )
            self._pulled[index] = size

    # -- stop: around the queue ---------------------------------------------------------------------

    async def stop(self, who: str) -> dict:
        """Interrupt whatever holds the hub and wait for it to confirm; idle hubs have nothing to stop."""
        holder = self._holder
        if not self.connected:
            return {"hub": self.hub_id, "name": self.name, "stopped": False, "detail": f"{self.state.status}"}
        if holder is None:
            return {"hub": self.hub_id, "name": self.name, "stopped": False, "detail": NOTHING_RUNNING}
        run = self._current_run or self._button_run
        loop = asyncio.get_running_loop()
        deadline = loop.time() + STOP_CONFIRM_S
        while self._holder is holder and loop.time() < deadline:
            changed = self._holder_changed
            with contextlib.suppress(LinkError):
                await self._link.write(b"\x03")
            with contextlib.suppress(TimeoutError):
                async with asyncio.timeout(min(STOP_RESEND_S, max(deadline - loop.time(), 0))):
                    await changed.wait()
        if self._holder is holder:
            return {
                "hub": self.hub_id,
                "name": self.name,
                "stopped": False,
                "detail": f"{holder.operation} did not end within {STOP_CONFIRM_S:g} s of Ctrl-C",
            }
        return {
            "hub": self.hub_id,
            "name": self.name,
            "stopped": True,
            "detail": _stopped_detail(holder, run),
        }


def repl_source(code: str) -> str:
    """What the hub runs for one REPL entry: a lone expression becomes `_ = (...)` and its repr is
    printed unless None, as an interactive prompt shows it; anything else runs as written. Whether the
    entry is an expression is decided by CPython's parser, the grammar MicroPython follows."""
    try:
        ast.parse(code, "<repl>", "eval")
    except (SyntaxError, ValueError, RecursionError, MemoryError):
        return code  # statements (or a syntax error, which the hub reports in its own words)
    return f"_ = ({code}\n)\nif _ is not None:\n    print(repr(_))\n"


def _text(data: bytes) -> str:
    return data.decode("utf-8", "replace").replace("\r\n", "\n")


def _stopped_detail(holder: Holder, run: _LiveRun | None) -> str:
    """What was stopped, in `openbricks stop`'s words when it was a program."""
    if run is not None and run.index is not None:
        trigger = "button press" if run.origin == "button" else "host run"
        return f"stopped the program (run {run.index}, started by {trigger})"
    return f"stopped {holder.operation}"


def _settle(future: asyncio.Future, result: Any, error: BaseException | None) -> None:
    if future.done():
        return
    if error is not None:
        future.set_exception(error)
    else:
        future.set_result(result)


async def _disconnect_work() -> None:
    return None


_DISCONNECT_WORK = _disconnect_work
