"""Files to and from a hub, through its host calls: `stage*` to write, `read_file` to read back.

Both directions carry base64 text (raw-REPL input is text, and a host call takes data, not code) and
check every byte: an upload is verified by size and crc32 on the hub before it replaces the old file;
a read checks each slice's size and crc32 and that the file did not change while it was read.
Commands are pipelined (see `RawRepl.exec_many`) so a file of many slices costs few round trips.
"""

from __future__ import annotations

import base64
import binascii
import zlib
from typing import TYPE_CHECKING

from openbricks.host_protocol import READ_FILE_MAX_BYTES
from openbricks_server.link.errors import LinkDropped, ProtocolError
from openbricks_server.link.host_call import Command, check_reply, command

if TYPE_CHECKING:
    from openbricks_server.link.raw_repl import RawRepl

# Staging: how much base64 text one raw-paste command may carry. The hub's lexer holds the whole
# string literal while it parses, then the str and the decoded bytes live next to it, so this bounds
# the hub's RAM per call (~30 KB at 12 KB, on a hub with ~100 KB free). A .mpy up to ~14 KB
# (compressing to 0.64) goes in one call; larger ones take one more command, pipelined.
DEFAULT_CALL_PAYLOAD_CHARS = 12 * 1024
# zlib window for staged payloads: the hub's inflater allocates 2**wbits bytes. 2 KB costs a few
# percent of ratio against 32 KB on .mpy files and keeps the hub's allocation small.
ZLIB_WBITS = 11
# Compression is used when it saves at least this fraction of the bytes on the wire.
COMPRESSION_MIN_SAVING = 0.05


def _any_failed(result) -> bool:
    return any(not reply.get("ok", False) for reply in result.results)


def _payload(data: bytes, compress: bool) -> tuple[str, str | None]:
    """The base64 text to send for `data` and its compression ("zlib" or None)."""
    payload, compression = data, None
    if compress:
        packer = zlib.compressobj(9, zlib.DEFLATED, ZLIB_WBITS)
        packed = packer.compress(data) + packer.flush()
        if len(packed) <= len(data) * (1 - COMPRESSION_MIN_SAVING):
            payload, compression = packed, "zlib"
    return base64.b64encode(payload).decode("ascii"), compression


def _stage_commands(
    path: str, text: str, compression: str | None, size: int, crc: int, chars: int
) -> list[Command]:
    """One `stage` call when the text fits `chars`, else begin + first chunk, middle chunks, last
    chunk + end: each command stays within the hub's RAM budget and no command waits for another."""
    if len(text) <= chars:
        data = {
            "payload": text,
            "path": path,
            "encoding": "base64",
            "compression": compression,
            "size": size,
            "crc32": crc,
        }
        return [command(("stage", data))]
    chunks = [text[i : i + chars] for i in range(0, len(text), chars)]
    commands = []
    for index, chunk in enumerate(chunks):
        calls = []
        if index == 0:
            calls.append(("stage_begin", {"path": path}))
        calls.append(("stage_append", {"payload": chunk}))
        if index == len(chunks) - 1:
            calls.append(("stage_end", {"compression": compression, "size": size, "crc32": crc}))
        commands.append(command(*calls))
    return commands


async def put(
    repl: RawRepl,
    path: str,
    data: bytes,
    *,
    compress: bool | None = None,
    call_payload_chars: int = DEFAULT_CALL_PAYLOAD_CHARS,
    timeout_s: float | None = None,
) -> dict:
    """Store `data` at `path` on the hub atomically; see `RawRepl.put`."""
    if compress is None:
        compress = repl.info_cache is not None and "zlib" in repl.info_cache.compression
    text, compression = _payload(data, compress)
    size, crc = len(data), zlib.crc32(data)
    commands = _stage_commands(path, text, compression, size, crc, call_payload_chars)
    try:
        results = await repl.exec_many(commands, timeout_s=timeout_s, stop_when=_any_failed)
    except LinkDropped as drop:
        raise LinkDropped(repl.hub, drop.reason, f"uploading {path} ({size} bytes)") from None
    replies = [check_reply(repl.hub, "stage", reply) for result in results for reply in result.results]
    final = replies[-1] if replies else {}
    if final.get("bytes") != size or final.get("crc32") != crc:
        raise ProtocolError(f"{repl.hub} confirmed {final!r} for {path}; expected {size} bytes, crc32 {crc}")
    return final


def _slice(hub: str, path: str, reply: dict, offset: int, total: int | None) -> bytes:
    """The bytes one read_file reply carries, after checking they are the ones asked for, intact."""
    if reply.get("offset") != offset:
        raise ProtocolError(f"{hub} answered for offset {reply.get('offset')} of {path}, asked for {offset}")
    if total is not None and reply.get("total_bytes") != total:
        raise ProtocolError(
            f"{path} on {hub} changed size while it was read ({total} -> {reply.get('total_bytes')} bytes): "
            "read it again once nothing writes to it"
        )
    try:
        block = base64.b64decode(reply.get("data", ""), validate=True)
    except binascii.Error as err:
        raise ProtocolError(f"{hub} sent unreadable base64 for {path} at offset {offset}: {err}") from None
    if len(block) != reply.get("bytes") or zlib.crc32(block) != reply.get("crc32"):
        raise ProtocolError(
            f"{path} from {hub} arrived damaged at offset {offset} "
            f"(size or crc32 differ from what the hub sent); read it again"
        )
    return block


async def get(
    repl: RawRepl, path: str, *, block_bytes: int = READ_FILE_MAX_BYTES, timeout_s: float | None = None
) -> bytes:
    """Read file `path` from the hub; see `RawRepl.get`."""
    if block_bytes < 1:
        raise ValueError(f"block_bytes={block_bytes}: read at least 1 byte per call")
    first = await repl.call("read_file", path=path, offset=0, size=block_bytes, timeout_s=timeout_s)
    total = first.get("total_bytes")
    out = bytearray(_slice(repl.hub, path, first, 0, None))
    if first.get("next_offset") is None:
        return bytes(out)
    # The hub may cap a slice below what was asked: its first slice tells the real step.
    step = len(out)
    offsets = list(range(step, total, step))
    commands = [command(("read_file", {"path": path, "offset": o, "size": step})) for o in offsets]
    try:
        results = await repl.exec_many(commands, timeout_s=timeout_s, stop_when=_any_failed)
    except LinkDropped as drop:
        raise LinkDropped(repl.hub, drop.reason, f"reading {path} ({len(out)} of {total} bytes)") from None
    for offset, result in zip(offsets, results, strict=False):
        if not result.results:
            raise ProtocolError(
                f"read_file on {repl.hub} printed no result line for {path} at offset {offset}"
            )
        reply = check_reply(repl.hub, "read_file", result.results[-1])
        out += _slice(repl.hub, path, reply, offset, total)
    if len(out) != total:
        raise ProtocolError(
            f"{path} on {repl.hub} came back as {len(out)} of {total} bytes: read it again once nothing "
            "writes to it"
        )
    return bytes(out)
