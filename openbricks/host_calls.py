"""The hub side of every host operation, called over the raw REPL with data, never with generated code.

The host sends one short line such as `import openbricks.host_calls as h;h.tag('9f2c41d0');h.info()`
and reads back one result frame: `@openbricks:<tag> result <json>`, a JSON object with `"ok": true`
and the data, or `"ok": false` with `"error"` (what went wrong and how to fix it) and `"type"` (the
exception class). The tag is a fresh nonce the host picks for every call, so output a program
prints can neither be taken for a frame nor hide one, whatever it prints (no newline at the end,
text that looks like a frame). `run` frames the program's output too: `@openbricks:<tag> program`
before it, the result frame after it, so the host knows that bytes in between (a Ctrl-D included)
are the program's. A frame is written whole even if a Ctrl-C lands meanwhile (it is written again
and the interrupt raised after it), so a stop never cuts the result short.

A host that stays connected (the console daemon) passes `watch=<nonce>` to `run` and `idle`: each
program run is then announced on the console as `@openbricks:<nonce> run-begin {"run", "slot",
"started_ms"}` (the run log's index, slot and header stamp: the key that matches live output to the
log read back later) and, for button runs, `@openbricks:<nonce> run-end {"run", "outcome"}`; the
program's `openbricks.tools.plot()` samples carry the same nonce, and so do the line stamps
(`@openbricks:<nonce> t <ms>`, openbricks.log). Text a program prints can't pass
for these: it does not know the nonce.

Calls: info, set_rtc, stage, stage_begin / stage_append / stage_end, read_file, run, runs, read_run,
idle, identify, reset, paste_probe, record_provenance, set_hub_name, servo_scan, servo_set_id. Binary payloads
travel as base64 text, optionally zlib-compressed (the hub has `deflate`), because raw-REPL input is
text and base64 of compressed bytes is shorter than a Python bytes literal of the originals.
"""

import binascii
import gc
import io
import json
import os
import sys
import time

import machine

import openbricks
from openbricks import _native, launcher, log, pins, tools
from openbricks.host_protocol import FRAME_PREFIX, MAX_PROGRAM_BYTES, READ_CHUNK_BYTES, READ_FILE_MAX_BYTES

PROTOCOL = 2  # 2: tagged frames (tag(), "program" and "result" frames)
SERVO_UART_ID = 1
SERVO_TX = 14
SERVO_RX = 41
SERVO_BAUD = 1000000
_S_IFDIR = 0x4000
RESET_GRACE_MS = 100  # lets the reset reply drain from the UART/BLE buffers before the chip restarts
WATCHED_NOTE = "watched: "  # the run log's record of the nonce a watched run's frames carry
IDENTIFY_MAX_MS = 30000

_EPOCH_2000_MS = 946684800000

_staging = {}  # the chunked upload in progress: path, part, file, received
_tag = ["-"]  # the host's nonce for the frames of the call now running
_answered_after = [None]  # launcher.last_end() when a host call last replied (run's own reply aside)


def tag(nonce):
    """Take the host's nonce for the frames of the call that follows on the same command line."""
    _tag[0] = str(nonce)


def _frame(kind, payload=""):
    """Write one frame whole; returns the KeyboardInterrupt that landed meanwhile (or None).

    An interrupted write is written again, marked "again": the host then drops what the cut one
    left (it cannot tell a cut frame's first bytes from program output otherwise).
    """
    body = kind + (" " + payload if payload else "") + "\n"
    interrupted = None
    while True:
        try:
            print(FRAME_PREFIX + _tag[0] + (" again " if interrupted else " ") + body, end="")
            return interrupted
        except KeyboardInterrupt as exc:
            interrupted = exc


def _last_run_report():
    """How the latest run ended, and whether it ended after the last reply of a host call: a run
    stopped by a console Ctrl-C since then was stopped by the Ctrl-C that opened this session (a
    CLI killed mid-run leaves its program running; `openbricks stop` says it stopped it)."""
    end = launcher.last_end()
    if end is None:
        return None
    return {
        "index": end[0],
        "outcome": end[1],
        "trigger": end[2],
        "stopped_by": end[3],
        "since_last_call": end is not _answered_after[0],
    }


def _reply(result):
    _answered_after[0] = launcher.last_end()
    interrupted = _frame("result", json.dumps(result))
    if interrupted is not None:
        raise interrupted
    return result


def _call(fn, *args, **kwargs):
    """Run one host call and print its single result line; KeyboardInterrupt still propagates."""
    try:
        result = fn(*args, **kwargs)
    except KeyboardInterrupt:
        raise
    except Exception as exc:  # noqa: BLE001 - every failure must reach the host as data
        return _reply({"ok": False, "type": type(exc).__name__, "error": str(exc)})
    result["ok"] = True
    return _reply(result)


# -- version and capabilities --------------------------------------------------------------------


def _info():
    impl = sys.implementation
    mpy = getattr(impl, "_mpy", None)
    try:
        import deflate  # noqa: F401

        compression = ["zlib"]
    except ImportError:
        compression = []
    gc.collect()
    return {
        "protocol": PROTOCOL,
        "firmware": openbricks.firmware_label(),
        "version": openbricks.__version__,
        "provenance": openbricks.provenance(),
        "chip": pins.chip(),
        "machine": getattr(impl, "_machine", None),
        "runtime": "%s %s" % (impl.name, ".".join([str(part) for part in impl.version[:3]])),
        "accepts_mpy": mpy is not None,
        "mpy_version": None if mpy is None else mpy & 0xFF,
        "program_path": launcher.DEFAULT_PROGRAM_PATH,
        "max_program_bytes": MAX_PROGRAM_BYTES,
        "compression": compression,
        "log_slots": log.MAX_RUNS,
        "log_max_bytes": log.MAX_BYTES,
        "running": launcher.program_running(),
        "last_run": _last_run_report(),
        "free_bytes": gc.mem_free() if hasattr(gc, "mem_free") else None,
        "epoch_ms": log.epoch_ms(),
    }


def info():
    """Firmware label, chip, runtime and what the hub accepts (.mpy version, sizes, log slots)."""
    return _call(_info)


# -- the clock -----------------------------------------------------------------------------------


def _set_rtc(epoch_ms):
    if not isinstance(epoch_ms, int) or epoch_ms < _EPOCH_2000_MS:
        raise ValueError("epoch_ms=%r: pass the host's UTC time as integer Unix milliseconds" % (epoch_ms,))
    port_s = epoch_ms // 1000
    if time.gmtime(0)[0] == 2000:
        port_s -= _EPOCH_2000_MS // 1000
    t = time.gmtime(port_s)
    # RTC tuple: (year, month, day, weekday, hours, minutes, seconds, microseconds)
    machine.RTC().datetime((t[0], t[1], t[2], t[6], t[3], t[4], t[5], (epoch_ms % 1000) * 1000))
    return {"epoch_ms": log.epoch_ms()}


def set_rtc(epoch_ms):
    """Set the hub clock to the host's UTC time so run-log stamps are real wall-clock times."""
    return _call(_set_rtc, epoch_ms)


# -- staging a program ---------------------------------------------------------------------------


def _decode(payload, encoding):
    if encoding == "base64":
        # Bytes in: some builds' binascii (the pure-Python one) only takes bytes.
        return binascii.a2b_base64(payload.encode() if isinstance(payload, str) else payload)
    if encoding == "raw":
        return bytes(payload)
    raise ValueError("encoding=%r: use 'base64' (text) or 'raw' (bytes)" % (encoding,))


def _check_path(path):
    if not isinstance(path, str) or not path.startswith("/") or path.endswith("/") or ".." in path:
        raise ValueError("path=%r: stage to an absolute file path such as /program.mpy" % (path,))


def _copy_out(source, dest, compression):
    """Copy (and inflate) stream `source` into file `dest`; returns (size, crc32) of what was written."""
    if compression == "zlib":
        try:
            import deflate
        except ImportError:
            raise ValueError("this runtime has no deflate module: stage the program uncompressed") from None
        source = deflate.DeflateIO(source, deflate.ZLIB)
    elif compression is not None:
        raise ValueError("compression=%r: use 'zlib' or None" % (compression,))
    size = 0
    crc = 0
    buf = bytearray(512)
    view = memoryview(buf)
    while True:
        n = source.readinto(buf)
        if not n:
            return size, crc
        size += n
        if size > MAX_PROGRAM_BYTES:
            raise ValueError(
                "program is larger than the hub accepts (%d bytes max); split it into modules"
                % MAX_PROGRAM_BYTES
            )
        crc = binascii.crc32(view[:n], crc)
        dest.write(view[:n])


def _remove(path):
    try:
        os.remove(path)
    except OSError:
        pass


def _commit(part, path, size, crc, want_size, want_crc32):
    """Verify the temp file and move it into place, so a broken upload never replaces a good program."""
    if want_size is not None and size != want_size:
        _remove(part)
        raise ValueError("upload truncated: got %d bytes, expected %d; stage it again" % (size, want_size))
    if want_crc32 is not None and crc != want_crc32 & 0xFFFFFFFF:
        _remove(part)
        raise ValueError("upload corrupted: crc32 %08x, expected %08x; stage it again" % (crc, want_crc32))
    try:
        os.rename(part, path)
    except OSError:
        _remove(path)  # filesystems that refuse to rename over an existing file
        os.rename(part, path)
    # The launcher (and import) would pick up a stale .py/.mpy sibling: it must not shadow this one.
    if path.endswith(".mpy"):
        _remove(path[:-4] + ".py")
    elif path.endswith(".py"):
        _remove(path[:-3] + ".mpy")
    return {"path": path, "bytes": size, "crc32": crc}


def _stage(payload, path, encoding, compression, size, crc32):
    _check_path(path)
    if launcher.program_running():
        raise RuntimeError("a program is running: stop it before staging a new one")
    data = _decode(payload, encoding)
    part = path + ".part"
    with open(part, "wb") as f:
        try:
            got, crc = _copy_out(io.BytesIO(data), f, compression)
        except Exception:
            f.close()
            _remove(part)
            raise
    return _commit(part, path, got, crc, size, crc32)


def stage(
    payload, path=launcher.DEFAULT_PROGRAM_PATH, encoding="base64", compression=None, size=None, crc32=None
):
    """Write a program to `path` atomically (temp file, verify `size`/`crc32` of the result, rename)."""
    return _call(_stage, payload, path, encoding, compression, size, crc32)


def _stage_begin(path):
    _check_path(path)
    if launcher.program_running():
        raise RuntimeError("a program is running: stop it before staging a new one")
    _stage_abort()
    part = path + ".upload"
    _staging.update(path=path, part=part, file=open(part, "wb"), received=0)
    return {"path": path}


def _stage_abort():
    f = _staging.get("file")
    if f is not None:
        f.close()
        _remove(_staging["part"])
    _staging.clear()


def _stage_append(payload, encoding):
    if not _staging:
        raise RuntimeError("no upload in progress: call stage_begin(path) first")
    data = _decode(payload, encoding)
    _staging["received"] += len(data)
    if _staging["received"] > MAX_PROGRAM_BYTES:
        _stage_abort()
        raise ValueError("program is larger than the hub accepts (%d bytes max)" % MAX_PROGRAM_BYTES)
    _staging["file"].write(data)
    return {"received": _staging["received"]}


def _stage_end(compression, size, crc32):
    if not _staging:
        raise RuntimeError("no upload in progress: call stage_begin(path) first")
    path, upload = _staging["path"], _staging["part"]
    _staging["file"].close()
    _staging.clear()
    part = path + ".part"
    try:
        with open(upload, "rb") as source, open(part, "wb") as dest:
            got, crc = _copy_out(source, dest, compression)
    except Exception:
        _remove(part)
        raise
    finally:
        _remove(upload)
    return _commit(part, path, got, crc, size, crc32)


def stage_begin(path=launcher.DEFAULT_PROGRAM_PATH):
    """Start a chunked upload (for programs too big for one call); any unfinished one is dropped."""
    return _call(_stage_begin, path)


def stage_append(payload, encoding="base64"):
    """Append one chunk (as sent: still compressed if the upload is)."""
    return _call(_stage_append, payload, encoding)


def stage_end(compression=None, size=None, crc32=None):
    """Finish the chunked upload: inflate if needed, verify, and move it into place."""
    return _call(_stage_end, compression, size, crc32)


# -- reading a file back -------------------------------------------------------------------------


def _read_file(path, offset, size):
    if not isinstance(path, str) or not path.startswith("/") or path.endswith("/"):
        raise ValueError("path=%r: give an absolute file path such as /program.py" % (path,))
    if not isinstance(offset, int) or offset < 0:
        raise ValueError("offset=%r: give a byte offset of 0 or more" % (offset,))
    if not isinstance(size, int) or size < 1:
        raise ValueError("size=%r: give the number of bytes to read (1 or more)" % (size,))
    try:
        stat = os.stat(path)
    except OSError:
        raise OSError("no file %s on the hub: check the path (names are case-sensitive)" % path) from None
    if stat[0] & _S_IFDIR:
        raise OSError("%s on the hub is a directory, not a file: name a file inside it" % path)
    total = stat[6]
    with open(path, "rb") as f:
        f.seek(offset)
        data = f.read(min(size, READ_FILE_MAX_BYTES))
    end = offset + len(data)
    return {
        "path": path,
        "offset": offset,
        "bytes": len(data),
        "crc32": binascii.crc32(data) & 0xFFFFFFFF,
        "data": binascii.b2a_base64(data).decode().strip(),
        "total_bytes": total,
        "next_offset": end if end < total else None,
    }


def read_file(path, offset=0, size=READ_FILE_MAX_BYTES):
    """Up to `size` bytes of file `path` from byte `offset`, as base64 with their length and crc32 so
    the host can verify each slice; call again at `next_offset` until it is None."""
    return _call(_read_file, path, offset, size)


# -- running and the run logs --------------------------------------------------------------------


def _alnum(text):
    for char in text:
        if not ("0" <= char <= "9" or "a" <= char <= "z" or "A" <= char <= "Z"):
            return False
    return True


class _Watch:
    """While a host watches (`watch=<nonce>`): run starts and ends announced, plot() samples tagged."""

    def __init__(self, nonce):
        if nonce is not None and (not isinstance(nonce, str) or not nonce or not _alnum(nonce)):
            raise ValueError("watch=%r: give the host's nonce as letters and digits" % (nonce,))
        self.nonce = nonce

    def frame(self, kind, payload):
        text = FRAME_PREFIX + self.nonce + " " + kind + " " + json.dumps(payload) + "\n"
        print(text, end="")
        log.count_printed(text)  # inside the program's output: counted with it (log.printed)

    def _on_running(self, running):
        session = log.active()
        if running and session is not None:
            # In the log too: its plot lines are this run's samples, other lookalikes its output.
            session.write_text(WATCHED_NOTE + self.nonce)
            slot = session.index % log.MAX_RUNS
            self.frame("run-begin", {"run": session.index, "slot": slot, "started_ms": session.started_ms})

    def on_run_end(self, outcome):
        self.frame("run-end", {"run": _last_run(launcher.get().log_dir), "outcome": outcome})

    def __enter__(self):
        if self.nonce is not None:
            launcher.add_listener(self._on_running)
            tools._plot_tag[0] = self.nonce
            log.stamp_console(self.nonce)
        return self

    def __exit__(self, *exc_info):
        if self.nonce is not None:
            launcher.remove_listener(self._on_running)
            tools._plot_tag[0] = None
            log.stamp_console(None)
        return False


def run(path=None, watch=None, name=None):
    """Run the staged program through the launcher between a program frame and the result frame
    (`name`: the program's own file name, for its tracebacks).

    Whatever ends the run, the result frame follows: a stop (program button or Ctrl-C, even one
    that lands while the run is being wrapped up) prints it and then propagates KeyboardInterrupt,
    as any interrupted raw-REPL command does. With `watch`, the run's start is announced (see the
    top) inside the program's output.
    """
    try:
        watcher = _Watch(watch)
    except ValueError as exc:
        return _reply({"ok": False, "type": "ValueError", "error": str(exc)})
    interrupted = None
    result = None
    before = None  # the newest run log before this run: a newer one is this run's
    try:
        hub = launcher.get()
        before = _last_run(hub.log_dir)
        interrupted = _frame("program")
        if interrupted is None:
            with watcher:
                result = {"ok": True, "outcome": hub.run_program("host run", path, name=name)}
    except KeyboardInterrupt as exc:
        interrupted = exc
    except Exception as exc:  # noqa: BLE001 - e.g. nothing staged: the host gets the reason
        result = {"ok": False, "type": type(exc).__name__, "error": str(exc)}
    if result is None:
        result = {"ok": True, "outcome": "stopped"}
    while result["ok"]:
        try:
            newest = _last_run(launcher.get().log_dir)
            result["run"] = newest if newest != before else None
            if result["run"] is not None:
                result["printed_bytes"], result["printed_crc32"] = log.printed()
            break
        except KeyboardInterrupt as exc:
            interrupted = exc
    late = _frame("result", json.dumps(result))
    interrupted = interrupted or late
    if interrupted is not None:
        raise interrupted
    return result


def _last_run(log_dir):
    runs = log.list_runs(log_dir)
    return runs[-1][0] if runs else None


def _runs(log_dir):
    found = []
    for index, path in log.list_runs(log_dir):
        found.append({"index": index, "bytes": os.stat(path)[6]})
    return {"runs": found, "slots": log.MAX_RUNS}


def runs(log_dir=log.LOG_DIR):
    """The run logs still on the hub, oldest first, with their sizes."""
    return _call(_runs, log_dir)


def _read_run(index, offset, max_bytes, log_dir):
    max_bytes = max(1, min(max_bytes, READ_CHUNK_BYTES))
    path = log.run_path(index, log_dir)
    total = os.stat(path)[6]
    with open(path, "rb") as f:
        f.seek(offset)
        data = f.read(max_bytes)
    end = offset + len(data)
    if end < total:
        cut = data.rfind(b"\n") + 1  # hand out whole lines so stamps stay with their text
        if cut == 0:
            cut = len(data)
            while cut > 0 and (data[cut - 1] & 0xC0) == 0x80:
                cut -= 1  # never split a UTF-8 character
            if cut > 0 and data[cut - 1] >= 0xC0:
                cut -= 1
        data = data[:cut]
        end = offset + cut
    return {
        "index": index,
        "offset": offset,
        "text": data.decode(),
        "crc32": binascii.crc32(data) & 0xFFFFFFFF,  # the host checks the slice arrived intact
        "next_offset": end if end < total else None,
        "total_bytes": total,
    }


def read_run(index, offset=0, max_bytes=READ_CHUNK_BYTES, log_dir=log.LOG_DIR):
    """A slice of run `index`'s log from byte `offset`; call again at `next_offset` until it is None."""
    return _call(_read_run, index, offset, max_bytes, log_dir)


def idle(watch=None):
    """Hand the hub back to the launcher's idle loop, so the program button starts programs again.

    The host calls this last, before it disconnects; its next connection's Ctrl-C ends the loop. A
    host that stays connected passes `watch`, and sees each button run begin and end (see the top).
    """
    try:
        watcher = _Watch(watch)
    except ValueError as exc:
        return _reply({"ok": False, "type": "ValueError", "error": str(exc)})
    _reply({"ok": True, "idle": True})
    try:
        with watcher:
            launcher.get().idle(on_run_end=watcher.on_run_end if watch is not None else None)
    except KeyboardInterrupt:
        pass


def _identify(duration_ms):
    if not isinstance(duration_ms, int) or not 0 < duration_ms <= IDENTIFY_MAX_MS:
        raise ValueError("duration_ms=%r: blink for 1..%d ms" % (duration_ms, IDENTIFY_MAX_MS))
    from openbricks import bluetooth_button

    if not bluetooth_button.identify(duration_ms):
        raise OSError(
            "this hub has no status LED watcher running (its board setup failed at boot, or a user "
            "main.py replaced it): reset the hub, or look for it by name"
        )
    return {"identify_ms": duration_ms}


def identify(duration_ms=3000):
    """Blink the status LED white for `duration_ms` so a person can find this hub on the table.

    Returns at once: the LED's own timer does the blinking, so the hub stays free meanwhile."""
    return _call(_identify, duration_ms)


def reset():
    """Restart the hub as its RESET button would (after a flash, so it comes up advertising its name).

    The reply is printed first and given a moment to leave over the link: the restart cuts it.
    """
    _reply({"ok": True, "resetting": True})
    time.sleep_ms(RESET_GRACE_MS)
    machine.reset()


def paste_probe(token, padding):
    """Echo `token` and how many bytes of `padding` arrived: `openbricks paste-probe` sends calls of
    growing size through raw-paste and compares, so a command cut short shows as a wrong count (or as
    the SyntaxError of an unterminated string), never as a silent success."""

    def _probe():
        if not isinstance(token, str) or not isinstance(padding, str):
            raise ValueError("token and padding must be text")
        return {"token": token, "padding_bytes": len(padding)}

    return _call(_probe)


def record_provenance(verdict):
    """Store the flasher's verdict ("official" / "customized") for the firmware now on the hub."""

    def _record():
        openbricks.record_provenance(verdict)
        return {"firmware": openbricks.firmware_label()}

    return _call(_record)


_MAX_NAME_BYTES = 26  # what fits in a legacy BLE advertisement beside the flags


def _set_hub_name(hub_name):
    from openbricks import bluetooth

    if not isinstance(hub_name, str) or not hub_name or len(hub_name.encode()) > _MAX_NAME_BYTES:
        raise ValueError(
            "hub_name=%r: give 1..%d bytes of text (it is advertised over BLE)" % (hub_name, _MAX_NAME_BYTES)
        )
    import esp32

    nvs = esp32.NVS(bluetooth.NVS_NAMESPACE)
    nvs.set_blob(bluetooth.NVS_KEY_HUB_NAME, hub_name.encode())
    nvs.commit()
    openbricks.HUB_NAME = bluetooth.hub_name()  # read back from NVS, so the host can verify it
    return {"hub_name": openbricks.HUB_NAME}


def set_hub_name(hub_name):
    """Store the name the hub advertises (what `openbricks flash --name` sets) and read it back."""
    return _call(_set_hub_name, hub_name)


# -- servo bus: scan and re-ID through the hub ---------------------------------------------------


def _open_bus(uart_id, tx, rx, baud):
    if launcher.program_running():
        raise RuntimeError("a program is running and owns the servo bus: stop it first")
    from openbricks.drivers import st3215

    existed = st3215._SCServoBus._by_uart.get(uart_id) is not None
    return st3215._SCServoBus.for_uart(uart_id, tx, rx, baud, None), existed


def _scan(bus):
    found = []
    ping = _native.scs.PING
    for servo_id in range(_native.scs.MAX_SERVO_ID + 1):
        if bus.request(servo_id, ping, b"", 1) is not None:
            found.append(servo_id)
    return found


def _servo_scan(uart_id, tx, rx, baud):
    bus, existed = _open_bus(uart_id, tx, rx, baud)
    try:
        return {"ids": _scan(bus), "bus": bus.where()}
    finally:
        if not existed:
            bus.close()


def servo_scan(uart_id=SERVO_UART_ID, tx=SERVO_TX, rx=SERVO_RX, baud=SERVO_BAUD):
    """List the servo ids (0..253) answering on the hub's servo bus; changes nothing."""
    return _call(_servo_scan, uart_id, tx, rx, baud)


def _check_id(name, value):
    scs = _native.scs
    if not isinstance(value, int) or not 0 <= value <= scs.MAX_SERVO_ID:
        raise ValueError(
            "%s=%r: servo bus ids are 0..%d (%d is broadcast)"
            % (name, value, scs.MAX_SERVO_ID, scs.BROADCAST_ID)
        )


def _servo_set_id(new_id, old_id, uart_id, tx, rx, baud):
    _check_id("new_id", new_id)
    if old_id is not None:
        _check_id("old_id", old_id)
    bus, existed = _open_bus(uart_id, tx, rx, baud)
    try:
        ids = _scan(bus)
        if not ids:
            raise OSError(
                "no servo answers on %s: check its power and the TX/RX wiring, then scan again" % bus.where()
            )
        if old_id is None:
            if len(ids) > 1:
                raise ValueError(
                    "%d servos answer (ids %s): pass old_id= to say which one to re-ID; it is never guessed"
                    % (len(ids), ", ".join([str(i) for i in ids]))
                )
            old_id = ids[0]
        elif old_id not in ids:
            raise ValueError(
                "no servo answers at old_id=%d; the bus has ids %s"
                % (old_id, ", ".join([str(i) for i in ids]))
            )
        if new_id == old_id:
            return {"old_id": old_id, "new_id": new_id, "ids": ids, "changed": False}
        if new_id in ids:
            raise ValueError(
                "id %d is already taken by another servo on the bus: pick a free id (in use: %s)"
                % (new_id, ", ".join([str(i) for i in ids]))
            )
        scs = _native.scs
        if bus.write(old_id, scs.REG_LOCK, b"\x00") is None:
            raise OSError("servo %d did not acknowledge the EEPROM unlock; nothing was changed" % old_id)
        # The servo answers an id write from its new id (or not at all): read-back is the real check.
        bus.write(old_id, scs.REG_ID, bytes((new_id,)), 1)
        bus.write(new_id, scs.REG_LOCK, b"\x01")
        reply = bus.read(new_id, scs.REG_ID, 1)
        if reply is None or reply[1][0] != new_id:
            raise OSError(
                "servo %d did not come back as id %d after the write: scan the bus to see where it is"
                % (old_id, new_id)
            )
        after = _scan(bus)
        if old_id in after:
            raise OSError(
                "a servo still answers at id %d after the re-ID (two servos shared that id?); "
                "wire one servo at a time and retry" % old_id
            )
        return {"old_id": old_id, "new_id": new_id, "ids": after, "changed": True}
    finally:
        if not existed:
            bus.close()


def servo_set_id(new_id, old_id=None, uart_id=SERVO_UART_ID, tx=SERVO_TX, rx=SERVO_RX, baud=SERVO_BAUD):
    """Re-ID one servo on the hub's bus and verify it by read-back.

    With more than one servo answering, `old_id` is required: the hub never guesses which to change.
    """
    return _call(_servo_set_id, new_id, old_id, uart_id, tx, rx, baud)
