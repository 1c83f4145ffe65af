"""The bad-input catalogue: every command of the `openbricks` CLI fed what people really type wrong.

Each case runs the real CLI in its own process, against a real virtual hub where a hub is needed,
and checks what the person at the terminal sees: the exit status the CLI documents (2 a wrong
argument, 1 a failure; docs/cli.md, server/errors.py), the words that say what is wrong and how
to fix it, and that nothing of the machinery leaks: no traceback, no internal exception names, no
bare errno codes. A user's own program raising is the one place a traceback belongs; those cases
say so.
"""

from __future__ import annotations

import os
import re
import time
from dataclasses import dataclass

import pytest

from .conftest import cli

pytestmark = pytest.mark.e2e

USAGE, FAILED = 2, 1
HUB = "RobotA"
OVERSIZED_BYTES = 300_000  # above the 256 KB a hub takes

# What a person must never be shown: the CLI's insides.
_TRACEBACK = re.compile(r"Traceback \(most recent call last\)|^\s+File \".*\", line \d+, in ", re.MULTILINE)
_ERRNO = re.compile(r"\[Errno|\b(ENOENT|ENOTDIR|EISDIR|EACCES|ENOSPC|EEXIST|EINVAL|EIO|ENODEV)\b")
_EXCEPTION_NAME = re.compile(r"\b[A-Z]\w*(?:Error|Exception|Warning)\b")
# Exception names a user meets in their own program's terms: Python's syntax errors of their code,
# and what their program raised on the hub.
_USER_FACING = {"SyntaxError", "IndentationError", "TabError", "MemoryError"}


@dataclass(frozen=True)
class Case:
    id: str
    argv: tuple[str, ...]
    status: int
    words: tuple[str, ...]
    program_error: bool = False  # the user's program raised: its own traceback is the point
    answer_within_s: float | None = None  # refused before any port or hub is touched
    unset: tuple[str, ...] = ()  # environment variables the person's session lacks


def case(id_, argv, status, *words, **options):
    """`argv` as a string splits on spaces; a tuple keeps arguments that are empty or have spaces."""
    argv = tuple(argv.split()) if isinstance(argv, str) else argv
    return pytest.param(Case(id_, argv, status, words, **options), id=id_)


CASES = [
    # -- the command itself ------------------------------------------------------------------------
    case("unknown-command", "bogus", USAGE, "invalid choice: 'bogus'", "run"),
    case("unknown-option", "--nope", USAGE, "unrecognized arguments: --nope"),
    # -- run: arguments --------------------------------------------------------------------------
    case("run-without-name", "run {f}/ok.py", USAGE, "required: -n/--name"),
    case("run-without-program", "run -n {hub}", USAGE, "give a SCRIPT to run, or code with -c"),
    case(
        "run-script-and-code", "run -n {hub} -c pass {f}/ok.py", USAGE, "either SCRIPT or -c CODE, not both"
    ),
    case("run-empty-hub-name", ("run", "-n", "", "-c", "pass"), USAGE, "hub name is empty", "-n RobotA"),
    case(
        "run-zero-scan-timeout", "run -n {hub} --scan-timeout 0 -c pass", USAGE, "positive number of seconds"
    ),
    case(
        "run-nan-scan-timeout", "run -n {hub} --scan-timeout nan -c pass", USAGE, "positive number of seconds"
    ),
    case(
        "run-word-scan-timeout", "run -n {hub} --scan-timeout soon -c pass", USAGE, "'soon' is not a number"
    ),
    case("run-code-without-value", "run -n {hub} -c", USAGE, "-c/--code: expected one argument"),
    # -- run: the program file -------------------------------------------------------------------
    case(
        "run-missing-file",
        "run -n {hub} {f}/missing.py",
        FAILED,
        "missing.py: no such file",
        "check the path",
    ),
    case(
        "run-folder", "run -n {hub} {f}/folder.py", FAILED, "folder.py is a folder", "give the program's file"
    ),
    case(
        "run-binary-file",
        "run -n {hub} {f}/picture.py",
        FAILED,
        "line 1: byte 0x89 is not UTF-8",
        "UTF-8 encoding",
    ),
    case(
        "run-latin-1-file", "run -n {hub} {f}/latin1.py", FAILED, "latin1.py, line 3: byte 0xe9 is not UTF-8"
    ),
    case("run-nul-byte", "run -n {hub} {f}/nul.py", FAILED, "nul.py, line 2: a NUL byte", "binary file"),
    case(
        "run-oversized",
        "run -n {hub} {f}/big.py",
        FAILED,
        f"is {OVERSIZED_BYTES} bytes",
        "up to 262144 bytes",
    ),
    case(
        "run-unclosed-bracket",
        "run -n {hub} {f}/bracket.py",
        FAILED,
        "bracket.py:2: SyntaxError: '(' was never closed\n    2 | x = (1,\n      |     ^",
    ),
    case(
        "run-code-syntax-error",  # the right line (not the one after the end), quoted, with a caret
        ("run", "-n", HUB, "-c", "print(1"),
        FAILED,
        "<code>:1: SyntaxError: '(' was never closed\n    1 | print(1\n      |      ^",
    ),
    case(
        "run-indentation",
        "run -n {hub} {f}/indent.py",
        FAILED,
        "indent.py:2: IndentationError: unexpected indent",
    ),
    case(
        "run-open-string",
        "run -n {hub} {f}/open_string.py",
        FAILED,
        "open_string.py:1: SyntaxError: unterminated string",
    ),
    case(
        "run-desktop-only-syntax",
        "run -n {hub} {f}/match.py",
        FAILED,
        "match.py:1: SyntaxError",
        "valid desktop Python, but MicroPython does not support it",
        "1 | match command:",
    ),
    # -- run: the hub ----------------------------------------------------------------------------
    case("run-unknown-hub", "run -n Nope --scan-timeout 0.5 -c pass", FAILED, "no hub named 'Nope'", HUB),
    case(
        "run-out-of-memory",
        "run -n {hub} {f}/memory.py",
        FAILED,
        "MemoryError",
        "the program ran out of memory",
        "gc.collect()",
        "the program ended with an error",
        program_error=True,
    ),
    # -- upload ----------------------------------------------------------------------------------
    case("upload-without-program", "upload -n {hub}", USAGE, "required: SCRIPT"),
    case("upload-syntax-error", "upload -n {hub} {f}/bracket.py", FAILED, "bracket.py:2: SyntaxError"),
    case("upload-missing-file", "upload -n {hub} {f}/missing.py", FAILED, "missing.py: no such file"),
    case(
        "upload-relative-path", "upload -n {hub} --path tools.py {f}/ok.py", USAGE, "absolute hub file path"
    ),
    case("upload-folder-path", "upload -n {hub} --path /lib/ {f}/ok.py", USAGE, "absolute hub file path"),
    case(
        "upload-dotdot-path",
        "upload -n {hub} --path /../etc/x {f}/ok.py",
        USAGE,
        "'..' parts are not allowed",
    ),
    case(
        "upload-empty-part-path", "upload -n {hub} --path /lib//x.py {f}/ok.py", USAGE, "empty, '.' and '..'"
    ),
    case("upload-verbatim-missing", "upload -n {hub} --path /x.txt {f}/missing.py", FAILED, "no such file"),
    case("upload-verbatim-folder", "upload -n {hub} --path /x.txt {f}/folder.py", FAILED, "is a folder"),
    case(
        "upload-verbatim-oversized",
        "upload -n {hub} --path /x.txt {f}/big.py",
        FAILED,
        f"is {OVERSIZED_BYTES} bytes",
        "up to 262144 bytes",
    ),
    case(
        "upload-into-missing-folder",
        "upload -n {hub} --path /nodir/x.py {f}/ok.py",
        FAILED,
        "could not store /nodir/x.py",
        "there is no folder /nodir on the hub",
    ),
    case(
        "upload-onto-the-run-logs",  # a file there would fail every later run
        "upload -n {hub} --path /openbricks_logs {f}/ok.py",
        USAGE,
        "the hub keeps its run logs there",
    ),
    case(
        "upload-into-the-run-logs",
        "upload -n {hub} --path /openbricks_logs/slot_0.log {f}/ok.py",
        USAGE,
        "the hub keeps its run logs there",
    ),
    case(
        "upload-under-a-file",
        "upload -n {hub} --path /program.py/x.py {f}/ok.py",
        FAILED,
        "part of /program.py is a file on the hub, not a folder",
    ),
    # -- stop ------------------------------------------------------------------------------------
    case("stop-without-name", "stop", USAGE, "required: -n/--name"),
    case("stop-extra-argument", "stop -n {hub} now", USAGE, "unrecognized arguments: now"),
    case("stop-unknown-hub", "stop -n Nope --scan-timeout 0.5", FAILED, "no hub named 'Nope'", HUB),
    # -- log -------------------------------------------------------------------------------------
    case(
        "log-run-that-never-was",
        "log -n {hub} --run 99",
        FAILED,
        "has no run 99: no such run exists yet",
        "the newest is run ",
        "runs you can show: ",
    ),
    case(
        "log-negative-run",
        "log -n {hub} --run -1",
        USAGE,
        "there is no run -1: runs are numbered from 0",
        "--list",
    ),
    case(
        "log-overwritten-run",
        "log -n {hub} --run 0",
        FAILED,
        "run 0 of RobotA was overwritten",
        "last 10 runs",
        "runs you can show: ",
    ),
    case("log-word-run", "log -n {hub} --run last", USAGE, "'last' is not a run number"),
    case("log-unknown-hub", "log -n Nope --scan-timeout 0.5", FAILED, "no hub named 'Nope'"),
    case(
        "log-without-a-runtime-dir",  # a container or `su` session: no XDG_RUNTIME_DIR, no warning either
        "log -n Nope --scan-timeout 0.5",
        FAILED,
        "no hub",
        "'Nope'",
        unset=("XDG_RUNTIME_DIR", "OPENBRICKS_RUNTIME_DIR"),
    ),
    # -- list ------------------------------------------------------------------------------------
    case("list-negative-timeout", "list --timeout -3", USAGE, "positive number of seconds"),
    case("list-zero-timeout", "list --timeout 0", USAGE, "positive number of seconds"),
    case("list-extra-argument", "list RobotA", USAGE, "unrecognized arguments: RobotA"),
    # -- servo-id --------------------------------------------------------------------------------
    case("servo-id-nothing-to-do", "servo-id", USAGE, "give the NEW_ID to assign, or --scan"),
    case("servo-id-too-high", "servo-id 300", USAGE, "new id 300: servo bus ids are 0..253"),
    case("servo-id-negative", "servo-id -1", USAGE, "new id -1: servo bus ids are 0..253"),
    case("servo-id-broadcast", "servo-id 254", USAGE, "254 is the broadcast id"),
    case(
        "servo-id-old-id-too-high", "servo-id 5 --old-id 999", USAGE, "--old-id 999: servo bus ids are 0..253"
    ),
    case("servo-id-hub-bad-id", "servo-id -n {hub} 300", USAGE, "servo bus ids are 0..253"),
    case("servo-id-word", "servo-id five", USAGE, "invalid int value: 'five'"),
    case("servo-id-port-and-hub", "servo-id 5 -p /dev/ttyUSB0 -n {hub}", USAGE, "not allowed with argument"),
    case(
        "servo-id-missing-port",
        "servo-id 5 -p /dev/no-such-adapter",
        FAILED,
        "cannot open /dev/no-such-adapter: there is no such port",
    ),
    case("servo-id-negative-timeout", "servo-id --scan --timeout -1", USAGE, "positive number of seconds"),
    case("servo-id-zero-baudrate", "servo-id --scan --baudrate 0", USAGE, "whole number above 0"),
    case("servo-id-negative-pin", "servo-id --scan -n {hub} --tx -3", USAGE, "GPIO numbers start at 0"),
    case(
        "servo-id-missing-pin",
        "servo-id --scan -n {hub} --tx 99",
        FAILED,
        "GPIO 99 doesn't exist on the ESP32-S3",
    ),
    case("servo-id-unknown-hub", "servo-id 5 -n Nope --scan-timeout 0.5", FAILED, "no hub named 'Nope'"),
    # -- paste-probe -----------------------------------------------------------------------------
    case("paste-probe-tiny-max", "paste-probe -n {hub} --max 10", USAGE, "the probe starts at 256 bytes"),
    case("paste-probe-zero-timeout", "paste-probe -n {hub} --timeout 0", USAGE, "positive number of seconds"),
    case("paste-probe-without-name", "paste-probe", USAGE, "required: -n/--name"),
    # -- flash -----------------------------------------------------------------------------------
    case("flash-without-name", "flash", USAGE, "required: --name"),
    case("flash-empty-name", ("flash", "--name", ""), USAGE, "--name is empty"),
    case("flash-name-with-spaces", ("flash", "--name", " RobotA"), USAGE, "starts or ends with spaces"),
    case("flash-long-name", "flash --name " + "R" * 40, USAGE, "is 40 bytes", "at most 26"),
    case("flash-unknown-chip", "flash --name A --chip esp99", USAGE, "invalid choice: 'esp99'"),
    case("flash-zero-baud", "flash --name A --baud 0", USAGE, "whole number above 0"),
    case(
        "flash-missing-firmware",
        "flash --name A --port {silent_port} --firmware {f}/missing.bin",
        FAILED,
        "missing.bin: no such firmware file",
        answer_within_s=5.0,
    ),
    case(
        "flash-junk-firmware",
        "flash --name A --port {silent_port} --firmware {f}/junk.bin",
        FAILED,
        "junk.bin is not an ESP32 firmware image",
        answer_within_s=5.0,
    ),
    case(
        "flash-empty-firmware",
        "flash --name A --port {silent_port} --firmware {f}/empty.bin",
        FAILED,
        "empty.bin is not an ESP32 firmware image",
        answer_within_s=5.0,
    ),
    case(
        "flash-folder-firmware",
        "flash --name A --port {silent_port} --firmware {f}/folder.py",
        FAILED,
        "folder.py is a folder",
        answer_within_s=5.0,
    ),
    case("flash-missing-port", "flash --name A --port /dev/no-such-board", FAILED, "there is no such port"),
    # -- completion --------------------------------------------------------------------------------
    case("completion-unknown-shell", "completion tcsh", USAGE, "invalid choice: 'tcsh'", "bash", "fish"),
    case("completion-without-shell", "completion", USAGE, "required: shell"),
    # -- docs ------------------------------------------------------------------------------------
    case("docs-unknown-page", "docs nosuch", USAGE, "no docs page 'nosuch'", "pages: "),
    case("docs-typo", "docs simulater", USAGE, "did you mean simulator?"),
    case("docs-path-traversal", "docs ../../etc/passwd", USAGE, "no docs page '../../etc/passwd'"),
    # -- console -------------------------------------------------------------------------------
    case(
        "console-port-out-of-range",
        "console --port 99999",
        USAGE,
        "--port 99999 is not a port number (0-65535)",
    ),
    case("console-port-word", "console --port high", USAGE, "invalid int value: 'high'"),
    case("console-negative-virtual", "console --virtual -2", USAGE, "--virtual -2: give 0 or more"),
    case("console-unknown-action", "console bogus", USAGE, "invalid choice: 'bogus'"),
    case("console-token-unknown-role", "console token --role king", USAGE, "invalid choice: 'king'"),
    case(
        "console-foreign-address",
        "console --host 192.0.2.1 --port 1 --virtual 0 --no-ble",
        FAILED,
        "cannot listen on 192.0.2.1:1",
    ),
    # -- sim -------------------------------------------------------------------------------------
    case("sim-unknown-command", "sim bogus", USAGE, "invalid choice: 'bogus'"),
    case("sim-run-without-program", "sim run", USAGE, "required: SCRIPT"),
    case("sim-run-missing-file", "sim run {f}/missing.py", FAILED, "missing.py: no such program file"),
    case("sim-run-folder", "sim run {f}/folder.py", FAILED, "folder.py is a folder"),
    case("sim-run-binary-file", "sim run {f}/picture.py", FAILED, "is not UTF-8 text"),
    case("sim-run-nul-byte", "sim run {f}/nul.py", FAILED, "nul.py contains a NUL byte"),
    case(
        "sim-run-syntax-error",
        "sim run {f}/bracket.py",
        FAILED,
        'File "bracket.py", line 2',
        "x = (1,",
        "^",
        "SyntaxError: '(' was never closed",
    ),
    case(
        "sim-run-unknown-world",
        "sim run {f}/ok.py --world mars",
        FAILED,
        "unknown world 'mars'",
        "line_track",
    ),
    case("sim-run-program-as-world", "sim run {f}/ok.py --world {f}/ok.py", FAILED, "is not an MJCF model"),
    case(
        "sim-run-broken-world",
        "sim run {f}/ok.py --world {f}/broken.xml",
        FAILED,
        "not a model MuJoCo can load",
    ),
    case(
        "sim-run-bad-world-file",
        "sim run {f}/ok.py --world {f}/table.toml",
        FAILED,
        "table.toml:2: size_mm: must be positive, got 0",
        "table.toml:4: colour: unknown key",
        "table.toml:1: mat: image 'missing.png' not found",
    ),
    case(
        "sim-run-mat-without-size",
        "sim run {f}/ok.py --world {f}/mat.png",
        FAILED,
        "add --mat-size WIDTHxHEIGHT",
    ),
    case(
        "sim-run-bad-mat-size", "sim run {f}/ok.py --world {f}/mat.png --mat-size 2362", USAGE, "WIDTHxHEIGHT"
    ),
    case(
        "console-bad-world-file",
        "console --world {f}/table.toml",
        USAGE,
        "--world:",
        "size_mm: must be positive",
    ),
    case("sim-run-unknown-chassis", "sim run {f}/ok.py --chassis tank", USAGE, "invalid choice: 'tank'"),
    case("sim-run-negative-duration", "sim run {f}/ok.py --duration -1", USAGE, "give a positive number"),
    case("sim-run-zero-speed", "sim run {f}/ok.py --speed 0", USAGE, "give a positive number"),
    case(
        "sim-run-negative-wall-limit", "sim run {f}/ok.py --wall-limit -1", USAGE, "give a number from 0 up"
    ),
    case(
        "sim-run-negative-seed", "sim run {f}/ok.py --seed -3", USAGE, "'-3': give a whole number from 0 up"
    ),
    case("sim-run-nan-position", "sim run {f}/ok.py --x nan", USAGE, "give a finite number"),
    case("sim-run-hub-dir-is-a-file", "sim run {f}/ok.py --hub-dir {f}/ok.py", FAILED, "is a file"),
    case("sim-preview-zero-duration", "sim preview --headless --duration 0", USAGE, "give a positive number"),
]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """The bad files people hand the CLI."""
    folder = tmp_path_factory.mktemp("bad-input")
    (folder / "ok.py").write_text("print('ok')\n")
    (folder / "folder.py").mkdir()
    (folder / "picture.py").write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(range(256)))
    (folder / "latin1.py").write_bytes("print('a')\nprint('b')\nname = 'café'\n".encode("latin-1"))
    (folder / "nul.py").write_bytes(b"print(1)\nprint(2)\x00\n")
    (folder / "big.py").write_text("#" * (OVERSIZED_BYTES - 1) + "\n")
    (folder / "bracket.py").write_text("print('start')\nx = (1,\n")
    (folder / "indent.py").write_text("x = 1\n    y = 2\n")
    (folder / "open_string.py").write_text('x = "abc\n')
    (folder / "match.py").write_text("match command:\n    case 1:\n        pass\n")
    (folder / "memory.py").write_text("print('allocating')\nbuffer = bytearray(1 << 40)\n")
    (folder / "junk.bin").write_bytes(b"not a firmware image at all\n")
    (folder / "empty.bin").write_bytes(b"")
    (folder / "broken.xml").write_text("<mujoco><worldbody>\n")
    (folder / "table.toml").write_text(
        'mat = "missing.png"\nsize_mm = [2362, 0]\nstart = { x_mm = 100, y_mm = 100 }\ncolour = "red"\n'
    )
    (folder / "mat.png").write_bytes(b"\x89PNG\r\n\x1a\n")
    return folder


@pytest.fixture(scope="module")
def silent_port():
    """A serial port nothing answers on: probing it would cost seconds, so it must not be probed."""
    main, other = os.openpty()
    yield os.ttyname(other)
    os.close(main)
    os.close(other)


@pytest.fixture(scope="module")
def catalogue_env(hub, tmp_path_factory):
    """The hub with eleven runs behind it (run 0 overwritten, runs 1..10 kept) and a staged
    /program.py; an esptool that cannot start and a browser that opens nothing, so a case that went
    further than it should shows up in its message instead of touching anything."""
    for _ in range(11):
        done = cli(hub.env, "run", "-n", HUB, "-c", "pass")
        assert done.returncode == 0, done.stderr
    return dict(
        hub.env,
        OPENBRICKS_ESPTOOL=str(tmp_path_factory.mktemp("no-esptool") / "esptool"),
        BROWSER="true %s",
        OPENBRICKS_CACHE_DIR=str(tmp_path_factory.mktemp("cache")),
    )


@pytest.mark.parametrize("bad", CASES)
def test_bad_input_gets_a_clear_answer(bad: Case, catalogue_env, files, silent_port):
    args = [part.format(f=files, hub=HUB, silent_port=silent_port) for part in bad.argv]
    started = time.monotonic()
    env = {name: value for name, value in catalogue_env.items() if name not in bad.unset}
    done = cli(env, *args)
    elapsed_s = time.monotonic() - started
    said = done.stderr + done.stdout

    assert done.returncode == bad.status, f"exit {done.returncode}, not {bad.status}: {said}"
    for words in bad.words:
        assert words in said, f"{words!r} missing from: {said}"
    if not bad.program_error:
        assert not _TRACEBACK.search(said), said
    leaked = {name for name in _EXCEPTION_NAME.findall(said) if name not in _USER_FACING}
    assert not leaked, f"internal exception names {leaked} in: {said}"
    assert not _ERRNO.search(said), said
    if bad.answer_within_s is not None:
        assert "==>" not in done.stderr, f"it started working before checking: {said}"
        assert elapsed_s < bad.answer_within_s, f"took {elapsed_s:.1f} s: {said}"


def test_the_catalogue_covers_every_command():
    from openbricks_server.cli import COMMANDS

    covered = {c.values[0].argv[0] for c in CASES}
    assert set(COMMANDS) - {"doc"} <= covered
    assert len(CASES) >= 40


# -- the console daemon: REST and WebSocket ---------------------------------------------------------
# A real daemon under uvicorn on 127.0.0.1 (tests/server/daemon/conftest.py); every refusal is a
# specific status with the one error shape, {"error", "message", "hint"}.


@dataclass(frozen=True)
class ApiCase:
    method: str
    path: str
    status: int
    error: str
    words: tuple[str, ...]
    request: dict  # httpx keywords: json=, content=, headers=
    role: str = "operator"


def api(id_, method, path, status, error, *words, role="operator", **request):
    return pytest.param(ApiCase(method, path, status, error, words, request, role), id=id_)


JSON = {"content-type": "application/json"}

API_CASES = [
    api("unknown-endpoint", "GET", "/api/nope", 404, "not_found", "no such endpoint: /api/nope"),
    api("unknown-program", "GET", "/api/programs/nope.py", 404, "not_found", "program 'nope.py' not found"),
    api("delete-unknown-program", "DELETE", "/api/programs/nope.py", 404, "not_found", "'nope.py'"),
    api(
        "program-path-traversal",
        "PUT",
        "/api/programs/..%2F..%2Fetc%2Fpasswd",
        404,
        "not_found",
        "no such endpoint",
        json={"source": "x = 1"},
    ),
    api(
        "program-named-dotdot",
        "PUT",
        "/api/programs/%2E%2E",
        422,
        "bad_program_name",
        "'..' is not a program name",
        json={"source": "x = 1"},
    ),
    api(
        "program-hidden-name",
        "PUT",
        "/api/programs/.hidden",
        422,
        "bad_program_name",
        "no '..'",
        json={"source": "x = 1"},
    ),
    api(
        "malformed-json",
        "PUT",
        "/api/programs/x.py",
        422,
        "invalid_request",
        "not valid JSON",
        content=b"{not json",
        headers=JSON,
    ),
    api(
        "non-utf8-body",
        "PUT",
        "/api/programs/x.py",
        400,
        "bad_request",
        "send UTF-8 JSON",
        content=b'{"source": "\xff\xfe"}',
        headers=JSON,
    ),
    api(
        "missing-source",
        "PUT",
        "/api/programs/x.py",
        422,
        "invalid_request",
        "source: Field required",
        json={},
    ),
    api(
        "source-not-text", "PUT", "/api/programs/x.py", 422, "invalid_request", "source:", json={"source": 5}
    ),
    api(
        "binary-program",
        "PUT",
        "/api/programs/x.py",
        422,
        "binary_program",
        "control character 0x00",
        json={"source": "print(1)\x00"},
    ),
    api(
        "oversized-program",
        "PUT",
        "/api/programs/x.py",
        413,
        "program_too_large",
        f"x.py is {OVERSIZED_BYTES} bytes",
        json={"source": "#" * OVERSIZED_BYTES},
    ),
    api(
        "program-syntax-error",
        "PUT",
        "/api/programs/x.py",
        422,
        "syntax_error",
        "x.py, line 1: '(' was never closed",
        json={"source": "print(1"},
    ),
    api(
        "wrong-method",
        "POST",
        "/api/programs/x.py",
        405,
        "method_not_allowed",
        "POST is not allowed",
        json={},
    ),
    api(
        "version-zero",
        "GET",
        "/api/programs/x.py/versions/0",
        422,
        "invalid_request",
        "greater than or equal to 1",
    ),
    api("bad-run-id", "GET", "/api/runs/notanid", 422, "bad_run_id", "'notanid' is not a run id"),
    api(
        "unknown-run",
        "GET",
        "/api/runs/01HZZZZZZZZZZZZZZZZZZZZZZZ",
        404,
        "not_found",
        "run 01HZZZZZZZZZZZZZZZZZZZZZZZ",
    ),
    api("bad-date", "GET", "/api/runs?since=garbage", 422, "invalid_request", "since (in the query)"),
    api(
        "bad-export-format",
        "GET",
        "/api/runs/01HZZZZZZZZZZZZZZZZZZZZZZZ/export?format=xml",
        422,
        "invalid_request",
        "'json' or 'text'",
    ),
    api("no-token", "GET", "/api/programs", 401, "unauthorized", "no valid token", role="none"),
    api("wrong-token", "GET", "/api/programs", 401, "unauthorized", "no valid token", role="wrong"),
    api(
        "viewer-writes",
        "PUT",
        "/api/programs/x.py",
        403,
        "operator_required",
        "is a viewer's (read-only)",
        role="viewer",
        json={"source": "x = 1"},
    ),
    # the hubs API, with one virtual hub (SimHub-1)
    api("unknown-hub", "GET", "/api/hubs/Nope", 404, "hub_not_found", "no hub 'Nope' (hubs: SimHub-1)"),
    api(
        "run-on-unknown-hub",
        "POST",
        "/api/hubs/Nope/run",
        404,
        "hub_not_found",
        "no hub 'Nope'",
        json={"source": "pass"},
    ),
    api(
        "hub-run-syntax-error",
        "POST",
        "/api/hubs/SimHub-1/run",
        422,
        "syntax_error",
        "'(' was never closed",
        json={"source": "print(1"},
    ),
    api(
        "hub-run-source-and-program",
        "POST",
        "/api/hubs/SimHub-1/run",
        422,
        "invalid_request",
        "give either `source`",
        json={"source": "pass", "program": "x.py"},
    ),
    api(
        "hub-run-nothing",
        "POST",
        "/api/hubs/SimHub-1/run",
        422,
        "invalid_request",
        "give either `source`",
        json={},
    ),
    api(
        "hub-run-unknown-program",
        "POST",
        "/api/hubs/SimHub-1/run",
        404,
        "not_found",
        "program 'nope.py' not found",
        json={"program": "nope.py"},
    ),
    api(
        "hub-run-name-traversal",
        "POST",
        "/api/hubs/SimHub-1/run",
        422,
        "bad_program_name",
        "'../../x.py' is not a program name",
        json={"source": "pass", "name": "../../x.py"},
    ),
    api(
        "hub-run-oversized",
        "POST",
        "/api/hubs/SimHub-1/run",
        413,
        "program_too_large",
        f"{OVERSIZED_BYTES} bytes",
        json={"source": "#" * OVERSIZED_BYTES},
    ),
    api(
        "hub-run-binary",
        "POST",
        "/api/hubs/SimHub-1/run",
        422,
        "binary_program",
        "control character 0x00",
        json={"source": "print(1)\x00"},
    ),
    api(
        "hub-run-desktop-only-syntax",
        "POST",
        "/api/hubs/SimHub-1/run",
        422,
        "program_invalid",
        "MicroPython does not support it",
        json={"source": "match x:\n    case 1:\n        pass\n"},
    ),
    api(
        "hub-upload-path-traversal",
        "POST",
        "/api/hubs/SimHub-1/upload",
        422,
        "bad_path",
        "give an absolute hub file path",
        json={"source": "pass", "path": "/../etc/passwd"},
    ),
    api(
        "hub-upload-missing-folder",
        "POST",
        "/api/hubs/SimHub-1/upload",
        422,
        "hub_refused",
        "there is no folder /nodir on the hub",
        json={"source": "pass", "path": "/nodir/x.py"},
    ),
    api(
        "hub-upload-onto-the-run-logs",
        "POST",
        "/api/hubs/SimHub-1/upload",
        422,
        "hub_refused",
        "the hub keeps its run logs there",
        json={"source": "pass", "path": "/openbricks_logs"},
    ),
    api(
        "hub-identify-zero",
        "POST",
        "/api/hubs/SimHub-1/identify",
        422,
        "invalid_request",
        "duration_ms",
        json={"duration_ms": 0},
    ),
    api(
        "hub-log-never-was",
        "GET",
        "/api/hubs/SimHub-1/logs/99",
        404,
        "log_not_found",
        "SimHub-1 has no run 99",
    ),
    api(
        "hub-log-negative",
        "GET",
        "/api/hubs/SimHub-1/logs/-1",
        422,
        "invalid_request",
        "greater than or equal to 0",
    ),
    api("hub-log-word", "GET", "/api/hubs/SimHub-1/logs/last", 422, "invalid_request", "valid integer"),
    api(
        "foreign-host",
        "GET",
        "/api/programs",
        403,
        "host_not_allowed",
        "host name 'evil.example'",
        headers={"Host": "evil.example"},
    ),
]


@pytest.fixture(scope="module")
def console(tmp_path_factory):
    from openbricks_server.daemon.config import DaemonConfig

    from ..daemon.conftest import Daemon

    data = tmp_path_factory.mktemp("console") / "data"
    with pytest.MonkeyPatch.context() as env:
        env.setenv("OPENBRICKS_DATA_DIR", str(data))  # where its virtual hub keeps its flash
        running = Daemon(DaemonConfig(host="127.0.0.1", port=0, virtual=1, ble=False, data_dir=data))
        try:
            running.viewer_token = running.ctx.store.tokens.mint("viewer", "mentor")
            with running.client() as client:
                deadline = time.monotonic() + 60
                while [h["status"] for h in client.get("/api/hubs").json()["hubs"]] != ["idle"]:
                    assert time.monotonic() < deadline, "the console's virtual hub never came up"
                    time.sleep(0.1)
            yield running
        finally:
            running.stop()


@pytest.mark.parametrize("bad", API_CASES)
def test_bad_requests_get_a_specific_status_and_the_error_shape(bad: ApiCase, console):
    import httpx

    tokens = {
        "operator": console.token,
        "viewer": console.viewer_token,
        "wrong": "not-a-token",
    }
    headers = dict(bad.request.get("headers", {}))
    if bad.role in tokens:
        headers["Authorization"] = f"Bearer {tokens[bad.role]}"
    request = {k: v for k, v in bad.request.items() if k != "headers"}
    with httpx.Client(base_url=console.url, timeout=10) as client:
        answer = client.request(bad.method, bad.path, headers=headers, **request)
    assert answer.status_code == bad.status, answer.text
    body = answer.json()
    assert body["error"] == bad.error, body
    assert body["message"] and body.get("hint"), f"no message or hint: {body}"
    for words in bad.words:
        assert words in body["message"] + body["hint"], body
    leaked = {name for name in _EXCEPTION_NAME.findall(answer.text) if name not in _USER_FACING}
    assert not _TRACEBACK.search(answer.text) and not leaked, answer.text
    assert not _ERRNO.search(answer.text), answer.text


WS_CASES = [
    pytest.param("not json", "bad_message", "not JSON", id="ws-not-json"),
    pytest.param("[1, 2]", "bad_message", 'a JSON object with a "cmd" string', id="ws-json-array"),
    pytest.param('{"cmd": 5}', "bad_message", '"cmd" string', id="ws-cmd-not-text"),
    pytest.param(
        '{"cmd": "launch", "id": 1}', "unknown_command", "no command 'launch'", id="ws-unknown-command"
    ),
    pytest.param(b"\x00\x01\xff binary", "bad_message", "JSON text frames", id="ws-binary-frame"),
    pytest.param("x" * (64 * 1024 + 1), "bad_message", "at most 65536 bytes", id="ws-oversized-command"),
]


@pytest.mark.parametrize(("message", "error", "words"), WS_CASES)
def test_garbage_on_the_event_stream_gets_a_reply_and_the_stream_goes_on(console, message, error, words):
    import json

    with console.websocket() as ws:
        assert json.loads(ws.recv(timeout=10))["type"] == "hello"
        ws.send(message)
        reply = json.loads(ws.recv(timeout=10))
        while reply["type"] != "reply":  # events of the stream may come first
            reply = json.loads(ws.recv(timeout=10))
        ws.send(json.dumps({"cmd": "ping", "id": "after"}))
        pong = json.loads(ws.recv(timeout=10))
    assert reply["data"]["ok"] is False and reply["data"]["error"]["error"] == error, reply
    assert words in reply["data"]["error"]["message"] and reply["data"]["error"]["hint"], reply
    assert pong["data"]["ok"] is True, pong


@pytest.mark.parametrize(
    ("token", "origin"),
    [
        pytest.param("not-a-token", None, id="ws-wrong-token"),
        pytest.param(None, "http://evil.example", id="ws-foreign-origin"),
    ],
)
def test_the_event_stream_refuses_strangers(console, token, origin):
    from websockets.exceptions import InvalidStatus

    with pytest.raises(InvalidStatus) as refused:
        with console.websocket(token=token, origin=origin):
            pass
    assert refused.value.response.status_code in (401, 403)


def test_ctrl_c_stops_a_sim_run_with_status_130(files):
    """Ctrl-C is input too: the run stops, says so, and the shell sees 130 like any interrupted command."""
    import signal
    import subprocess
    import sys

    program = files / "ticking.py"
    program.write_text("import time\nwhile True:\n    print('tick')\n    time.sleep_ms(100)\n")
    process = subprocess.Popen(
        [sys.executable, "-m", "openbricks_server.cli", "sim", "run", str(program), "--speed", "1"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert process.stdout.readline() == "tick\n"
        process.send_signal(signal.SIGINT)
        _out, err = process.communicate(timeout=30)
    finally:
        process.kill()
    assert process.returncode == 130, err
    assert "[stopped]" in err and not _TRACEBACK.search(err), err
