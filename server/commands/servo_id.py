"""`openbricks servo-id`: scan a servo bus or re-ID one servo, over a USB adapter or through a hub (-n)."""

from __future__ import annotations

import sys

from openbricks_server.errors import EXIT_OK
from openbricks_server.servo_id import check_id, choose_old_id


def main(args) -> int:
    check_id("new id", args.new_id)
    check_id("--old-id", args.old_id)
    if args.name:
        return _through_hub(args)
    return _over_usb(args)


def _report_scan(ids: list[int], where: str) -> None:
    if ids:
        print(f"servo ids on {where}: {', '.join(str(i) for i in ids)}")
    else:
        print(f"no servo answers on {where}", file=sys.stderr)


def _report_reid(old_id: int, new_id: int, ids_after: list[int], changed: bool) -> None:
    if not changed:
        print(f"servo {old_id} already has id {new_id}; nothing to change")
        return
    print(
        f"servo {old_id} is now id {new_id} (read back from the servo); ids on the bus: "
        f"{', '.join(str(i) for i in ids_after)}"
    )


def _over_usb(args) -> int:
    from openbricks_server.flash.ports import connected_ports, pick_port
    from openbricks_server.servo_id import UsbServoBus, reid

    port = args.port or pick_port(connected_ports(), None, "USB serial adapter", "-p/--port")
    with UsbServoBus(port, args.baudrate, args.timeout) as bus:
        if args.scan:
            _report_scan(bus.scan(), bus.where())
            return EXIT_OK
        done = reid(bus, args.new_id, args.old_id)
    _report_reid(done.old_id, done.new_id, done.ids_after, done.changed)
    return EXIT_OK


def _through_hub(args) -> int:
    import asyncio

    from openbricks_server import hub_session

    async def talk(session):
        bus = {"tx": args.tx, "rx": args.rx, "baud": args.baudrate}
        if args.scan:
            result = await session.call("servo_scan", timeout_s=60, **bus)
            _report_scan(result["ids"], f"{args.name}'s servo bus")
            return EXIT_OK
        old_id = args.old_id
        if old_id is None:
            # The --old-id rule in the CLI's own words; the hub then re-IDs exactly the servo named.
            scan = await session.call("servo_scan", timeout_s=60, **bus)
            old_id = choose_old_id(scan["ids"], None, f"{args.name}'s servo bus")
        result = await session.call("servo_set_id", timeout_s=60, new_id=args.new_id, old_id=old_id, **bus)
        _report_reid(result["old_id"], result["new_id"], result["ids"], result["changed"])
        return EXIT_OK

    return asyncio.run(hub_session.with_hub(args.name, args.scan_timeout, talk))
