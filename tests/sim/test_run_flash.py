"""A sim run's files are the hub's: a program (and the runtime it imports) reads and writes the run's
own hub flash, never the host's filesystem; a fresh flash per run unless a hub directory is given."""

import os

import pytest

from openbricks_sim.run import ERROR, FINISHED, run_program


def run(source, **kwargs):
    return run_program("mission.py", source=source, **kwargs)


def test_a_program_writes_to_its_hub_flash_not_to_the_hosts_root():
    marker = "/openbricks-sim-run-flash-probe.txt"
    result = run(
        f"import os\nwith open({marker!r}, 'w') as f:\n    f.write('hello')\nprint(sorted(os.listdir('/')))\n"
    )
    assert result.exit == FINISHED, result.error
    assert result.output == f"[{marker[1:]!r}]\n"  # the hub's root holds only what the run wrote
    assert not os.path.exists(marker)


def test_every_run_starts_on_a_blank_flash_by_default():
    first = run("open('/note.txt', 'w').write('from run 1')\n")
    assert first.exit == FINISHED, first.error
    second = run("import os\nprint(os.listdir('/'))\n")
    assert second.output == "[]\n"


def test_the_temporary_flash_is_removed_after_the_run_even_when_the_program_fails(tmp_path, monkeypatch):
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    result = run("open('/x', 'w').close()\nraise ValueError('mission failed')\n")
    assert result.exit == ERROR and "mission failed" in result.error
    assert os.listdir(tmp_path) == []


def test_a_given_hub_dir_keeps_files_from_one_run_to_the_next(tmp_path):
    hub = tmp_path / "hub"
    first = run("with open('/count.txt', 'w') as f:\n    f.write('1')\n", hub_dir=hub)
    assert first.exit == FINISHED, first.error
    assert (hub / "count.txt").read_text() == "1"
    second = run("print(open('/count.txt').read())\n", hub_dir=hub)
    assert second.output == "1\n"
    assert second.job["hub_dir"] == str(hub)


def test_hub_paths_never_reach_outside_the_flash(tmp_path):
    hub = tmp_path / "hub"
    (tmp_path / "secret.txt").write_text("host file")
    result = run(
        "for path in ('/../secret.txt', '../secret.txt', '/../../etc/passwd'):\n"
        "    try:\n"
        "        open(path).read()\n"
        "        print(path, 'opened')\n"
        "    except OSError as exc:\n"
        "        print(path, exc.args[0])\n",
        hub_dir=hub,
    )
    assert result.output.splitlines() == ["/../secret.txt 2", "../secret.txt 2", "/../../etc/passwd 2"]


def test_the_runtimes_own_files_land_on_the_flash(tmp_path):
    """openbricks.log keeps run logs under the hub's /openbricks_logs, with the runtime's own os/open."""
    hub = tmp_path / "hub"
    result = run(
        "from openbricks import log\n"
        "with log.session() as session:\n"
        "    session.write_text('mission started')\n"
        "print(log.list_runs())\n",
        hub_dir=hub,
    )
    assert result.exit == FINISHED, result.error
    assert result.output == "[(0, '/openbricks_logs/slot_0.log')]\n"
    assert "mission started" in (hub / "openbricks_logs" / "slot_0.log").read_text()


def test_a_module_on_the_flash_imports_as_on_the_hub(tmp_path):
    hub = tmp_path / "hub"
    (hub / "lib").mkdir(parents=True)
    (hub / "lib" / "mission_helpers.py").write_text("SIDE_MM = 300\n")
    result = run("from mission_helpers import SIDE_MM\nprint(SIDE_MM)\n", hub_dir=hub)
    assert result.exit == FINISHED, result.error
    assert result.output == "300\n"


def test_the_pins_guard_checks_the_simulated_hubs_chip():
    """The hub is an ESP32-S3: a pin wired to its flash is refused in the simulator as on the robot."""
    result = run("from openbricks.drivers.l298n import L298NMotor\nL298NMotor(in1=26, in2=2, pwm=17)\n")
    assert result.exit == ERROR
    assert "GPIO 26 can't be used as" in result.error and "SPI flash" in result.error


@pytest.mark.e2e
def test_the_module_entry_point_takes_a_hub_dir(tmp_path):
    import json
    import subprocess
    import sys

    import openbricks_mjcontrol

    import openbricks_native

    program = tmp_path / "mission.py"
    program.write_text("open('/from_cli.txt', 'w').write('kept')\n")
    env = dict(os.environ)
    paths = {os.path.dirname(openbricks_native.__file__), os.path.dirname(openbricks_mjcontrol.__file__)}
    env["PYTHONPATH"] = os.pathsep.join([*paths, env.get("PYTHONPATH", "")])
    out = subprocess.run(
        [sys.executable, "-m", "openbricks_sim.run", str(program), "--json", "--hub-dir", "flash"],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
        cwd=tmp_path,
    )
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["exit"] == FINISHED
    assert (tmp_path / "flash" / "from_cli.txt").read_text() == "kept"


def test_a_hub_dir_that_is_a_file_is_refused_before_the_run_with_the_path(tmp_path, capsys):
    from openbricks_sim import cli
    from openbricks_sim.run_flash import HubDirError

    not_a_dir = tmp_path / "notes.txt"
    not_a_dir.write_text("")
    with pytest.raises(HubDirError, match=f"hub directory {not_a_dir} is a file"):
        run("print('never runs')\n", hub_dir=not_a_dir)
    script = tmp_path / "mission.py"
    script.write_text("print('never runs')\n")
    assert cli.main(["run", str(script), "--hub-dir", str(not_a_dir)]) == cli.EXIT_FAILED
    captured = capsys.readouterr()
    assert captured.err == (
        f"openbricks sim run: error: hub directory {not_a_dir} is a file: "
        "give a directory for the hub's flash\n"
    )
    assert "never runs" not in captured.out
