"""`openbricks servo-id`: scan a servo bus or re-ID one servo, over a USB adapter or through a hub (-n).
The work and its messages are `openbricks_server.servo_id`'s, shared with the console's servo jobs."""

from __future__ import annotations

import sys

from openbricks_server import console_client
from openbricks_server.errors import EXIT_OK
from openbricks_server.servo_id import check_id, reid_report, scan_report


def main(args) -> int:
    check_id("new id", args.new_id)
    check_id("--old-id", args.old_id)
    if args.name:
        return _through_hub(args)
    return _over_usb(args)


def _print_scan(ids: list[int], where: str) -> None:
    print(scan_report(ids, where), file=sys.stdout if ids else sys.stderr)


def _over_usb(args) -> int:
    from openbricks_server.flash.ports import connected_ports, pick_port
    from openbricks_server.servo_id import reid_usb, scan_usb, usb_where

    port = args.port or pick_port(connected_ports(), None, "USB serial adapter", "-p/--port")
    console_client.refuse_held_port(
        port, "scan or re-ID {hub}'s servos from the console (its Servo-ID page, or POST /api/servos/scan)"
    )
    if args.scan:
        _print_scan(scan_usb(port, args.baudrate, args.timeout), usb_where(port))
    else:
        print(reid_report(reid_usb(port, args.baudrate, args.timeout, args.new_id, args.old_id)))
    return EXIT_OK


def _through_hub(args) -> int:
    import asyncio

    from openbricks_server import hub_session
    from openbricks_server.servo_id import hub_where, reid_through_hub, scan_through_hub

    bus = {"tx": args.tx, "rx": args.rx, "baud": args.baudrate}
    where = hub_where(args.name)

    async def talk(session):
        if args.scan:
            _print_scan(await scan_through_hub(session.call, bus), where)
        else:
            print(reid_report(await reid_through_hub(session.call, bus, args.new_id, args.old_id, where)))
        return EXIT_OK

    return asyncio.run(hub_session.with_hub(args.name, args.scan_timeout, talk))
