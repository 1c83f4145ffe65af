"""`openbricks paste-probe`: the largest program the hub's raw-paste path takes, and how failures look.

Do-nothing programs of doubling size (padded with comment lines, ending in one print of a token) go
through the real raw-paste path. A size passes when the token comes back; otherwise the failure is
"truncated" (the hub ran or parsed a cut program: an error instead of the token) or "hung" (nothing
within --timeout). After a failure the REPL is re-entered so the next size starts clean.
"""

from __future__ import annotations

import asyncio
import time

from openbricks_server.errors import EXIT_FAILED, EXIT_OK
from openbricks_server.hub_session import with_hub
from openbricks_server.link import HubException, LinkTimeout

FIRST_SIZE = 256


def padded_program(size: int, token: str) -> bytes:
    """Exactly `size` bytes (when larger than the final print): comment lines, then the print."""
    tail = f"print({token!r})\n".encode()
    room = size - len(tail)
    lines = []
    while room > 0:
        n = min(64, room)
        lines.append(b"#" + b"." * (n - 2) + b"\n" if n >= 2 else b"\n")
        room -= n
    return b"".join(lines) + tail


def sizes(max_bytes: int) -> list[int]:
    out, size = [], FIRST_SIZE
    while size < max_bytes:
        out.append(size)
        size *= 2
    return out + [max_bytes]


async def _probe(session, max_bytes: int, timeout_s: float):
    repl = session.repl
    results = []
    for size in sizes(max_bytes):
        token = f"paste-probe-{size}"
        program = padded_program(size, token)
        started = time.perf_counter()
        try:
            result = await repl.exec(program, timeout_s=timeout_s)
            ok = token.encode() in result.stdout
            verdict = "ok" if ok else "truncated (ran without printing the token)"
        except HubException as exc:
            ok, verdict = False, f"truncated ({exc.traceback.strip().splitlines()[-1]})"
        except LinkTimeout:
            ok, verdict = False, f"hung (no answer within {timeout_s:g} s)"
        elapsed = time.perf_counter() - started
        rate = f"{len(program) / elapsed / 1024:7.1f} KB/s" if ok and elapsed > 0 else ""
        print(f"{len(program):>7} bytes  {verdict:<12} {rate}".rstrip(), flush=True)
        results.append((len(program), ok))
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
