"""Flashing hubs over USB: upload a firmware image (or use a cached or reachable release), then flash any
number of ports at once, one job per port, with the CLI's safety gates (the image must be built for the
board's chip and carry its partition table where that chip boots from; the same or an older version than
the hub runs is refused unless `allow_downgrade`). A script can flash twenty ports and read twenty results:

    POST /api/flash {"targets": [{"port": "/dev/ttyUSB0", "name": "RobotA"}, ...]}
    GET  /api/flash/{job}?wait_s=120     (each job's steps, progress and result)

Progress arrives on the event stream as `job_progress` events, state changes as `job` events.
"""

from __future__ import annotations

import asyncio

from fastapi import APIRouter, Depends, Query, Request
from pydantic import BaseModel, Field

from openbricks_server.daemon.auth import Caller, audit_as_started, require_operator, require_viewer
from openbricks_server.daemon.competition import unlocked
from openbricks_server.daemon.errors import ApiError
from openbricks_server.daemon.hubs.errors import HubOperationError
from openbricks_server.daemon.jobs.flash import MAX_FIRMWARE_BYTES, FlashTarget, hubs_by_port
from openbricks_server.daemon.routers.jobs import JobOut, JobRef, WaitQuery, find_job, registry
from openbricks_server.errors import CliError
from openbricks_server.flash.flasher import validate_hub_name
from openbricks_server.flash.releases import NoFirmwareError, find_releases

router = APIRouter(prefix="/flash", tags=["flash"], dependencies=[Depends(require_viewer)])

MAX_TARGETS = 64
FLASH_ALLOWED = Depends(unlocked("flash firmware"))  # operators, unless competition mode locks it
UPLOAD_GIVE = "upload one (POST /api/flash/firmware, or the Flash page's Firmware field) and send its id"


class Target(BaseModel):
    """One board: its port (or the console's USB hub on it), and the name to give it."""

    port: str | None = Field(None, max_length=300, description="the serial port, e.g. /dev/ttyUSB0 or COM5")
    hub: str | None = Field(None, max_length=200, description="or: the console's USB hub (id or name)")
    name: str | None = Field(
        None, max_length=100, description="the hub's Bluetooth name; default: the USB hub's current name"
    )


class FlashBody(BaseModel):
    targets: list[Target] = Field(min_length=1, max_length=MAX_TARGETS)
    firmware: str | None = Field(
        None,
        max_length=40,
        description=(
            "an uploaded image's id; default: the newest release for each chip, if one is cached or "
            "OPENBRICKS_RELEASES_URL names a releases location (else the request is refused: no_firmware)"
        ),
    )
    allow_downgrade: bool = Field(
        False, description="flash even when the image is the same or an older version than the hub runs"
    )


class FlashStarted(BaseModel):
    batch: str
    jobs: list[JobOut]


class FirmwareOut(BaseModel):
    firmware_id: str
    filename: str
    chip: str
    version: str | None
    offset: int  # where it is written: fixed by the chip, never chosen by hand
    size: int


def _flash(request: Request):
    flash = request.app.state.ctx.flash
    if flash is None:
        raise ApiError(503, "flash_unavailable", "flashing is not running", "restart the console")
    return flash


def _targets(request: Request, body: FlashBody) -> list[FlashTarget]:
    """The request's boards, resolved and checked as a whole (a malformed request starts nothing)."""
    hubs = request.app.state.ctx.hubs
    by_port = hubs_by_port(hubs)
    targets, ports, names = [], set(), set()
    for i, target in enumerate(body.targets):
        where = f"targets[{i}]"
        actor = None
        if (target.port is None) == (target.hub is None):
            raise ApiError.invalid("bad_target", f"{where}: give either `port` or `hub`", "see /docs")
        if target.hub is not None:
            try:
                actor = hubs.get(target.hub)
            except HubOperationError as exc:
                raise ApiError.invalid("bad_target", f"{where}: {exc.message}", exc.hint or None) from None
            if actor.backend.serial_port is None:
                raise ApiError.invalid(
                    "bad_target",
                    f"{where}: {actor.name} is a {actor.state.kind} hub, not one on a USB port",
                    "plug it in over USB and give its port",
                )
            port = actor.backend.serial_port
        else:
            port = target.port.strip()
            actor = by_port.get(port)
        name = target.name if target.name is not None else (actor.name if actor is not None else None)
        if name is None:
            raise ApiError.invalid(
                "name_required",
                f"{where}: give the hub a `name`; hubs that share a name cannot be told apart over Bluetooth",
                'e.g. {"port": "/dev/ttyUSB0", "name": "RobotA"}',
            )
        try:
            validate_hub_name(name, option=f"{where}.name")
        except CliError as exc:
            raise ApiError.invalid("bad_name", str(exc), "names are 1-26 bytes of printable text") from None
        if port in ports:
            raise ApiError.invalid("duplicate_port", f"{where}: port {port} is listed twice", "list it once")
        if name in names:
            raise ApiError.invalid(
                "duplicate_name", f"{where}: name {name!r} is given twice", "give every hub its own name"
            )
        ports.add(port)
        names.add(name)
        targets.append(FlashTarget(port, name, actor))
    return targets


@router.post(
    "/firmware",
    response_model=FirmwareOut,
    openapi_extra={
        "requestBody": {
            "required": True,
            "content": {"application/octet-stream": {"schema": {"type": "string", "format": "binary"}}},
        }
    },
)
async def upload_firmware(
    request: Request,
    filename: str = Query(
        "firmware.bin", max_length=200, description="the file's name (a release's name carries its version)"
    ),
    caller: Caller = Depends(require_operator),
) -> FirmwareOut:
    """Upload a firmware image (the request body is the .bin file); it is checked at once (an ESP32 or
    ESP32-S3 image with its partition table where the chip boots from) and kept for POST /api/flash."""
    data = bytearray()
    async for chunk in request.stream():
        data += chunk
        if len(data) > MAX_FIRMWARE_BYTES:
            raise ApiError(
                413, "too_large", f"{filename} is larger than any ESP32's flash (16 MB)", "upload the .bin"
            )
    if not data:
        raise ApiError.invalid("empty", "the request body is empty: send the firmware .bin file as the body")
    try:
        firmware_id, image = _flash(request).store_upload(bytes(data), filename)
    except CliError as exc:
        raise ApiError.invalid(
            "bad_firmware", str(exc), "upload the build's firmware.bin or a release"
        ) from None
    return FirmwareOut(
        firmware_id=firmware_id,
        filename=image.path.name,
        chip=image.chip,
        version=image.version,
        offset=image.offset,
        size=image.size,
    )


@router.post("", response_model=FlashStarted)
async def start_flash(body: FlashBody, request: Request, caller: Caller = FLASH_ALLOWED) -> FlashStarted:
    """Flash every target at once (one job per port; at most the console's limit run together, the rest
    wait their turn). Answers at once with the jobs; follow them on the event stream or GET each one.
    Without `firmware` and with no release to take, nothing starts: the answer says how to get an image."""
    flash = _flash(request)
    targets = _targets(request, body)
    image = releases = None
    if body.firmware is not None:
        try:
            image = flash.uploaded(body.firmware)
        except CliError as exc:
            raise ApiError.invalid("bad_firmware", str(exc)) from None
        if image is None:
            raise ApiError.not_found(
                f"firmware {body.firmware!r}", "upload it with POST /api/flash/firmware, or leave it out"
            )
    else:
        try:
            releases = await asyncio.to_thread(find_releases, None, UPLOAD_GIVE)
        except NoFirmwareError as exc:
            raise ApiError.conflict(
                "no_firmware", str(exc), "build the image, then upload its firmware.bin"
            ) from None
    batch, jobs = flash.start(targets, image, body.allow_downgrade, caller.label, releases)
    audit_as_started(request)
    return FlashStarted(batch=batch, jobs=[JobOut(**job.record()) for job in jobs])


@router.get("", response_model=list[JobOut])
async def list_flash_jobs(
    request: Request,
    batch: str | None = Query(None, max_length=40, description="only the jobs one request started"),
    limit: int = Query(100, ge=1, le=1000),
) -> list[JobOut]:
    """Flash jobs, the most recent first."""
    return [JobOut(**job) for job in registry(request).list("flash", batch, limit)]


@router.get("/{job}", response_model=JobOut)
async def get_flash_job(request: Request, job: str = JobRef, wait_s: float = WaitQuery) -> JobOut:
    """One port's flash: state, steps, progress, and the result (hub name read back, chip, image,
    provenance) or why it failed. With `wait_s`, answers when it is over (or when that time is up)."""
    return await find_job(request, job, "flash", wait_s)
