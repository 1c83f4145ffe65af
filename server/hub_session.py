"""One conversation with one hub, found by name: the frame every hub command runs in.

    result = asyncio.run(with_hub("RobotA", scan_timeout_s, talk))   # talk(session) -> result

1. take the hub's lock (hub_lock), so no other command or the console talks to it meanwhile;
2. find it: a virtual hub of that name on this computer first (no radio needed), else a BLE scan;
3. connect, enter the raw REPL (which stops whatever ran), read `info`, set the hub's clock from ours
   (so run-log stamps are real times);
4. run the command's own part;
5. hand the hub back to its launcher (so the program button works again) and close.

Link failures become CliErrors that say what happened and what to do; a dropped link keeps what was
already received on screen (the commands print as data arrives), and says so.
"""

from __future__ import annotations

import asyncio
import sys
import time
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from typing import Any, TypeVar

from openbricks_server.errors import CliError
from openbricks_server.hub_lock import hub_lock
from openbricks_server.link import (
    HubCallError,
    HubException,
    HubNotFound,
    LinkDropped,
    LinkError,
    LinkTimeout,
)
from openbricks_server.link.host_call import HubInfo, call_source
from openbricks_server.link.raw_repl import RawRepl

T = TypeVar("T")
CONNECT_TIMEOUT_S = 20.0
ENTER_TIMEOUT_S = 10.0
HAND_BACK_LINE = call_source("idle", {}).encode() + b"\r"
BOOT_WAIT_S = 20.0


class LinkLostError(CliError):
    """The connection went away mid-command."""


@dataclass
class HubSession:
    name: str
    repl: RawRepl
    info: HubInfo
    virtual: bool

    @property
    def link(self):
        return self.repl.link

    async def call(self, call: str, *, timeout_s: float | None = None, **data: Any) -> dict:
        return await self.repl.call(call, timeout_s=timeout_s, **data)


def _virtual_names() -> list[str]:
    from openbricks_server.link.discovery import virtual_hubs

    return [hub.name for hub in virtual_hubs()]


async def open_link(name: str, scan_timeout_s: float):
    """(link, virtual) for the hub called `name`; CliError naming the hubs seen when there is none."""
    from openbricks_server.link.discovery import find_virtual_hub
    from openbricks_server.link.serial_link import SerialLink

    virtual = find_virtual_hub(name)
    if virtual is not None:
        return SerialLink(virtual.pty, hub=name, connect_timeout_s=CONNECT_TIMEOUT_S), True
    try:
        from openbricks_server.link.ble import BleLink, find_hub

        advert = await find_hub(name, scan_timeout_s)
    except HubNotFound as exc:
        others = _virtual_names()
        extra = f"; virtual hubs running here: {', '.join(others)}" if others else ""
        raise CliError(f"{exc}{extra}") from None
    except Exception as exc:  # noqa: BLE001 - no adapter, no D-Bus, radio off: all mean "no BLE"
        others = _virtual_names()
        seen = ", ".join(others) if others else "none running"
        raise CliError(
            f"no hub named {name!r} was found: no virtual hub of that name runs on this computer "
            f"(virtual hubs: {seen}), and Bluetooth is unavailable on this computer "
            f"({bluetooth_unavailable(exc)}), so no real hub could be looked for; switch Bluetooth on, or "
            "check the name"
        ) from None
    return BleLink(name, device=advert.device, connect_timeout_s=CONNECT_TIMEOUT_S), False


def bluetooth_unavailable(exc: Exception) -> str:
    """Why a scan could not start, in words for the person at the table; the Bluetooth stack's own
    exception names say nothing to them."""
    text = str(exc).lower()
    if isinstance(exc, (FileNotFoundError, ConnectionRefusedError)):
        return "the system's Bluetooth service is not running"
    if isinstance(exc, PermissionError):
        return "this user may not use Bluetooth"
    if "adapter" in text:
        return "no Bluetooth adapter was found"
    if "powered" in text or "turned off" in text:
        return "the Bluetooth radio is switched off"
    return str(exc) or "the Bluetooth stack gave no reason"


def _packet_dump(data: bytes) -> None:
    """--debug: every packet as it arrives, with a time stamp, hex and printable text."""
    stamp = time.strftime("%H:%M:%S") + f".{int(time.time() * 1000) % 1000:03d}"
    text = "".join(chr(b) if 32 <= b < 127 else "." for b in data)
    print(f"[{stamp}] {len(data):4d} B  {data.hex(' ')}  |{text}|", file=sys.stderr, flush=True)


def _tap(link, listener: Callable[[bytes], None]) -> None:
    received = link._received  # the transport's single entry point for incoming bytes

    def tapped(data: bytes) -> None:
        listener(bytes(data))
        received(data)

    link._received = tapped


def translate(name: str, exc: LinkError, dropped: bool = False) -> CliError:
    """A link failure as the message a user acts on; `dropped`: the link had dropped before it."""
    if isinstance(exc, LinkDropped) or dropped:
        reason = exc.reason if isinstance(exc, LinkDropped) else f"reconnecting failed: {exc}"
        return LinkLostError(
            f"the link to {name} was lost ({reason}); what arrived before is shown above. If a program "
            f"was running it may still run: `openbricks log -n {name}` shows its output later"
        )
    if isinstance(exc, LinkTimeout):
        return CliError(f"{name} stopped answering: {exc}; check that it is powered and in range, then retry")
    if isinstance(exc, HubCallError):
        return CliError(f"{name}: {exc.error}")
    if isinstance(exc, HubException):
        return CliError(hub_exception_message(name, exc))
    return CliError(f"{name}: {exc}")


def hub_exception_message(name: str, exc: HubException) -> str:
    """One line for code the CLI sent that raised on the hub (host calls do not raise by design), with
    the likely cause; the hub's traceback is for --debug, not for the person at the table."""
    kind = exc.summary.split(":", 1)[0]
    if kind in ("ImportError", "AttributeError"):
        return (
            f"{name} raised {exc.summary}: its firmware lacks host calls this openbricks uses; "
            f"update it with `openbricks flash`"
        )
    if kind == "MemoryError":
        return f"{name} ran out of memory ({exc.summary}); press its RESET button to free it, then retry"
    return f"{name} raised {exc.summary}"


async def _hand_back(session: HubSession) -> None:
    """Back to the launcher: `idle()` never returns (it is the launcher's loop), so it is typed at the
    friendly prompt rather than run as a raw command whose end we would wait for."""
    await session.repl.exit()
    await session.link.write(HAND_BACK_LINE)
    try:
        await session.link.read_until(b'"idle": true', "the hub's return to its launcher", 3.0)
    except LinkError:
        pass  # the command is done either way; the hub finishes the hand-back by itself


async def with_hub(
    name: str,
    scan_timeout_s: float,
    talk: Callable[[HubSession], Awaitable[T]],
    *,
    debug: bool = False,
    hand_back: bool = True,
) -> T:
    with hub_lock(name):
        link, virtual = await open_link(name, scan_timeout_s)
        if debug:
            _tap(link, _packet_dump)
        session = None
        try:
            await link.connect()
            repl = RawRepl(link)
            await repl.enter(timeout_s=ENTER_TIMEOUT_S)
            info = await repl.info()
            await repl.set_rtc(int(time.time() * 1000))
            session = HubSession(name, repl, info, virtual)
            return await talk(session)
        except LinkError as exc:
            raise translate(name, exc, dropped=link.dropped_at is not None) from None
        finally:
            # Whatever happened, a hub we can still reach goes back to its launcher, or its program
            # button stays dead until the next connection. Not when the user left mid-wait (Ctrl-C
            # twice): the hub may still be running, and the hand-back line would reach the program.
            task = asyncio.current_task()
            if hand_back and session is not None and link.is_open and not (task and task.cancelling()):
                try:
                    await _hand_back(session)
                except LinkError:
                    pass
            await link.close()


# -- over USB, for flash ----------------------------------------------------------------------------


async def read_serial_info(port: str) -> HubInfo | None:
    """The firmware on the hub at `port`, or None if no openbricks firmware answers there."""
    from openbricks_server.link.serial_link import SerialLink

    link = SerialLink(port, connect_timeout_s=5.0)
    try:
        await link.connect()
        repl = RawRepl(link)
        await repl.enter(timeout_s=3.0)
        return await repl.info(timeout_s=3.0)
    except (LinkError, OSError):
        return None
    finally:
        await link.close()


async def set_up_flashed_hub(port: str, name: str, provenance: str, qtr_calibration: bytes | None) -> dict:
    """After a flash: wait for the boot, name the hub (read back), record provenance, optional QTR file,
    then reset so the hub comes up advertising its name."""
    from openbricks_server.link.serial_link import SerialLink

    deadline = asyncio.get_running_loop().time() + BOOT_WAIT_S
    last_error: Exception | None = None
    while asyncio.get_running_loop().time() < deadline:
        link = SerialLink(port, connect_timeout_s=5.0)
        try:
            await link.connect()
            repl = RawRepl(link)
            await repl.enter(timeout_s=3.0)
            await repl.info()
            named = await repl.call("set_hub_name", hub_name=name)
            if named.get("hub_name") != name:
                raise CliError(
                    f"the hub read back name {named.get('hub_name')!r} instead of {name!r}; flash again"
                )
            recorded = await repl.call("record_provenance", verdict=provenance)
            if qtr_calibration is not None:
                await repl.put("/qtr.cal", qtr_calibration)
            await repl.reset_hub()  # it comes back up advertising its new name
            return {"hub_name": named["hub_name"], "firmware": recorded["firmware"]}
        except HubCallError as exc:
            raise CliError(f"the flashed hub on {port} refused {exc.call}: {exc.error}") from None
        except HubException as exc:  # e.g. a host call it lacks: not a hub that is still booting
            raise CliError(f"the flashed hub on {port}: {hub_exception_message(name, exc)}") from None
        except (LinkError, OSError) as exc:  # not up yet: still booting
            last_error = exc
            await asyncio.sleep(0.5)
        finally:
            await link.close()
    raise CliError(
        f"the hub on {port} did not answer after the flash ({last_error}); press its RESET button and run "
        "`openbricks flash` again with --skip-erase"
    )
