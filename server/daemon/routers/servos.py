"""Servo-ID: scan a serial servo bus and give one servo a new id, verified by reading it back, through a
hub the console holds (the servos wired to the robot) or a USB adapter on a serial port. Each is a job
(kept in the history, announced on the event stream) that answers when it is over; the rules and the
words are `openbricks servo-id`'s: with more than one servo answering, `old_id` must say which one (it is
never guessed); a new id already in use is refused."""

from __future__ import annotations

from contextlib import contextmanager

from fastapi import APIRouter, Depends, Request
from pydantic import BaseModel, Field, model_validator

from openbricks_server.daemon.auth import Caller, require_operator, require_viewer
from openbricks_server.daemon.competition import unlocked
from openbricks_server.daemon.errors import ApiError
from openbricks_server.daemon.jobs.servos import ServoBus, ServoJobs
from openbricks_server.daemon.routers.hub_lookup import find_hub, hub_errors
from openbricks_server.daemon.routers.jobs import registry
from openbricks_server.errors import CliError

router = APIRouter(prefix="/servos", tags=["servos"], dependencies=[Depends(require_viewer)])
SET_ID_ALLOWED = Depends(unlocked("change a servo's id"))  # operators, unless competition mode locks it


class BusBody(BaseModel):
    """The bus: through `hub` (its servo UART on pins `tx`/`rx`) or a USB adapter on `port`."""

    hub: str | None = Field(None, max_length=200, description="a hub the console holds (id or name)")
    port: str | None = Field(None, max_length=300, description="or: a USB adapter's serial port")
    baudrate: int = Field(1_000_000, ge=1200, le=4_000_000, description="the bus rate (factory: 1 Mbaud)")
    tx: int = Field(14, ge=0, le=48, description="through a hub: servo bus TX pin")
    rx: int = Field(41, ge=0, le=48, description="through a hub: servo bus RX pin")
    timeout_s: float = Field(0.02, gt=0, le=1.0, description="over USB: wait per servo answer")

    @model_validator(mode="after")
    def _one_of(self):
        if (self.hub is None) == (self.port is None):
            raise ValueError("give either `hub` (a hub's id or name) or `port` (a USB adapter's serial port)")
        return self


class SetIdBody(BusBody):
    new_id: int = Field(ge=-(2**31), le=2**31, description="the id to give the servo (0..253)")
    old_id: int | None = Field(
        None, ge=-(2**31), le=2**31, description="its id now; needed when several servos answer"
    )


class ScanOut(BaseModel):
    job_id: str
    where: str
    ids: list[int]
    message: str  # the CLI's line: "servo ids on RobotA's servo bus: 1, 2"


class SetIdOut(BaseModel):
    job_id: str
    where: str
    old_id: int
    new_id: int
    ids: list[int]  # on the bus after the change
    changed: bool  # False: the servo already had that id
    message: str  # "servo 2 is now id 7 (read back from the servo); ids on the bus: 1, 7"


def _bus(request: Request, body: BusBody) -> ServoBus:
    actor = find_hub(request.app.state.ctx, body.hub) if body.hub is not None else None
    port = body.port.strip() if body.port is not None else None
    return ServoBus(actor, port, body.baudrate, body.tx, body.rx, body.timeout_s)


@contextmanager
def _api_errors():
    try:
        with hub_errors():
            yield
    except CliError as exc:
        raise ApiError.invalid("servo_refused", str(exc), "nothing was changed on the bus") from None


def _servos(request: Request) -> ServoJobs:
    return ServoJobs(registry(request))


@router.post("/scan", response_model=ScanOut)
async def scan(body: BusBody, request: Request, caller: Caller = Depends(require_operator)) -> ScanOut:
    """List the servo ids (0..253) answering on the bus; changes nothing. Up to a minute through a hub."""
    bus = _bus(request, body)
    with _api_errors():
        job = await _servos(request).scan(bus, caller.label)
    return ScanOut(job_id=job["job_id"], **{k: job["result"][k] for k in ("where", "ids", "message")})


@router.post("/set-id", response_model=SetIdOut)
async def set_id(body: SetIdBody, request: Request, caller: Caller = SET_ID_ALLOWED) -> SetIdOut:
    """Give one servo `new_id`, verified by reading it back from the new id and the old id falling silent."""
    bus = _bus(request, body)
    with _api_errors():
        job = await _servos(request).set_id(bus, body.new_id, body.old_id, caller.label)
    return SetIdOut(job_id=job["job_id"], **job["result"])
