"""Servo jobs: scan a servo bus or re-ID one servo, through a hub the console holds (as one operation of
its actor, refused with 409 while something else holds the hub) or through a USB adapter on a port (the
blocking serial work in a thread). The rules, the read-back check and the messages are
`openbricks_server.servo_id`'s, the same as `openbricks servo-id`'s; only the option names in them are
the API's (`old_id`, not `--old-id`)."""

from __future__ import annotations

import asyncio
from dataclasses import dataclass

from openbricks_server.daemon.jobs.registry import JobRegistry
from openbricks_server.servo_id import (
    check_id,
    hub_where,
    reid_report,
    reid_through_hub,
    reid_usb,
    scan_report,
    scan_through_hub,
    scan_usb,
    usb_where,
)

OLD_ID = "old_id"  # how the API spells the CLI's --old-id in messages


@dataclass(frozen=True)
class ServoBus:
    """Where the servos are: `actor` (a hub, with its servo UART pins) or `port` (a USB adapter)."""

    actor: object | None
    port: str | None
    baudrate: int
    tx: int
    rx: int
    timeout_s: float  # per servo answer, over USB

    @property
    def where(self) -> str:
        return hub_where(self.actor.name) if self.actor is not None else usb_where(self.port)

    @property
    def label(self) -> str:
        return self.actor.hub_id if self.actor is not None else self.port

    @property
    def uart(self) -> dict:
        return {"tx": self.tx, "rx": self.rx, "baud": self.baudrate}

    def params(self) -> dict:
        return {"hub": self.actor.hub_id if self.actor else None, "port": self.port, **self.uart}


class ServoJobs:
    def __init__(self, jobs: JobRegistry):
        self.jobs = jobs

    async def scan(self, bus: ServoBus, who: str) -> dict:
        """The job record of a finished scan (result: ids, where, message); raises what failed it."""

        async def work(job):
            self.jobs.running(job)
            if bus.actor is not None:
                ids = await bus.actor.host_calls(
                    "servo scan", who, lambda call: scan_through_hub(call, bus.uart)
                )
            else:
                ids = await asyncio.to_thread(scan_usb, bus.port, bus.baudrate, bus.timeout_s)
            return {"ids": ids, "where": bus.where, "message": scan_report(ids, bus.where)}

        job = self.jobs.create("servo_scan", bus.label, who, bus.params())
        await self.jobs.run(job, work)
        return job.record()

    async def set_id(self, bus: ServoBus, new_id: int, old_id: int | None, who: str) -> dict:
        """The job record of a finished re-ID, verified by read-back; raises what failed it."""
        check_id("new id", new_id)
        check_id(OLD_ID, old_id)

        async def work(job):
            self.jobs.running(job)
            if bus.actor is not None:
                done = await bus.actor.host_calls(
                    "servo re-ID",
                    who,
                    lambda call: reid_through_hub(call, bus.uart, new_id, old_id, bus.where, OLD_ID),
                )
            else:
                done = await asyncio.to_thread(
                    reid_usb, bus.port, bus.baudrate, bus.timeout_s, new_id, old_id, OLD_ID
                )
            return {
                "old_id": done.old_id,
                "new_id": done.new_id,
                "ids": done.ids_after,
                "changed": done.changed,
                "where": bus.where,
                "message": reid_report(done),
            }

        params = {**bus.params(), "new_id": new_id, "old_id": old_id}
        job = self.jobs.create("servo_set_id", bus.label, who, params)
        await self.jobs.run(job, work)
        return job.record()
