"""What the daemon is: version, health, where it keeps its data, and the audit log."""

from __future__ import annotations

import os

from fastapi import APIRouter, Depends, Query, Request
from pydantic import BaseModel

from openbricks import __version__
from openbricks_server.daemon.auth import require_viewer
from openbricks_server.daemon.store import now_ms

router = APIRouter(prefix="/system", tags=["system"], dependencies=[Depends(require_viewer)])


class VersionInfo(BaseModel):
    version: str
    schema_version: int


class Health(BaseModel):
    ok: bool
    uptime_ms: int
    boot: str  # this lifetime's id: event sequence numbers are counted from its first_seq
    seq: int  # the last event sequence number given out
    hubs: int  # hubs in the registry
    clients: int  # WebSocket clients connected


class DataDir(BaseModel):
    data_dir: str
    database: str
    database_bytes: int


class AuditEntry(BaseModel):
    id: int
    ts_ms: int
    who: str
    role: str
    action: str
    status: int  # HTTP-like result: 200 done, 403 refused, 4xx/5xx failed


@router.get("/version", response_model=VersionInfo)
async def version(request: Request) -> VersionInfo:
    return VersionInfo(version=__version__, schema_version=request.app.state.ctx.store.db.schema_version)


@router.get("/health", response_model=Health)
async def health(request: Request) -> Health:
    ctx = request.app.state.ctx
    return Health(
        ok=True,
        uptime_ms=now_ms() - ctx.started_ms,
        boot=ctx.events.boot_id,
        seq=ctx.events.seq,
        hubs=len(ctx.store.hubs.list()),
        clients=ctx.events.subscribers,
    )


@router.get("/data-dir", response_model=DataDir)
async def data_dir(request: Request) -> DataDir:
    ctx = request.app.state.ctx
    db = ctx.store.path
    size = sum(os.path.getsize(p) for p in (db, f"{db}-wal") if os.path.exists(p))
    return DataDir(data_dir=str(ctx.config.resolved_data_dir), database=str(db), database_bytes=size)


@router.get("/audit", response_model=list[AuditEntry])
async def audit(
    request: Request,
    limit: int = Query(100, ge=1, le=1000),
    before: int | None = Query(None, ge=1, description="only entries older than this id (paging)"),
) -> list[AuditEntry]:
    return [AuditEntry(**e) for e in request.app.state.ctx.store.audit.list(limit, before)]
