"""`openbricks paste-probe`: the largest command the hub's raw-paste path takes, and how failures look.

Do-nothing commands of doubling size go through the real raw-paste path: each is the hub's
`paste_probe` host call with a token and padding text, sized to the byte. A size passes when the
hub echoes the token and counts every padding byte; otherwise the failure is "truncated" (the hub
parsed a cut command: an error, or fewer bytes than sent) or "hung" (nothing within --timeout).
After a failure the REPL is re-entered so the next size starts clean.
"""

from __future__ import annotations

import asyncio
import time

from openbricks_server.cli import PROBE_FIRST_SIZE
from openbricks_server.errors import EXIT_FAILED, EXIT_OK, CliError
from openbricks_server.hub_session import hub_exception_message, with_hub
from openbricks_server.link import HubException, LinkTimeout
from openbricks_server.link.host_call import Command, command


def probe_command(size: int, token: str) -> tuple[Command, int]:
    """The `paste_probe` call that is exactly `size` bytes (when larger than the bare call), and how
    many padding bytes it carries."""
    bare = len(command(("paste_probe", {"token": token, "padding": ""})).source)
    padding = max(size - bare, 0)
    return command(("paste_probe", {"token": token, "padding": "." * padding})), padding


def sizes(max_bytes: int) -> list[int]:
    out, size = [], PROBE_FIRST_SIZE
    while size < max_bytes:
        out.append(size)
        size *= 2
    return out + [max_bytes]


async def _probe(session, max_bytes: int, timeout_s: float):
    repl = session.repl
    results = []
    for size in sizes(max_bytes):
        token = f"paste-probe-{size}"
        probe, padding = probe_command(size, token)
        started = time.perf_counter()
        try:
            result = await repl.exec(probe, timeout_s=timeout_s)
            reply = result.results[-1] if result.results else {}
            ok = reply.get("token") == token and reply.get("padding_bytes") == padding
            if ok:
                verdict = "ok"
            elif "padding_bytes" in reply:
                verdict = f"truncated (the hub got {reply['padding_bytes']} of {padding} padding bytes)"
            else:
                verdict = "truncated (ran without echoing the token)"
        except HubException as exc:
            if exc.summary.startswith("AttributeError") and "paste_probe" in exc.summary:
                raise CliError(hub_exception_message(session.name, exc)) from None
            ok, verdict = False, f"truncated ({exc.summary})"
        except LinkTimeout:
            ok, verdict = False, f"hung (no answer within {timeout_s:g} s)"
        elapsed = time.perf_counter() - started
        rate = f"{len(probe.source) / elapsed / 1024:7.1f} KB/s" if ok and elapsed > 0 else ""
        print(f"{len(probe.source):>7} bytes  {verdict:<12} {rate}".rstrip(), flush=True)
        results.append((len(probe.source), ok))
        if not ok:
            await repl.enter(timeout_s=timeout_s)
    window = repl.paste_window
    return results, window


def main(args) -> int:
    results, window = asyncio.run(
        with_hub(args.name, args.scan_timeout, lambda session: _probe(session, args.max, args.timeout))
    )
    passed = [size for size, ok in results if ok]
    print(f"raw-paste window granted by {args.name}: {window} bytes")
    if passed:
        print(f"largest program that completed: {max(passed)} bytes")
    if all(ok for _size, ok in results):
        return EXIT_OK
    print("some sizes failed: keep MICROPY_REPL_STDIN_BUFFER_MAX at or below the largest size that passed")
    return EXIT_FAILED
