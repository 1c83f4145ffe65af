"""The daemon's FastAPI application: `create_app(config)` wires the store, the event stream, the auth
checks, the routers and the long-lived services (the output writer, the hub manager) into one app served
by a single uvicorn worker.

Extension points, so parts can land one at a time:
- `SERVICES`: async context managers entered in order at start-up and left in reverse at shutdown, each
  given the `DaemonContext`. The hub manager is one: `HubManager(config, hub_events, store)`, set as
  `ctx.hubs`, `await hubs.start()` on entry and `await hubs.close()` on exit.
- `ROUTERS`: one router per resource, included under `/api`.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import AsyncIterator, Callable, Sequence
from contextlib import AbstractAsyncContextManager, AsyncExitStack, asynccontextmanager
from dataclasses import dataclass, field
from typing import Any

from fastapi import FastAPI
from fastapi.routing import APIRoute
from fastapi.staticfiles import StaticFiles
from fastapi_offline import FastAPIOffline
from ulid import ULID

from openbricks import __version__
from openbricks_server.daemon import errors
from openbricks_server.daemon.auth import MUTATING_METHODS, Auth, AuthMiddleware, require_operator
from openbricks_server.daemon.competition import Competition
from openbricks_server.daemon.config import DaemonConfig
from openbricks_server.daemon.events import EventBus
from openbricks_server.daemon.recorder import INTERRUPTED_BY_CRASH, Recorder
from openbricks_server.daemon.routers import auth as auth_router
from openbricks_server.daemon.routers import competition as competition_router
from openbricks_server.daemon.routers import events as events_router
from openbricks_server.daemon.routers import examples as examples_router
from openbricks_server.daemon.routers import flash as flash_router
from openbricks_server.daemon.routers import hubs as hubs_router
from openbricks_server.daemon.routers import jobs as jobs_router
from openbricks_server.daemon.routers import (
    pages,
    programs,
    runs,
    runtime,
    serial,
    servos,
    sim,
    sim_sweeps,
    sim_view,
    system,
)
from openbricks_server.daemon.store import Store, now_ms


class StartupRefused(Exception):
    """The daemon must not start as configured (the message says why and what to do)."""


@dataclass
class DaemonContext:
    """Everything a route or service reaches through `app.state.ctx`."""

    config: DaemonConfig
    store: Store
    events: EventBus
    hub_events: Recorder  # implements openbricks_server.daemon.hub_events.HubEvents
    auth: Auth
    competition: Competition
    hubs: Any = None  # the HubManager, once its service has started
    sim: Any = None  # the SimJobs (sim runs), once its service has started
    jobs: Any = None  # the JobRegistry (flash, servo jobs), once its service has started
    flash: Any = None  # the FlashJobs
    sweeps: Any = None  # the SweepJobs (seed sweeps)
    started_ms: int = field(default_factory=now_ms)


Service = Callable[[DaemonContext], AbstractAsyncContextManager[None]]


@asynccontextmanager
async def output_writer(ctx: DaemonContext) -> AsyncIterator[None]:
    """Writes output lines within the flush interval; at shutdown writes the rest and ends open runs."""
    task = asyncio.create_task(ctx.hub_events.flush_loop(), name="output-writer")
    try:
        yield
    finally:
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task
        ctx.hub_events.close()


@asynccontextmanager
async def hub_manager(ctx: DaemonContext) -> AsyncIterator[None]:
    """Starts the hubs (virtual ones as subprocesses, the BLE scan); hands them all back at shutdown."""
    from openbricks_server.daemon.hubs.manager import HubManager

    ctx.hubs = HubManager(ctx.config, ctx.hub_events, ctx.store)
    try:
        await ctx.hubs.start()
        yield
    finally:
        await ctx.hubs.close()


@asynccontextmanager
async def sim_jobs(ctx: DaemonContext) -> AsyncIterator[None]:
    """Sim runs (child processes); at shutdown every live one is stopped and recorded."""
    from openbricks_server.daemon.recorder import INTERRUPTED_BY_CRASH
    from openbricks_server.daemon.sim.jobs import SimJobs

    ctx.store.sim_runs.mark_failed_open(INTERRUPTED_BY_CRASH)
    ctx.sim = SimJobs(ctx)
    try:
        yield
    finally:
        await ctx.sim.close()


@asynccontextmanager
async def job_runner(ctx: DaemonContext) -> AsyncIterator[None]:
    """Runs jobs (flash, servo scans, seed sweeps); jobs a previous daemon left unfinished are marked
    failed first. At shutdown, jobs still running are cancelled (an esptool mid-write is killed)."""
    from openbricks_server.daemon.jobs.flash import FlashJobs
    from openbricks_server.daemon.jobs.registry import JobRegistry
    from openbricks_server.daemon.sim.sweeps import SweepJobs

    ctx.store.jobs.mark_interrupted()
    ctx.jobs = JobRegistry(ctx.store, ctx.events)
    ctx.flash = FlashJobs(ctx.jobs, ctx.config.resolved_data_dir, ctx.config.flash_parallel)
    ctx.sweeps = SweepJobs(ctx.jobs)
    try:
        yield
    finally:
        await ctx.jobs.close()


SERVICES: list[Service] = [output_writer, hub_manager, sim_jobs, job_runner]
ROUTERS = [
    system.router,
    auth_router.router,
    programs.router,
    programs.drafts_router,
    runtime.router,
    examples_router.router,
    runs.router,
    events_router.router,
    hubs_router.router,
    sim.router,
    sim_sweeps.router,
    jobs_router.router,
    serial.router,
    flash_router.router,
    servos.router,
    competition_router.router,
]


def create_app(config: DaemonConfig, services: Sequence[Service] | None = None) -> FastAPI:
    """The app for `config`, with its database opened (and migrated) and a new lifetime begun.

    Raises StartupRefused when the configuration is unsafe (a network bind without minted tokens)."""
    store = Store(config.db_path)
    if not config.is_loopback and not store.tokens.any():
        store.close()
        raise StartupRefused(
            f"refusing to listen on {config.host}: anyone on the network could reach the console, and no "
            "access token has been minted yet. Mint one first (`openbricks console token --role viewer` "
            "for people who watch, --role operator for those who run programs), or listen on 127.0.0.1"
        )
    boot_id = str(ULID())
    store.runs.mark_interrupted(None, INTERRUPTED_BY_CRASH)
    store.hubs.mark_all_offline()
    first_seq = store.events.begin_boot(boot_id)
    bus = EventBus(store, boot_id, first_seq, config.ring_size, config.client_queue)
    ctx = DaemonContext(
        config=config,
        store=store,
        events=bus,
        hub_events=Recorder(store, bus, config.flush_interval_s),
        auth=Auth(config, store),
        competition=Competition(store, bus),
    )
    chosen = list(SERVICES if services is None else services)

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        async with AsyncExitStack() as stack:
            stack.callback(store.close)
            stack.callback(store.events.end_boot, boot_id)
            for service in chosen:
                await stack.enter_async_context(service(ctx))
            yield

    app = FastAPIOffline(
        title="openbricks console",
        version=__version__,
        description=(
            "One daemon owns every hub link, the run history and the event stream. Sign in with the URL "
            "the console printed, or send `Authorization: Bearer <token>`."
        ),
        lifespan=lifespan,
        redoc_url=None,
        static_url="/static/docs",
        responses=errors.ERROR_RESPONSES,
    )
    app.state.ctx = ctx
    errors.install(app)
    app.add_middleware(AuthMiddleware)
    app.include_router(pages.router)
    app.include_router(sim_view.router)
    if pages.ASSETS_DIR.is_dir():
        app.mount("/assets", StaticFiles(directory=pages.ASSETS_DIR), name="assets")
    pages.mount_manual(app)
    for router in ROUTERS:
        app.include_router(router, prefix="/api")
    check_mutating_routes(app)
    return app


def check_mutating_routes(app: FastAPI) -> None:
    """Refuse to build an app where a state-changing route does not depend on `require_operator`."""
    for route in app.routes:
        if isinstance(route, APIRoute) and route.methods & MUTATING_METHODS:
            if not _depends_on(route.dependant, require_operator):
                raise RuntimeError(
                    f"{sorted(route.methods)} {route.path} changes state but does not depend on "
                    "require_operator; add `dependencies=[Depends(require_operator)]` or a parameter"
                )


def _depends_on(dependant, call) -> bool:
    return any(d.call is call or _depends_on(d, call) for d in dependant.dependencies)
