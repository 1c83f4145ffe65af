"""An emulated hub for the link tests: the virtual hub's REPL protocol with scripted code behind it.

The bytes are the virtual hub's (sim/virtual_hub/repl.py: friendly, raw and raw-paste REPL, flow
control, Ctrl-C / Ctrl-D, soft reboot), here over a stdin ring of the size a test picks, so a host
that sends beyond a raw-paste grant or a full ring loses bytes as on a hub (`overflow_bytes`).
What a test scripts is what runs behind them: commands run with CPython in a worker thread, so
output streams while a command runs and Ctrl-C interrupts a program's `sleep_ms`; and
`openbricks.host_calls` answers from memory (`files`, `run_logs`), with the faults a test asks for
(calls the firmware lacks, calls that fail, a smaller read slice, damaged slices).

Everything runs on the event loop's thread except the command thread, which posts back to it.
"""

from __future__ import annotations

import asyncio
import base64
import builtins
import io
import json
import threading
import traceback
import zlib
from collections.abc import Callable

from openbricks.host_protocol import FRAME_PREFIX, MAX_PROGRAM_BYTES, READ_FILE_MAX_BYTES
from openbricks_sim.virtual_hub.repl import SOFT_REBOOT, Interrupt, ReplProtocol, SoftReboot, cooked

BANNER = (
    b"MicroPython v1.27.0 on 2026-01-01; openbricks hub with ESP32S3\r\n"
    b'Type "help()" for more information.\r\n'
)
TRACEBACK_HEAD = 'Traceback (most recent call last):\n  File "<stdin>", line 1, in <module>\n'
# The hub's stdin ring is a little larger than MICROPY_REPL_STDIN_BUFFER_MAX (260 for 256): room for a
# Ctrl-D and the next raw-paste request that a host sends right after a full window.
RING_SLACK_BYTES = 4
LOG_STAMP = "1767225600000 "  # the epoch stamp every run-log line starts with


class ScriptedHub:
    def __init__(
        self,
        name: str = "RobotA",
        *,
        stdin_buffer_max: int = 256,
        raw_paste: bool = True,
        compression: tuple[str, ...] = ("zlib",),
    ):
        self.name = name
        self.compression = compression
        self.files: dict[str, bytes] = {}
        self.commands: list[str] = []
        self.runs = 0
        #: Each run's printed text by run number, as the hub's run log holds it (read_run pages it).
        self.run_logs: dict[int, str] = {}
        self.logging_run: int | None = None
        self.printed = (0, 0)  # bytes and crc32 of the running program's console output
        self.resets = 0
        #: Host calls this hub's firmware lacks (an older release): calling one raises AttributeError.
        self.missing_calls: set[str] = set()
        #: Host calls that fail on this hub, with the exception each reports.
        self.call_failures: dict[str, Exception] = {}
        #: Most bytes one read_file reply carries (the hub's cap; a test may set a smaller one).
        self.read_cap_bytes = READ_FILE_MAX_BYTES
        #: What read_file sends instead of a slice's bytes (a damaged link).
        self.corrupt_read: Callable[[bytes], bytes] = lambda data: data
        self._send: Callable[[bytes], None] = lambda data: None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._interrupt = threading.Event()
        self._staging: dict | None = None
        self.protocol = ReplProtocol(
            lambda data: self._send(data),
            banner=BANNER,
            paste_window=stdin_buffer_max // 2,
            raw_paste=raw_paste,
            stdin_ring_bytes=stdin_buffer_max + RING_SLACK_BYTES,
        )
        self.protocol.execution_done()  # powered up: boot is over and the friendly prompt waits

    # -- wiring ---------------------------------------------------------------------------------

    def attach(self, send: Callable[[bytes], None], loop: asyncio.AbstractEventLoop) -> None:
        """Where the hub's output goes (called on `loop`'s thread) and which loop runs the hub."""
        self._send = send
        self._loop = loop

    @property
    def busy(self) -> bool:
        return self.protocol.running is not None

    @property
    def overflow_bytes(self) -> int:
        return self.protocol.overrun_bytes

    def feed(self, data: bytes) -> None:
        """Bytes from the host, in order (on the loop's thread)."""
        self._handle(self.protocol.feed(data))

    def _handle(self, events) -> None:
        for event in events:
            if isinstance(event, Interrupt):
                self._interrupt.set()
            elif isinstance(event, SoftReboot):
                self._staging = None
                self._send(SOFT_REBOOT)
                self._handle(self.protocol.execution_done())
            else:
                self._execute(event.source)

    # -- executing ------------------------------------------------------------------------------

    def _execute(self, source: bytes) -> None:
        self._interrupt.clear()
        text = source.decode("utf-8", "replace")
        self.commands.append(text)
        threading.Thread(
            target=self._run_command, args=(text,), name=f"{self.name}-exec", daemon=True
        ).start()

    def _post(self, fn, *args) -> None:
        assert self._loop is not None, "attach() the hub to a loop first"
        self._loop.call_soon_threadsafe(fn, *args)

    def _stdout(self, text: str) -> None:
        self._post(self._send, cooked(text))

    def _program_print(self, text: str) -> None:
        """A running program's print: to the console, counted (bytes and crc32 as sent), and into its
        run log with a stamp per line, as the launcher tees it."""
        if self.logging_run is not None:
            log = self.run_logs[self.logging_run]
            for piece in text.splitlines(keepends=True):
                log += (LOG_STAMP if log == "" or log.endswith("\n") else "") + piece
            self.run_logs[self.logging_run] = log
            sent = cooked(text)
            self.printed = (self.printed[0] + len(sent), zlib.crc32(sent, self.printed[1]))
        self._stdout(text)

    def _run_command(self, text: str) -> None:
        error = None
        namespace = {"__name__": "__main__", "__builtins__": self._builtins()}
        try:
            exec(compile(text, "<stdin>", "exec"), namespace)  # noqa: S102 - the emulated hub runs host code
        except _HardReset:
            self._post(self._boot)
            return
        except KeyboardInterrupt:
            error = TRACEBACK_HEAD + "KeyboardInterrupt: \n"
        except BaseException as exc:  # noqa: BLE001 - every error is reported as the hub would
            error = TRACEBACK_HEAD + "".join(traceback.format_exception_only(type(exc), exc))
        self._post(self._finish, error)

    def _finish(self, error: str | None) -> None:
        self._handle(self.protocol.execution_done(error))

    def _boot(self) -> None:
        """After machine.reset(): a fresh hub in the friendly REPL, as after power-on."""
        self.resets += 1
        self._staging = None
        self.protocol.start_boot()
        self._finish(None)

    def sleep_ms(self, ms: int) -> None:
        """The hub program's sleep: Ctrl-C ends it with KeyboardInterrupt, as on the hub."""
        if self._interrupt.wait(ms / 1000):
            self._interrupt.clear()
            raise KeyboardInterrupt

    def _builtins(self) -> dict:
        hub = self
        names = dict(vars(builtins))

        def hub_print(*args, sep=" ", end="\n", file=None):
            hub._program_print(sep.join(str(a) for a in args) + end)

        def hub_import(name, globals=None, locals=None, fromlist=(), level=0):
            if name == "openbricks.host_calls":
                module = _HostCalls(hub)
                return module if fromlist else _Package(host_calls=module)
            return builtins.__import__(name, globals, locals, fromlist, level)

        def hub_open(path, mode="r"):
            if "r" not in mode or path not in hub.files:
                raise OSError(2, "ENOENT")
            data = hub.files[path]
            return io.BytesIO(data) if "b" in mode else io.StringIO(data.decode())

        names["open"] = hub_open
        names["print"] = hub_print
        names["__import__"] = hub_import
        names["sleep_ms"] = self.sleep_ms
        return names


class _HardReset(BaseException):
    """machine.reset() in a command: the chip restarts, the command never ends."""


class _Package:
    def __init__(self, **modules):
        self.__dict__.update(modules)


class _HostCalls:
    """The hub's `openbricks.host_calls` as the tests script it: one result line per call."""

    def __init__(self, hub: ScriptedHub):
        self.hub = hub
        self._tag = "-"

    def __getattribute__(self, name: str):
        if name in object.__getattribute__(self, "hub").missing_calls:
            raise AttributeError(f"'module' object has no attribute '{name}'")
        return object.__getattribute__(self, name)

    def tag(self, nonce):
        self._tag = str(nonce)

    def _frame(self, kind: str, payload: str = "") -> None:
        self.hub._stdout(f"{FRAME_PREFIX}{self._tag} {kind}" + (f" {payload}" if payload else "") + "\n")

    def _reply(self, result: dict) -> dict:
        self._frame("result", json.dumps(result))
        return result

    def _call(self, name: str, fn, *args) -> dict:
        try:
            failure = self.hub.call_failures.get(name)
            if failure is not None:
                raise failure
            result = fn(*args)
        except KeyboardInterrupt:
            raise
        except Exception as exc:  # noqa: BLE001 - the hub reports every failure as data
            return self._reply({"ok": False, "type": type(exc).__name__, "error": str(exc)})
        result["ok"] = True
        return self._reply(result)

    def info(self):
        return self._call(
            "info",
            lambda: {
                "protocol": 2,
                "firmware": "openbricks 2.7.1 (emulated)",
                "version": "2.7.1",
                "chip": "esp32s3",
                "runtime": "micropython 1.27.0",
                "accepts_mpy": True,
                "mpy_version": 6,
                "program_path": "/program.mpy",
                "max_program_bytes": MAX_PROGRAM_BYTES,
                "compression": list(self.hub.compression),
                "running": False,
                "name": self.hub.name,
            },
        )

    def set_rtc(self, epoch_ms):
        return self._call("set_rtc", lambda: {"epoch_ms": epoch_ms})

    def _inflate(self, data: bytes, compression) -> bytes:
        if compression is None:
            return data
        if compression != "zlib" or "zlib" not in self.hub.compression:
            raise ValueError(f"compression={compression!r}: this hub cannot inflate it")
        return zlib.decompress(data)

    def _commit(self, path, data, size, crc32):
        if size is not None and len(data) != size:
            raise ValueError(f"upload truncated: got {len(data)} bytes, expected {size}; stage it again")
        crc = zlib.crc32(data)
        if crc32 is not None and crc != crc32:
            raise ValueError(f"upload corrupted: crc32 {crc:08x}, expected {crc32:08x}; stage it again")
        self.hub.files[path] = data
        return {"path": path, "bytes": len(data), "crc32": crc}

    def stage(self, payload, path="/program.mpy", encoding="base64", compression=None, size=None, crc32=None):
        return self._call(
            "stage",
            lambda: self._commit(path, self._inflate(base64.b64decode(payload), compression), size, crc32),
        )

    def stage_begin(self, path="/program.mpy"):
        def _begin():
            self.hub._staging = {"path": path, "data": bytearray()}
            return {"path": path}

        return self._call("stage_begin", _begin)

    def _staged(self) -> dict:
        if self.hub._staging is None:
            raise RuntimeError("no upload in progress: call stage_begin(path) first")
        return self.hub._staging

    def stage_append(self, payload, encoding="base64"):
        def _append():
            staging = self._staged()
            staging["data"] += base64.b64decode(payload)
            return {"received": len(staging["data"])}

        return self._call("stage_append", _append)

    def stage_end(self, compression=None, size=None, crc32=None):
        def _end():
            staging = self._staged()
            self.hub._staging = None
            return self._commit(
                staging["path"], self._inflate(bytes(staging["data"]), compression), size, crc32
            )

        return self._call("stage_end", _end)

    def read_file(self, path, offset=0, size=4096):
        def _read():
            if path not in self.hub.files:
                raise OSError(f"no file {path} on the hub: check the path (names are case-sensitive)")
            whole = self.hub.files[path]
            data = whole[offset : offset + min(size, self.hub.read_cap_bytes)]
            end = offset + len(data)
            return {
                "path": path,
                "offset": offset,
                "bytes": len(data),
                "crc32": zlib.crc32(data),
                "data": base64.b64encode(self.hub.corrupt_read(data)).decode(),
                "total_bytes": len(whole),
                "next_offset": end if end < len(whole) else None,
            }

        return self._call("read_file", _read)

    def reset(self):
        self._reply({"ok": True, "resetting": True})
        raise _HardReset

    def read_run(self, index, offset=0, max_bytes=8192):
        def _read():
            text = self.hub.run_logs.get(index)
            if text is None:
                raise OSError(f"no log of run {index}")
            data = text.encode()
            piece = data[offset : offset + max_bytes]
            cut = piece.rfind(b"\n") + 1 if offset + len(piece) < len(data) else len(piece)
            piece = piece[: cut or len(piece)]
            end = offset + len(piece)
            return {
                "index": index,
                "offset": offset,
                "text": piece.decode(),
                "crc32": zlib.crc32(piece),
                "next_offset": end if end < len(data) else None,
                "total_bytes": len(data),
            }

        return self._call("read_run", _read)

    def run(self, path="/program.mpy", name=None):
        hub = self.hub
        hub.runs += 1
        hub.run_logs[hub.runs] = ""
        source = hub.files.get(path)
        if source is None:
            return self._reply({"ok": False, "type": "OSError", "error": f"no program staged at {path}"})
        namespace = {"__name__": "__main__", "__builtins__": hub._builtins()}
        self._frame("program")
        hub.logging_run = hub.runs
        hub.printed = (0, 0)
        try:
            exec(compile(source.decode(), name or path, "exec"), namespace)  # noqa: S102
        except KeyboardInterrupt:
            hub.logging_run = None
            self._reply({"ok": True, "outcome": "stopped", "run": hub.runs, **self._printed()})
            raise
        except Exception as exc:  # noqa: BLE001
            hub.logging_run = None
            hub._stdout(f"Traceback (most recent call last):\n{type(exc).__name__}: {exc}\n")
            return self._reply({"ok": True, "outcome": "error", "run": hub.runs, **self._printed()})
        hub.logging_run = None
        return self._reply({"ok": True, "outcome": "finished", "run": hub.runs, **self._printed()})

    def _printed(self) -> dict:
        return {"printed_bytes": self.hub.printed[0], "printed_crc32": self.hub.printed[1]}
