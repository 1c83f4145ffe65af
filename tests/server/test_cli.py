"""The parser matches the manual's chapter 3: commands, option names, defaults; --help stays light."""

import subprocess
import sys

import pytest

from openbricks_server.cli import COMMANDS, build_parser, main


def parse(*argv):
    return build_parser().parse_args(list(argv))


def test_every_command_of_chapter_3_is_there():
    assert set(COMMANDS) == {
        "flash",
        "run",
        "upload",
        "stop",
        "list",
        "log",
        "servo-id",
        "paste-probe",
        "docs",
        "doc",
        "sim",
        "console",
        "completion",
    }


def test_defaults_are_the_manuals():
    flash = parse("flash", "--name", "RobotA")
    assert (flash.chip, flash.baud, flash.port, flash.firmware) == ("auto", 460800, None, None)
    assert not (flash.with_qtr_init or flash.skip_erase or flash.yes or flash.verbose)
    assert parse("flash", "--name", "A", "-v").verbose
    run = parse("run", "-n", "RobotA", "main.py")
    assert (run.script, run.code, run.scan_timeout, run.debug) == ("main.py", None, 5.0, False)
    assert parse("upload", "-n", "A", "x.py").path is None
    assert parse("stop", "-n", "A").scan_timeout == 5.0
    listing = parse("list")
    assert (listing.timeout, listing.all) == (5.0, False)
    log = parse("log", "-n", "A")
    assert (log.list, log.run, log.scan_timeout) == (False, None, 5.0)
    servo = parse("servo-id", "--scan")
    assert (servo.tx, servo.rx, servo.baudrate, servo.timeout, servo.scan_timeout) == (
        14,
        41,
        1000000,
        0.02,
        5.0,
    )
    assert (servo.port, servo.name, servo.old_id, servo.new_id) == (None, None, None, None)
    probe = parse("paste-probe", "-n", "A")
    assert (probe.max, probe.timeout, probe.scan_timeout) == (8192, 15.0, 5.0)
    assert parse("doc", "cli").topic == "cli"
    console = parse("console")
    assert (console.host, console.port, console.virtual, console.world) == ("127.0.0.1", 8765, 2, None)
    assert (console.data_dir, console.no_ble, console.console_command) == (None, False, None)
    token = parse("console", "token", "--role", "viewer")
    assert (token.console_command, token.role, token.label) == ("token", "viewer", None)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["run", "-n", "A"], "give a SCRIPT to run, or code with -c"),
        (["run", "-n", "A", "-c", "print(1)", "x.py"], "give either SCRIPT or -c CODE, not both"),
        (["servo-id", "-p", "/dev/ttyUSB0", "-n", "A", "--scan"], "not allowed with argument"),
        (["servo-id"], "give the NEW_ID to assign, or --scan"),
        (["flash"], "the following arguments are required: --name"),
    ],
)
def test_wrong_combinations_are_usage_errors(capsys, argv, message):
    with pytest.raises(SystemExit) as stopped:
        main(argv)
    assert stopped.value.code == 2
    assert message in capsys.readouterr().err


@pytest.mark.parametrize("command", sorted(set(COMMANDS) - {"sim", "doc"}))
def test_every_subcommand_has_help(command, capsys):
    with pytest.raises(SystemExit) as stopped:
        main([command, "--help"])
    assert stopped.value.code == 0
    assert f"usage: openbricks {command}" in capsys.readouterr().out


def test_help_imports_no_command_machinery():
    probe = (
        "import sys\n"
        "from openbricks_server import cli\n"
        "try:\n"
        "    cli.main(['--help'])\n"
        "except SystemExit:\n"
        "    pass\n"
        "heavy = [m for m in ('asyncio', 'bleak', 'serial', 'mujoco', 'cryptography', 'openbricks_native',\n"
        "                     'openbricks_server.commands', 'openbricks_server.link', 'fastapi', 'uvicorn',\n"
        "                     'pydantic', 'openbricks_server.daemon.app') if m in sys.modules]\n"
        "print(heavy, file=sys.stderr)\n"
    )
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=60)
    assert done.stderr.strip() == "[]"


def test_sim_forwards_everything_including_help():
    done = subprocess.run(
        [sys.executable, "-m", "openbricks_server.cli", "sim", "run", "--help"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 0 and "usage: openbricks sim run" in done.stdout and "--no-shim" in done.stdout


@pytest.mark.parametrize("shell", ["bash", "zsh", "fish"])
def test_completion_prints_code_that_loads_in_the_shell(shell, capsys):
    assert main(["completion", shell]) == 0
    code = capsys.readouterr().out
    assert "openbricks" in code and "_ARGCOMPLETE" in code


def test_tab_completes_commands_and_options_from_the_real_parser(tmp_path):
    """What the shell code asks for when Tab is pressed: the commands, then a command's options."""
    import os

    answer = tmp_path / "completions"

    def complete(line):
        env = {
            **os.environ,
            "_ARGCOMPLETE": "1",
            "_ARGCOMPLETE_IFS": "\n",
            "_ARGCOMPLETE_STDOUT_FILENAME": str(answer),
            "COMP_LINE": line,
            "COMP_POINT": str(len(line)),
        }
        command = [sys.executable, "-m", "openbricks_server.cli"]
        done = subprocess.run(command, env=env, capture_output=True, text=True, timeout=60)
        return done.returncode, [word.strip() for word in answer.read_text().split("\n")]

    status, words = complete("openbricks l")
    assert status == 0 and {"list", "log"} <= set(words)
    _, options = complete("openbricks log --l")
    assert "--list" in options


def _command(argv: list[str], before: str = "") -> subprocess.CompletedProcess:
    """`openbricks ARGV` as its console script runs it (cli.run), with `before` run first in the process."""
    probe = f"import sys\n{before}\nsys.argv = ['openbricks', *{argv!r}]\n"
    probe += "from openbricks_server.cli import run\nrun()\n"
    return subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)


def test_the_command_exits_with_its_status_its_output_flushed_and_its_exit_handlers_run(tmp_path):
    program = tmp_path / "hello.py"
    program.write_text("print('hello from the hub')\n", encoding="utf-8")
    at_exit = "import atexit\natexit.register(lambda: print('exit handlers ran', file=sys.stderr))"
    done = _command(["sim", "run", str(program)], before=at_exit)
    assert done.returncode == 0, done.stderr
    assert "hello from the hub" in done.stdout  # a pipe: block-buffered, flushed on the way out
    assert "exit handlers ran" in done.stderr

    failed = _command(["sim", "run", str(tmp_path / "missing.py")])
    assert failed.returncode != 0 and "missing.py" in failed.stderr

    usage = _command(["no-such-command"])
    assert usage.returncode == 2 and "invalid choice" in usage.stderr
