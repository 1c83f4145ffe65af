"""Scanning a serial servo bus and re-IDing a servo, through a USB half-duplex adapter or through a hub:
the one implementation behind `openbricks servo-id` and the console's servo jobs, with their messages.

Over USB the host runs the rules itself (`UsbServoBus`, `reid`); through a hub, the hub's own
`servo_scan` / `servo_set_id` host calls (openbricks.host_calls) run them on the robot's bus, with the
same rules:
- the tool never guesses: with more than one servo answering, the caller names `old_id`;
- a new id already in use is refused (two servos on one id answer on top of each other);
- the write is checked by reading the id register back from the new id, and by the old id falling
  silent; only then is the change reported.

Packets are built and parsed by the firmware's own SCS codec (`openbricks_native.scs`). Half-duplex
adapters often hear their own transmission: an echo of the request ahead of the reply is skipped.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from openbricks_native import scs
from openbricks_server.errors import CliError, UsageError

FIRST_ID = 0
LAST_ID = scs.MAX_SERVO_ID
_UNLOCK, _LOCK = b"\x00", b"\x01"


class ServoIdError(CliError):
    """The bus or the servo did not do what re-IDing needs."""


def check_id(option: str, value: int | None) -> None:
    if value is not None and not FIRST_ID <= value <= LAST_ID:
        raise UsageError(
            f"{option} {value}: servo bus ids are {FIRST_ID}..{LAST_ID} "
            f"({scs.BROADCAST_ID} is the broadcast id)"
        )


@dataclass(frozen=True)
class Reid:
    old_id: int
    new_id: int
    ids_after: list[int]
    changed: bool


class UsbServoBus:
    """One serial port with servos on it; each request waits `timeout_s` at most for its reply."""

    def __init__(self, port: str, baudrate: int, timeout_s: float):
        import serial

        self.scs = scs
        self.port = port
        self.timeout_s = timeout_s
        try:
            self.serial = serial.Serial(port, baudrate, timeout=min(timeout_s, 0.01))
        except (serial.SerialException, OSError) as exc:
            from openbricks_server.flash.ports import port_problem

            raise ServoIdError(f"cannot open {port}: {port_problem(port, exc)}") from None

    def close(self) -> None:
        self.serial.close()

    def __enter__(self) -> UsbServoBus:
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()

    def _transfer(self, packet: bytes, servo_id: int):
        """Send `packet`; the status reply from `servo_id`, or None if none came in time."""
        self.serial.reset_input_buffer()
        self.serial.write(packet)
        self.serial.flush()
        buffer = b""
        echo_skipped = False
        deadline = time.monotonic() + self.timeout_s
        while time.monotonic() < deadline:
            buffer += self.serial.read(64)
            if not echo_skipped:
                # An echoing adapter hands our own request back first, maybe behind a late reply to the
                # previous request. A ping's echo reads exactly like a status frame from the pinged id,
                # so everything up to and including the echo is dropped before any reply is believed.
                echo_at = buffer.find(packet)
                if echo_at >= 0:
                    buffer = buffer[echo_at + len(packet) :]
                    echo_skipped = True
            while buffer:
                status = self.scs.decode_status(buffer)
                if status.result == "ok" and status.id == servo_id:
                    return status
                if status.result == "need_more" and not status.consumed:
                    break  # a frame still arriving
                buffer = buffer[max(status.consumed, 1) :]  # noise or another servo's frame: drop, look on
        return None

    def ping(self, servo_id: int) -> bool:
        return self._transfer(self.scs.ping(servo_id), servo_id) is not None

    def read(self, servo_id: int, register: int, length: int) -> bytes | None:
        status = self._transfer(self.scs.read(servo_id, register, length), servo_id)
        return None if status is None else bytes(status.params)

    def write(self, servo_id: int, register: int, data: bytes, expect_reply_from: int | None = None) -> bool:
        replier = servo_id if expect_reply_from is None else expect_reply_from
        return self._transfer(self.scs.write(servo_id, register, data), replier) is not None

    def scan(self) -> list[int]:
        # A second ping confirms each answer, so a stray late frame cannot list a servo that is not there.
        return [i for i in range(FIRST_ID, LAST_ID + 1) if self.ping(i) and self.ping(i)]

    def where(self) -> str:
        return usb_where(self.port)


def choose_old_id(ids: list[int], old_id: int | None, where: str, option: str = "--old-id") -> int:
    """The servo to re-ID by the --old-id rule: the lone servo on the bus, or the one named; never guessed."""
    listed = ", ".join(str(i) for i in ids)
    if not ids:
        raise ServoIdError(f"no servo answers on {where}: check its power and the data wiring, then --scan")
    if old_id is None:
        if len(ids) > 1:
            raise ServoIdError(
                f"{len(ids)} servos answer (ids {listed}): pass {option} to say which one to re-ID; it is "
                "never guessed"
            )
        return ids[0]
    if old_id not in ids:
        raise ServoIdError(f"no servo answers at {option} {old_id}; the bus has ids {listed}")
    return old_id


def reid(bus: UsbServoBus, new_id: int, old_id: int | None, option: str = "--old-id") -> Reid:
    """Give one servo `new_id`, verified by read-back; see the module rules."""
    check_id("new id", new_id)
    check_id(option, old_id)
    scs = bus.scs
    ids = bus.scan()
    listed = ", ".join(str(i) for i in ids)
    old_id = choose_old_id(ids, old_id, bus.where(), option)
    if new_id == old_id:
        return Reid(old_id, new_id, ids, False)
    if new_id in ids:
        raise ServoIdError(
            f"id {new_id} is already taken by another servo on the bus (in use: {listed}); pick a free id"
        )
    if not bus.write(old_id, scs.REG_LOCK, _UNLOCK):
        raise ServoIdError(f"servo {old_id} did not acknowledge the EEPROM unlock; nothing was changed")
    # The servo answers an id write from its new id (or not at all): the read-back is the real check.
    bus.write(old_id, scs.REG_ID, bytes((new_id,)), expect_reply_from=new_id)
    bus.write(new_id, scs.REG_LOCK, _LOCK)
    readback = bus.read(new_id, scs.REG_ID, 1)
    if readback is None or readback[0] != new_id:
        raise ServoIdError(
            f"servo {old_id} did not come back as id {new_id} after the write: --scan to see where it is"
        )
    after = bus.scan()
    if old_id in after:
        raise ServoIdError(
            f"a servo still answers at id {old_id} after the re-ID (two servos shared that id?): wire one "
            "servo at a time and retry"
        )
    return Reid(old_id, new_id, after, True)


# -- reports and the two ways to reach a bus, shared by the CLI and the console ---------------------------

HUB_CALL_TIMEOUT_S = 60.0  # a full scan through the hub pings 254 ids


def scan_report(ids: list[int], where: str) -> str:
    if ids:
        return f"servo ids on {where}: {', '.join(str(i) for i in ids)}"
    return f"no servo answers on {where}"


def reid_report(done: Reid) -> str:
    if not done.changed:
        return f"servo {done.old_id} already has id {done.new_id}; nothing to change"
    return (
        f"servo {done.old_id} is now id {done.new_id} (read back from the servo); ids on the bus: "
        f"{', '.join(str(i) for i in done.ids_after)}"
    )


def usb_where(port: str) -> str:
    return f"the bus on {port}"


def hub_where(hub_name: str) -> str:
    return f"{hub_name}'s servo bus"


def scan_usb(port: str, baudrate: int, timeout_s: float) -> list[int]:
    """The ids answering on a USB adapter's bus (blocking: a thread's work in the console)."""
    with UsbServoBus(port, baudrate, timeout_s) as bus:
        return bus.scan()


def reid_usb(
    port: str, baudrate: int, timeout_s: float, new_id: int, old_id: int | None, option: str = "--old-id"
) -> Reid:
    with UsbServoBus(port, baudrate, timeout_s) as bus:
        return reid(bus, new_id, old_id, option)


async def scan_through_hub(call, bus: dict) -> list[int]:
    """`call(name, timeout_s=..., **args)` makes a host call on the hub (a HubSession's or an actor's);
    `bus` is the hub's servo UART: {"tx", "rx", "baud"}."""
    return list((await call("servo_scan", timeout_s=HUB_CALL_TIMEOUT_S, **bus))["ids"])


async def reid_through_hub(
    call, bus: dict, new_id: int, old_id: int | None, where: str, option: str = "--old-id"
) -> Reid:
    check_id("new id", new_id)
    check_id(option, old_id)
    if old_id is None:
        # The --old-id rule in the host's own words; the hub then re-IDs exactly the servo named.
        old_id = choose_old_id(await scan_through_hub(call, bus), None, where, option)
    done = await call("servo_set_id", timeout_s=HUB_CALL_TIMEOUT_S, new_id=new_id, old_id=old_id, **bus)
    return Reid(int(done["old_id"]), int(done["new_id"]), list(done["ids"]), bool(done["changed"]))
