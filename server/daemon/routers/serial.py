"""The computer's serial ports: USB ids, what they are, the chip found there by the last flash, and the
console's hub on the port, if it holds one (flash jobs and USB servo adapters pick ports from here)."""

from __future__ import annotations

import asyncio

from fastapi import APIRouter, Depends, Request
from pydantic import BaseModel, Field

from openbricks_server.daemon.auth import Caller, require_operator, require_viewer
from openbricks_server.daemon.errors import ApiError

router = APIRouter(prefix="/serial", tags=["serial"], dependencies=[Depends(require_viewer)])


class SerialPortOut(BaseModel):
    port: str
    vid: int | None
    pid: int | None
    description: str
    esp: str | None  # the USB bridge of an ESP32 board (Espressif USB, CP210x, CH340, FTDI), if it is one
    chip: str | None  # esp32 / esp32s3, as esptool found it on this port's last flash
    hub_id: str | None  # the console's hub whose link goes through this port
    hub_name: str | None


class SerialPorts(BaseModel):
    ports: list[SerialPortOut]


@router.get("/ports", response_model=SerialPorts)
async def list_ports(request: Request) -> SerialPorts:
    """USB serial ports seen by the OS, plus the ports of the console's USB hubs (given with --serial)."""
    from openbricks_server.flash.ports import connected_ports

    ctx = request.app.state.ctx
    chips = ctx.flash.chips if ctx.flash is not None else {}
    hubs = {}
    for actor in ctx.hubs.list() if ctx.hubs is not None else []:
        port = actor.backend.serial_port
        if port is not None and actor.state.kind == "serial":
            hubs[port] = actor
    found = [p for p in await asyncio.to_thread(connected_ports) if p.vid is not None or p.device in hubs]
    listed = {p.device for p in found}
    out = [
        SerialPortOut(
            port=p.device,
            vid=p.vid,
            pid=p.pid,
            description=p.description,
            esp=p.bridge,
            chip=chips.get(p.device),
            hub_id=hubs[p.device].hub_id if p.device in hubs else None,
            hub_name=hubs[p.device].name if p.device in hubs else None,
        )
        for p in found
    ]
    for port, actor in hubs.items():
        if port not in listed:
            out.append(
                SerialPortOut(
                    port=port,
                    vid=None,
                    pid=None,
                    description=f"the console's USB hub {actor.name}",
                    esp=None,
                    chip=chips.get(port),
                    hub_id=actor.hub_id,
                    hub_name=actor.name,
                )
            )
    return SerialPorts(ports=sorted(out, key=lambda p: p.port))


class ProbeBody(BaseModel):
    ports: list[str] = Field(min_length=1, max_length=64, description="serial ports to ask esptool about")


class ProbedPort(BaseModel):
    port: str
    chip: str | None  # esp32 / esp32s3
    error: str | None  # why this port could not be probed


class Probed(BaseModel):
    ports: list[ProbedPort]


@router.post("/probe", response_model=Probed)
async def probe(body: ProbeBody, request: Request, caller: Caller = Depends(require_operator)) -> Probed:
    """Ask esptool which chip is on each port, all at once (each board is reset into its bootloader and
    back; a USB hub the console holds is let go of meanwhile). GET /api/serial/ports shows the chips."""
    from openbricks_server.daemon.jobs.flash import FlashTarget, hubs_by_port

    ctx = request.app.state.ctx
    if ctx.flash is None:
        raise ApiError(503, "flash_unavailable", "flashing is not running", "restart the console")
    ports = list(dict.fromkeys(p.strip() for p in body.ports))
    by_port = hubs_by_port(ctx.hubs)
    targets = [FlashTarget(port, "", by_port.get(port)) for port in ports]
    return Probed(ports=[ProbedPort(**found) for found in await ctx.flash.probe(targets, caller.label)])
