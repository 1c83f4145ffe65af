"""The hub runtime's API (modules, classes, methods, signatures, docstring summaries), read from the
installed `openbricks` package: the editor's completion and hover help."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Depends
from pydantic import BaseModel

from openbricks_server.daemon.auth import require_viewer
from openbricks_server.runtime_api import runtime_api

router = APIRouter(prefix="/runtime", tags=["runtime"], dependencies=[Depends(require_viewer)])


class ApiSymbol(BaseModel):
    name: str
    kind: str  # class, function, method, property, constant
    signature: str  # e.g. "(distance_mm, then='coast', wait=True)"; "" for properties and constants
    doc: str
    members: list[ApiSymbol] = []
    bases: list[str] = []


class ApiModule(BaseModel):
    name: str  # e.g. openbricks.robotics.drivebase
    doc: str
    symbols: list[ApiSymbol]


class RuntimeApi(BaseModel):
    version: str  # the runtime's version these signatures are from
    modules: list[ApiModule]


@router.get("/api", response_model=RuntimeApi)
async def get_runtime_api() -> Any:
    """Every public module of the hub runtime with its classes, functions and methods."""
    return runtime_api()
