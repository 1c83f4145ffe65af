"""MicroPython's REPL protocol as a pure state machine over bytes: what a hub says back to each byte.

    repl = ReplProtocol(write=port.write, banner="...")
    for event in repl.feed(data):      # bytes from the host
        ...                            # Execute / SoftReboot / Interrupt, for the executor
    repl.execution_done(error_text)    # the executor finished: framing, then the next prompt

It follows pyexec.c and readline.c of MicroPython 1.27 byte for byte where a host can tell the
difference (mpremote, the openbricks host client and paste-probe all parse these bytes):

- friendly REPL: a banner, `>>> `, echo, `... ` continuation lines, Ctrl-E paste mode;
- Ctrl-A enters the raw REPL (`raw REPL; CTRL-B to exit\\r\\n>`), Ctrl-B leaves it;
- raw REPL: source, then Ctrl-D: `OK`, the program's stdout, `\\x04`, the traceback, `\\x04`, `>`;
  Ctrl-D on an empty line: `OK\\r\\n` and a soft reboot; Ctrl-C clears the line;
- raw-paste (`\\x05A\\x01`): `R\\x01`, the window as 16-bit little-endian, `\\x01` (a second window is
  free), then one `\\x01` each time a window of data has been consumed; the host's `\\x04` ends the
  data and is answered with `\\x04`, and the output follows as in raw mode. `\\x05` with any other
  letter, or on a build without raw-paste, gets `R\\x00` (unsupported). A host that sends more than
  it was granted overflows a real hub's stdin ring buffer: the excess is dropped here too (and
  counted), so the bug shows. A grant counts from the next read of the link on: bytes that arrived
  together with the bytes that earned it were sent before the host could have seen it. Only the
  first two windows, which the empty stdin ring holds, are for bytes already on their way: those
  that waited in the ring while code ran and, where the ring's size is given, those a host sent
  along with its request (one that knows the window from an earlier grant may);
- while code runs, Ctrl-C interrupts it and every other byte waits as stdin; what the code did not
  read is read by the REPL after it ends, as on the hub, where those bytes sit in the UART buffer
  (given its size, bytes beyond it are dropped and counted, as that ring would lose them).

Nothing here does IO or runs code; the caller owns threads and locking.
"""

import codeop
import struct
from dataclasses import dataclass

CTRL_A = 0x01  # raw REPL
CTRL_B = 0x02  # friendly REPL
CTRL_C = 0x03  # interrupt / cancel
CTRL_D = 0x04  # end of input / soft reboot
CTRL_E = 0x05  # paste mode (friendly), raw-paste request prefix (raw)
BACKSPACE = (0x08, 0x7F)
ESC = 0x1B
_ESC_START = 1  # ESC seen
_ESC_BODY = 2  # ESC [ (or ESC O) seen: parameters until a final byte 0x40..0x7E

RAW_BANNER = b"raw REPL; CTRL-B to exit\r\n"
PASTE_BANNER = b"\r\npaste mode; Ctrl-C to cancel, Ctrl-D to finish\r\n=== "
SOFT_REBOOT = b"MPY: soft reboot\r\n"
PROMPT = b">>> "
CONTINUATION = b"... "
DEFAULT_PASTE_WINDOW = 2048  # half the firmware boards' MICROPY_REPL_STDIN_BUFFER_MAX (4096)

# What started the code now running: it decides the framing of its output.
RAW = "raw"  # raw REPL, source sent before Ctrl-D
PASTE = "paste"  # raw-paste mode
FRIENDLY = "friendly"  # a line (or block) typed at `>>> `: expression results are printed
FRIENDLY_PASTE = "friendly-paste"  # Ctrl-E paste mode: a whole file of source
BOOT = "boot"  # boot.py / main.py after a reset


@dataclass(frozen=True)
class Execute:
    """Run `source` (bytes) in the REPL's namespace. `kind` is RAW, PASTE, FRIENDLY or FRIENDLY_PASTE;
    FRIENDLY code compiles in "single" mode (expression values are printed), the others as files."""

    source: bytes
    kind: str


@dataclass(frozen=True)
class SoftReboot:
    """Ctrl-D at an empty prompt: the hub resets its Python state, then runs boot (and main in the
    friendly REPL). The executor answers with execution_done() when that is over."""


@dataclass(frozen=True)
class Interrupt:
    """Ctrl-C while code runs: raise KeyboardInterrupt in it."""


def _needs_more_input(source):
    """True while a friendly-REPL entry (lines, each ending in a newline) is an unfinished compound
    statement or bracket."""
    text = source.decode("utf-8", "replace")
    lines = text.split("\n")[:-1]
    if len(lines) > 1 and not lines[-1].strip():
        return False  # an empty line ends a block, as at the MicroPython prompt
    try:
        return codeop.compile_command(text[:-1], "<stdin>", "single") is None
    except (SyntaxError, OverflowError, ValueError):
        return False  # let the executor report it


class ReplProtocol:
    """The hub side of the REPL wire protocol; `write(bytes)` sends to the host."""

    def __init__(
        self, write, banner=b"", paste_window=DEFAULT_PASTE_WINDOW, raw_paste=True, stdin_ring_bytes=None
    ):
        if not 1 <= paste_window <= 0xFFFF:
            raise ValueError(f"paste_window={paste_window}: the window is a 16-bit byte count, 1..65535")
        self._write = write
        self.banner = banner if isinstance(banner, bytes) else banner.encode()
        self.paste_window = paste_window
        self.raw_paste = raw_paste  # MICROPY_REPL_RAW_PASTE of the firmware build
        self.stdin_ring_bytes = stdin_ring_bytes  # what waits for running code at most (None: no limit)
        # Raw-paste bytes the ring holds beyond the two windows a paste request grants.
        self._ring_slack = 0 if stdin_ring_bytes is None else max(0, stdin_ring_bytes - 2 * paste_window)
        self.raw_mode = False
        self.overrun_bytes = 0  # bytes a host sent beyond its raw-paste window or the stdin ring (dropped)
        self._line = bytearray()  # raw REPL line / friendly current line
        self._block = bytearray()  # friendly: completed lines of an unfinished compound statement
        self._paste = None  # bytearray while in friendly paste mode
        self._raw_paste = None  # bytearray while receiving raw-paste data
        self._credit = 0  # raw-paste bytes the host may still send
        self._grant_in_flight = 0  # granted during the current feed(): usable from the next one
        self._replaying = False  # feeding what waited in the stdin ring while code ran
        self._since_ack = 0  # raw-paste bytes consumed since the last window grant
        self._escape = 0  # friendly: where we are in an escape sequence being swallowed
        self._after_cr = False
        self._running = BOOT  # hubs power up running boot.py/main.py
        self.stdin = bytearray()  # bytes received while code runs (its sys.stdin)
        self.interrupt_char = CTRL_C  # micropython.kbd_intr(): -1 while code reads binary stdin

    # -- state ----------------------------------------------------------------------------------

    @property
    def running(self):
        """What started the code now running (RAW, PASTE, FRIENDLY, FRIENDLY_PASTE, BOOT) or None."""
        return self._running

    @property
    def receiving_paste(self):
        return self._raw_paste is not None

    def take_stdin(self, n=-1):
        """Up to `n` bytes (all if n < 0) the host sent to the running code."""
        n = len(self.stdin) if n < 0 else min(n, len(self.stdin))
        data = bytes(self.stdin[:n])
        del self.stdin[:n]
        return data

    # -- from the host --------------------------------------------------------------------------

    def feed(self, data):
        """Process bytes from the host; returns the events for the executor, in order."""
        events = []
        self._credit += self._grant_in_flight
        self._grant_in_flight = 0
        for byte in data:
            if self._running is not None:
                if byte == self.interrupt_char:
                    events.append(Interrupt())
                elif self.stdin_ring_bytes is None or len(self.stdin) < self.stdin_ring_bytes:
                    self.stdin.append(byte)
                else:
                    self.overrun_bytes += 1  # the ring is full: a real hub loses it
                continue
            event = self._byte(byte)
            if event is not None:
                events.append(event)
        return events

    def _byte(self, c):
        if self._raw_paste is not None:
            return self._raw_paste_byte(c)
        if self.raw_mode:
            return self._raw_byte(c)
        if self._paste is not None:
            return self._friendly_paste_byte(c)
        return self._friendly_byte(c)

    # -- raw REPL -------------------------------------------------------------------------------

    def _raw_byte(self, c):
        line = self._line
        if c == CTRL_A:
            if len(line) == 2 and line[0] == CTRL_E:
                command = line[1]
                line.clear()
                if command != ord("A") or not self.raw_paste:
                    self._write(b"R\x00>")
                    return None
                return self._start_raw_paste()
            line.clear()
            self._write(RAW_BANNER + b">")
        elif c == CTRL_B:
            line.clear()
            self.raw_mode = False
            self._write(b"\r\n" + self.banner + PROMPT)
        elif c == CTRL_C:
            line.clear()
        elif c == CTRL_D:
            source = bytes(line)
            line.clear()
            if not source:
                self._write(b"OK\r\n")
                self._running = BOOT
                return SoftReboot()
            self._write(b"OK")
            self._running = RAW
            return Execute(source, RAW)
        else:
            line.append(c)
        return None

    def _start_raw_paste(self):
        window = self.paste_window
        # The window size implicitly frees one window; the trailing 0x01 frees a second one.
        self._write(b"R\x01" + struct.pack("<H", window) + b"\x01")
        self._raw_paste = bytearray()
        held = self._replaying or self.stdin_ring_bytes is not None
        self._credit = 2 * window if held else 0
        self._grant_in_flight = 0 if held else 2 * window
        self._since_ack = 0
        return None

    def _raw_paste_byte(self, c):
        if c in (CTRL_C, CTRL_D):
            source = bytes(self._raw_paste)
            self._raw_paste = None
            self._write(b"\x04")  # end of data acknowledged
            if c == CTRL_C:
                # The reader raises KeyboardInterrupt before anything compiled: empty stdout, the
                # exception, and back to the raw prompt.
                self._write(b"\x04KeyboardInterrupt: \r\n\x04>")
                return None
            self._running = PASTE
            return Execute(source, PASTE)
        if self._credit <= -self._ring_slack:
            self.overrun_bytes += 1  # a real hub's stdin ring buffer would have lost it
            return None
        self._credit -= 1
        self._raw_paste.append(c)
        self._since_ack += 1
        if self._since_ack == self.paste_window:
            self._since_ack = 0
            self._grant_in_flight += self.paste_window
            self._write(b"\x01")
        return None

    # -- friendly REPL --------------------------------------------------------------------------

    def _friendly_byte(self, c):
        if self._escape:
            # Arrow keys and friends (ESC [ A, ESC [ 3 ~, ESC O H): there is no history or cursor
            # movement here, so the whole sequence is swallowed.
            if self._escape == _ESC_START and c in (ord("["), ord("O")):
                self._escape = _ESC_BODY
            elif self._escape == _ESC_BODY and not 0x40 <= c <= 0x7E:
                pass  # parameter bytes (digits, ';') until the final byte
            else:
                self._escape = 0
            return None
        after_cr, self._after_cr = self._after_cr, False
        line = self._line
        if c == CTRL_A:
            self._reset_entry()
            self.raw_mode = True
            self._write(b"\r\n" + RAW_BANNER + b">")
        elif c == CTRL_B:
            self._reset_entry()
            self._write(b"\r\n" + self.banner + PROMPT)
        elif c == CTRL_C:
            self._reset_entry()
            self._write(b"\r\n" + PROMPT)
        elif c == CTRL_D:
            if line or self._block:
                if not line and self._block:  # ends a compound statement, as an empty line would
                    return self._submit_block()
                return None
            self._write(b"\r\n")
            self._running = BOOT
            return SoftReboot()
        elif c == CTRL_E:
            self._reset_entry()
            self._paste = bytearray()
            self._write(PASTE_BANNER)
        elif c == ord("\r") or c == ord("\n"):
            if c == ord("\n") and after_cr:
                return None
            self._after_cr = c == ord("\r")
            self._write(b"\r\n")
            return self._end_of_line()
        elif c in BACKSPACE:
            if line:
                del line[-1]
                self._write(b"\x08 \x08")
        elif c == ESC:
            self._escape = _ESC_START
        elif c == ord("\t"):
            line.extend(b"    ")
            self._write(b"    ")
        elif c >= 0x20:
            line.append(c)
            self._write(bytes((c,)))
        return None

    def _end_of_line(self):
        self._block.extend(self._line)
        self._block.append(ord("\n"))
        self._line.clear()
        if not self._block.strip():
            self._block.clear()
            self._write(PROMPT)
            return None
        if _needs_more_input(bytes(self._block)):
            self._write(CONTINUATION)
            return None
        return self._submit_block()

    def _submit_block(self):
        source = bytes(self._block)
        self._block.clear()
        self._running = FRIENDLY
        return Execute(source, FRIENDLY)

    def _reset_entry(self):
        self._line.clear()
        self._block.clear()

    def _friendly_paste_byte(self, c):
        if c == CTRL_C:
            self._paste = None
            self._write(b"\r\n" + PROMPT)
        elif c == CTRL_D:
            source = bytes(self._paste)
            self._paste = None
            self._write(b"\r\n")
            self._running = FRIENDLY_PASTE
            return Execute(source, FRIENDLY_PASTE)
        elif c == ord("\r"):
            self._paste.append(ord("\n"))
            self._write(b"\r\n=== ")
        elif c != ord("\n"):
            self._paste.append(c)
            self._write(bytes((c,)))
        return None

    # -- from the executor ----------------------------------------------------------------------

    def start_boot(self):
        """A hard reset (power-up, machine.reset()): the friendly REPL, boot and main run first."""
        self.raw_mode = False
        self._reset_entry()
        self._paste = None
        self._raw_paste = None
        self.stdin.clear()  # a reset loses what sat in the UART buffer
        self._running = BOOT

    def execution_done(self, error_text=None):
        """The running code ended (`error_text`: its traceback, or None). Writes the framing and the
        next prompt, then processes the input that arrived meanwhile; returns the events it makes."""
        kind = self._running
        if kind is None:
            raise RuntimeError("execution_done() without code running")
        error = cooked(error_text)
        self.interrupt_char = CTRL_C  # as pyexec re-arms Ctrl-C for the next code
        if kind in (RAW, PASTE):
            self._write(b"\x04" + error + b"\x04>")
        elif kind == BOOT:
            self._write(error + (RAW_BANNER + b">" if self.raw_mode else self.banner + PROMPT))
        else:
            self._write(error + PROMPT)
        self._running = None
        pending = bytes(self.stdin)
        self.stdin.clear()
        self._replaying = True
        try:
            return self.feed(pending)
        finally:
            self._replaying = False


def cooked(text):
    """Console text as the hub sends it: UTF-8 with every newline as CR LF (MicroPython's cooked
    stdout)."""
    if not text:
        return b""
    return text.replace("\r\n", "\n").replace("\n", "\r\n").encode("utf-8", "replace")
