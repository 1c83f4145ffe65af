"""Run logs: every program's print output and framing lines, stamped and kept on flash.

Storage: MAX_RUNS slot files `slot_<k>.log` in the log directory, reused in place. Run N truncates and
rewrites slot N % MAX_RUNS (deleting and recreating files churns littlefs metadata until every commit
slows down). The run index lives in the file's header line, `<epoch_ms> -- run_<N> --`, so indices
keep growing across reboots without a separate counter file.

Every line starts with the UTC Unix epoch in milliseconds: the hub has no timezone, the host renders
local time, and the host sets the RTC on every connect (an unsynced hub stamps year-2000 times, which
is self-diagnosing).

Writes are asynchronous: print only appends to a RAM buffer and returns; `pump()`, called from the
launcher's timer tick, moves bytes to the file without committing. A littlefs commit costs tens of
milliseconds on the ESP32, so it is paid only at the durable points: the framing lines (`write_text`,
`note`) and the end of the run. A hard reset can therefore lose recent prints, never the framing.

Each run is capped at `max_bytes` of print output so a runaway print loop can't fill the flash; the
framing lines still fit in a small reserve after the cap, because the end of a runaway run is exactly
what its owner wants to read.

A host that stays connected (the console daemon, `watch=<nonce>`) gets each line's stamp live too, so a
line shows the same hub time as it arrives and when read back from the log: before the first line a
print starts, `@openbricks:<nonce> t <ms since the run's header stamp>` (only when the stamp changed;
a line without a frame of its own has the last one's). Relative to the header, which the run-begin
frame carries, the frame stays short on a slow radio link.
"""

import binascii
import os
import time

from openbricks.host_protocol import FRAME_PREFIX

LOG_DIR = "/openbricks_logs"
MAX_RUNS = 10
MAX_BYTES = 64 * 1024

_FRAMING_RESERVE = 1024  # bytes past the cap kept for started:/stopped:/traceback lines
_BUFFER_LIMIT = 2048  # RAM held before a print pays for its own write (the tick is starved)
_HEADER_PREFIX = "-- run_"

_active = [None]  # the session of the running program, if any
_epoch_offset_ms = [None]


def epoch_ms():
    """UTC Unix epoch milliseconds from the RTC, whichever epoch (1970 or 2000) the port counts from."""
    if _epoch_offset_ms[0] is None:
        # Ports built with a 2000 epoch report gmtime(0) as 2000-01-01.
        _epoch_offset_ms[0] = 946684800000 if time.gmtime(0)[0] == 2000 else 0
    return time.time_ns() // 1000000 + _epoch_offset_ms[0]


def _join(directory, name):
    return directory.rstrip("/") + "/" + name


def _slot_path(log_dir, slot):
    return _join(log_dir, "slot_%d.log" % slot)


def _header_index(path):
    """Run index from a slot file's header line, or None if the file is missing or not a run log."""
    try:
        with open(path, "rb") as f:
            first = f.readline(80)
    except OSError:
        return None
    text = first.decode()
    at = text.find(_HEADER_PREFIX)
    if at < 0:
        return None
    digits = text[at + len(_HEADER_PREFIX) :].split(" ", 1)[0]
    try:
        return int(digits)
    except ValueError:
        return None


def list_runs(log_dir=LOG_DIR, max_runs=MAX_RUNS):
    """[(index, path)] of the runs still on flash, oldest first."""
    runs = []
    for slot in range(max_runs):
        path = _slot_path(log_dir, slot)
        index = _header_index(path)
        if index is not None:
            runs.append((index, path))
    runs.sort()
    return runs


def run_path(index, log_dir=LOG_DIR, max_runs=MAX_RUNS):
    """Path of run `index`; OSError if that run was overwritten by a newer one or never happened."""
    path = _slot_path(log_dir, index % max_runs)
    if index < 0 or _header_index(path) != index:
        raise OSError(
            2,
            "run %d is not on the hub (only the last %d runs are kept); list them with list_runs()"
            % (index, max_runs),
        )
    return path


def read_run(index, log_dir=LOG_DIR, max_runs=MAX_RUNS):
    """Text of run `index`; OSError if it is no longer (or never was) on the hub."""
    with open(run_path(index, log_dir, max_runs), "rb") as f:
        return f.read().decode()


def _ensure_dir(path):
    try:
        os.mkdir(path)
    except OSError:
        mode = os.stat(path)[0]  # already there is fine; no such parent raises
        if not mode & 0x4000:  # S_IFDIR: a file stored at the folder's name would fail every run
            raise OSError(
                "%s is a file, but the hub keeps its run logs in a folder of that name: remove "
                "the file (mpremote rm %s)" % (path, path)
            ) from None


class _LogSession:
    """One run's log file; use through `session()` as a context manager."""

    def __init__(self, log_dir=LOG_DIR, max_bytes=MAX_BYTES, max_runs=MAX_RUNS):
        _ensure_dir(log_dir)
        runs = list_runs(log_dir, max_runs)
        self.index = runs[-1][0] + 1 if runs else 0
        self.path = _slot_path(log_dir, self.index % max_runs)
        self.max_bytes = max_bytes
        self.worst_write_ms = 0
        self.dropped_bytes = 0
        self._file = open(self.path, "wb")  # truncates the slot in place
        self._pending = []
        self._pending_bytes = 0
        self._file_bytes = 0
        self._line_open = False  # the last print ended without a newline
        self._capped = False
        self._failed = None  # the OSError that stopped file writes, if any
        #: The header line's stamp: with the slot, what a host matches a live run to its log by.
        self.started_ms = epoch_ms()
        self.write_text("%s%d --" % (_HEADER_PREFIX, self.index), stamp_ms=self.started_ms)

    # -- what goes in ------------------------------------------------------------------------

    def _stamp(self, text, stamp_ms=None):
        """`text` with the epoch stamp in front of every line that starts in it."""
        stamp = "%d " % (epoch_ms() if stamp_ms is None else stamp_ms)
        out = []
        start = 0
        while start < len(text):
            end = text.find("\n", start)
            end = len(text) if end < 0 else end + 1
            if not self._line_open:
                out.append(stamp)
            out.append(text[start:end])
            self._line_open = text[end - 1] != "\n"
            start = end
        return "".join(out).encode()

    def _queue(self, data):
        self._pending.append(data)
        self._pending_bytes += len(data)
        if self._pending_bytes >= _BUFFER_LIMIT:
            self.pump()

    def write(self, text, stamp_ms=None):
        """Program output (from print): buffered, dropped from the file once the run passes the cap."""
        if not text or self._file is None:
            return
        data = self._stamp(text, stamp_ms)
        used = self._file_bytes + self._pending_bytes
        if self._capped or used + len(data) > self.max_bytes:
            self.dropped_bytes += len(data)
            if not self._capped:
                self._capped = True
                self.write_text(
                    "log capped at %d bytes: further output is dropped from this file (the console "
                    "still shows it)" % self.max_bytes
                )
            return
        self._queue(data)

    def write_text(self, text, commit=True, stamp_ms=None):
        """A framing line (or lines, e.g. a traceback): stamped, always kept, committed now (or, with
        commit=False, together with the next commit)."""
        if self._file is None:
            return
        if self._line_open:
            self._queue(b"\n")
            self._line_open = False
        if not text.endswith("\n"):
            text += "\n"
        data = self._stamp(text, stamp_ms)
        used = self._file_bytes + self._pending_bytes
        if used + len(data) > self.max_bytes + _FRAMING_RESERVE:
            self.dropped_bytes += len(data)
            return
        self._queue(data)
        if commit:
            self.flush()

    # -- what goes out -----------------------------------------------------------------------

    def _timed(self, action, data=None):
        started = time.ticks_ms()
        try:
            if data is None:
                action()
            else:
                action(data)
        except OSError as exc:
            # A full or failing filesystem must not take the program (or the tick) down with it.
            self._failed = exc
            self._pending = []
            self._pending_bytes = 0
            return
        spent = time.ticks_diff(time.ticks_ms(), started)
        if spent > self.worst_write_ms:
            self.worst_write_ms = spent

    def pump(self):
        """Move buffered bytes to the file (no commit). Never raises."""
        if not self._pending or self._file is None or self._failed is not None:
            return
        data = b"".join(self._pending)
        self._pending = []
        self._pending_bytes = 0
        self._file_bytes += len(data)
        self._timed(self._file.write, data)

    def flush(self):
        """Move buffered bytes to the file and commit them to flash. Never raises."""
        self.pump()
        if self._file is not None and self._failed is None:
            self._timed(self._file.flush)

    def close(self):
        if self._file is None:
            return
        if self._line_open:
            self._queue(b"\n")
            self._line_open = False
        self.flush()
        try:
            self._file.close()
        except OSError:
            pass
        self._file = None

    def __enter__(self):
        _active[0] = self
        return self

    def __exit__(self, exc_type, exc, tb):
        if _active[0] is self:
            _active[0] = None
        self.close()
        return False


def session(log_dir=LOG_DIR, max_bytes=MAX_BYTES, max_runs=MAX_RUNS):
    """A fresh run log; `with log.session() as s:` makes it the active one for print and note."""
    return _LogSession(log_dir, max_bytes, max_runs)


def active():
    """The active session, or None when no program is running."""
    return _active[0]


def write(text):
    """Program output into the active run's log (no-op when no program runs)."""
    current = _active[0]
    if current is not None:
        current.write(text)


def write_text(text):
    """Framing text (one or more lines) into the active run's log, committed now."""
    current = _active[0]
    if current is not None:
        current.write_text(text)


def note(text, commit=True):
    """One stamped line in the active run's log file only (the console is not touched).

    Committed at once unless commit=False, for a caller with something more urgent to do first
    (the stop button halts the motors before paying for a flash commit).
    """
    current = _active[0]
    if current is not None:
        current.write_text(text, commit)


def pump():
    """Drain buffered output to the file; called from the launcher's timer tick. Never raises."""
    current = _active[0]
    if current is not None:
        current.pump()


def flush():
    """Commit the active run's output now (the stop button, or before anything that may reset)."""
    current = _active[0]
    if current is not None:
        current.flush()


def worst_write_ms():
    """Slowest single file write or commit of the active run, in ms (0 when none)."""
    current = _active[0]
    return 0 if current is None else current.worst_write_ms


_printed = [0, 0]  # bytes and crc32 of what the running program printed, as the console sends it
_stamp_tag = [None]  # the watching host's nonce: line stamps go to the console too (see the top)
_console = [False, None]  # the console's line is open (no newline yet); the last stamp frame's ms


def reset_printed():
    """Start counting a new run's console output (the launcher, as a run starts)."""
    _printed[0] = 0
    _printed[1] = 0
    _console[0] = False
    _console[1] = None


def stamp_console(nonce):
    """Send line stamps to the console as frames tagged `nonce` while a run is on (None: stop)."""
    _stamp_tag[0] = nonce


def _console_text(text, stamp_ms, started_ms):
    """`text` as the console gets it: a stamp frame before the first line it starts, if that line's
    stamp differs from the last one sent. A frame never lands inside a line the console has open."""
    if _console[0]:
        newline = text.find("\n")
        at = -1 if newline < 0 else newline + 1
    else:
        at = 0
    if text:
        _console[0] = text[-1] != "\n"
    delta = stamp_ms - started_ms
    if at < 0 or at >= len(text) or delta == _console[1]:
        return text
    _console[1] = delta
    return text[:at] + FRAME_PREFIX + _stamp_tag[0] + " t " + str(delta) + "\n" + text[at:]


def printed():
    """(bytes, crc32) of the run's console output so far, as it went out (every newline as CR LF):
    the host checks what reached it against this, and reads the run log when they differ."""
    return _printed[0], _printed[1]


def count_printed(text):
    data = text.replace("\n", "\r\n").encode()
    _printed[0] += len(data)
    _printed[1] = binascii.crc32(data, _printed[1]) & 0xFFFFFFFF


def tee_print(*args, **kwargs):
    """print() that also copies its text into the active run's log, and counts it (printed()).

    The launcher installs it for the program's duration; teeing at print is what MicroPython allows
    on every port (sys.stdout is not rebindable everywhere).
    """
    sep = kwargs.get("sep")
    end = kwargs.get("end")
    text = (" " if sep is None else sep).join([str(a) for a in args]) + ("\n" if end is None else end)
    current = _active[0]
    if current is None or _stamp_tag[0] is None or kwargs.get("file") is not None:
        console_print(*args, **kwargs)
        count_printed(text)
        if current is not None:
            current.write(text)
        return
    stamp = epoch_ms()
    shown = _console_text(text, stamp, current.started_ms)
    console_print(shown, end="")
    count_printed(shown)
    current.write(text, stamp)


def print_framing(text):
    """Text for the console that the log keeps as a framing line (a traceback): one stamp for both."""
    current = _active[0]
    stamp = epoch_ms()
    shown = text
    if current is not None and _stamp_tag[0] is not None:
        shown = _console_text(text, stamp, current.started_ms)
    console_print(shown, end="")
    count_printed(shown)
    if current is not None:
        current.write_text(text, stamp_ms=stamp)


console_print = print  # the interpreter's own print, kept before anyone tees it
