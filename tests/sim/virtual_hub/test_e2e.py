"""A virtual hub process driven through its pseudo-terminal: real mpremote, a raw host, the control
socket. What a host sees is what it would see on a hub flashed with openbricks."""

import base64
import os
import signal
import struct
import time
import zlib

import pytest

from .hubproc import Host, HubProcess, result_of

pytestmark = pytest.mark.e2e

DRIVE = """\
import time
from openbricks.drivers.st3032 import ST3032Motor

left = ST3032Motor(1)
right = ST3032Motor(2, invert=True)
left.run_speed(360)
right.run_speed(360)
time.sleep_ms(1500)
left.brake()
right.brake()
print("drove until", time.ticks_ms() > 0)
"""

ENDLESS = """\
import time
while True:
    try:
        time.sleep_ms(50)
    except Exception:
        pass
"""


@pytest.fixture
def hub(tmp_path):
    process = HubProcess(tmp_path / "RobotA", "RobotA", "--speed", "max", "--paste-window", "64")
    try:
        yield process
    finally:
        assert process.stop() == 0, process.stderr()


@pytest.fixture
def host(hub):
    link = Host(hub.pty)
    link.enter_raw()
    try:
        yield link
    finally:
        link.close()


def wait_until(condition, timeout_s=20):
    deadline = time.monotonic() + timeout_s
    while not condition():
        assert time.monotonic() < deadline, "condition not met in time"
        time.sleep(0.05)


def flash(hub, *parts):
    return os.path.join(hub.directory, "flash", *parts)


def test_mpremote_execs_copies_lists_and_runs_files(hub, tmp_path):
    helper = tmp_path / "helper.py"
    helper.write_text("def greet(name):\n    return 'hello ' + name\n")
    program = tmp_path / "main_program.py"
    program.write_text(
        "import helper, os\nprint(helper.greet('hub'))\nprint(sorted(os.listdir('/')))\n"
        "print(open('/helper.py').read().count('def'))\n"
    )

    done = hub.mpremote("exec", "print('sum', 20 + 22)")
    assert done.returncode == 0, done.stderr
    assert done.stdout.decode().strip() == "sum 42"

    done = hub.mpremote("fs", "cp", str(helper), ":helper.py", "+", "fs", "ls")
    assert done.returncode == 0, done.stderr
    listing = done.stdout.decode()
    assert "helper.py" in listing and f"{helper.stat().st_size} helper.py" in listing
    with open(flash(hub, "helper.py")) as f:
        assert f.read() == helper.read_text()

    done = hub.mpremote("run", str(program))
    assert done.returncode == 0, done.stderr
    assert done.stdout.decode().splitlines() == ["hello hub", "['helper.py']", "1"]

    done = hub.mpremote("fs", "cp", ":helper.py", str(tmp_path / "back.py"))
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "back.py").read_text() == helper.read_text()

    done = hub.mpremote("fs", "cat", ":missing.py")
    assert done.returncode != 0
    assert "No such file" in (done.stdout + done.stderr).decode()


def test_mpremote_df_lists_the_flash_as_on_a_hub(hub):
    done = hub.mpremote("df")
    assert done.returncode == 0, done.stderr
    header, flash_line = done.stdout.decode().splitlines()
    assert header.split() == ["filesystem", "size", "used", "avail", "use%", "mounted", "on"]
    name, size, used, avail, _percent, mount_point = flash_line.split()
    assert (name, int(size), mount_point) == ("<VfsLfs2>", 2 * 1024 * 1024, "/")
    assert int(used) + int(avail) == int(size)


def test_mpremote_mount_runs_a_program_from_a_host_directory(hub, tmp_path):
    shared = tmp_path / "shared"
    shared.mkdir()
    (shared / "helper.py").write_text("VALUE = 42\n")
    (shared / "data.txt").write_text("from the host\n")
    (shared / "mission.py").write_text("import helper\nprint('helper says', helper.VALUE)\n")
    done = hub.mpremote(
        "mount",
        str(shared),
        "exec",
        "import os\nprint(os.getcwd(), sorted(os.listdir()))\nprint(open('data.txt').read().strip())\n"
        "with open('written.txt', 'w') as f:\n    f.write('from the hub')\n",
    )
    assert done.returncode == 0, done.stderr
    lines = done.stdout.decode().splitlines()
    assert lines[0] == f"Local directory {shared} is mounted at /remote"
    assert lines[1:] == ["/remote ['data.txt', 'helper.py', 'mission.py']", "from the host"]
    assert (shared / "written.txt").read_text() == "from the hub"
    assert not os.path.exists(flash(hub, "written.txt"))  # on the host directory, not the flash

    done = hub.mpremote("mount", str(shared), "run", str(shared / "mission.py"))
    assert done.returncode == 0, done.stderr
    assert done.stdout.decode().splitlines()[-1] == "helper says 42"

    # mpremote unmounts when it is done: the hub is back on its flash.
    done = hub.mpremote("exec", "import os, vfs\nprint(os.getcwd(), len(vfs.mount()))")
    assert done.returncode == 0, done.stderr
    assert done.stdout.decode().strip() == "/ 1"


def test_mpremote_sees_a_micropython_traceback_for_a_failing_exec(hub):
    done = hub.mpremote("exec", "def f():\n    raise ValueError('bad value')\nf()")
    assert done.returncode == 1
    text = done.stdout.decode()
    assert 'File "<stdin>", line 3, in <module>' in text and "line 2, in f" in text
    assert "ValueError: bad value" in text
    assert "virtual_hub" not in text and "site-packages" not in text


def test_raw_paste_flow_control_through_the_pty(host):
    source = "total = 0\n" + "".join(f"total += {i}\n" for i in range(400)) + "print('total', total)\n"
    assert len(source) > 10 * 64
    host.write(b"\x05A\x01")
    assert host.read_exactly(2) == b"R\x01"
    (window,) = struct.unpack("<H", host.read_exactly(2))
    assert window == 64
    data = source.encode()
    credit, sent = window, 0
    while sent < len(data):
        while credit == 0 or host.port.in_waiting:
            byte = host.read_exactly(1)
            assert byte == b"\x01", byte
            credit += window
        chunk = data[sent : sent + credit]
        host.write(chunk)
        sent += len(chunk)
        credit -= len(chunk)
    host.write(b"\x04")
    tail = host.read_until(b"\x04")
    assert tail.strip(b"\x01") == b"\x04"  # only window grants before the end-of-data ack
    out = host.read_until(b"\x04")
    err = host.read_until(b"\x04")
    assert out == f"total {sum(range(400))}\r\n\x04".encode() and err == b"\x04"
    assert host.read_exactly(1) == b">"


def test_ctrl_c_stops_a_running_loop_and_the_hub_answers_after(host):
    host.write(b"import time\nn = 0\nwhile True:\n    n += 1\n    time.sleep_ms(10)\n\x04")
    assert host.read_exactly(2) == b"OK"
    time.sleep(0.5)
    host.write(b"\x03")
    assert host.read_until(b"\x04") == b"\x04"
    err = host.read_until(b"\x04").decode()
    assert "KeyboardInterrupt" in err
    host.read_until(b">")
    out, err = host.exec_raw("print('alive', n > 0)")
    assert out == "alive True\r\n" and not err


BUSY_WAIT_DRIVE = """\
from openbricks.drivers.st3032 import ST3032Motor
from openbricks.robotics import DriveBase
db = DriveBase(ST3032Motor(1), ST3032Motor(2, invert=True), wheel_diameter_mm=88, axle_track_mm=138)
db.straight(100, wait=False)
while not db.done():
    pass
print("drove", round(db.distance()))
"""


def test_a_busy_wait_on_done_finishes_because_python_costs_hub_time(host):
    """As on a hub (and in `sim run`), code that spins without sleeping lets the robot move."""
    out, err = host.exec_raw(BUSY_WAIT_DRIVE, timeout_s=60)
    assert out == "drove 100\r\n" and not err


def test_ctrl_c_twice_with_python_costing_time_leaves_the_hub_answering(host):
    """The Ctrl-C path once hung with the Python-time charge on: the next code never started."""
    for _ in range(2):
        host.write(b"x = 0\nwhile True:\n    x += 1\n    abs(x)\n\x04")
        assert host.read_exactly(2) == b"OK"
        time.sleep(0.3)
        host.write(b"\x03")
        host.read_until(b"\x04")
        assert "KeyboardInterrupt" in host.read_until(b"\x04").decode()
        host.read_until(b">")
        assert host.exec_raw("print('alive', x > 0)", timeout_s=10) == ("alive True\r\n", "")


def test_a_busy_loop_that_never_sleeps_is_interrupted_too(host):
    host.write(b"x = 0\nwhile True:\n    x += 1\n\x04")
    assert host.read_exactly(2) == b"OK"
    time.sleep(0.3)
    host.write(b"\x03")
    host.read_until(b"\x04")
    assert "KeyboardInterrupt" in host.read_until(b"\x04").decode()
    host.read_until(b">")
    assert host.exec_raw("print(x > 1000)") == ("True\r\n", "")


def test_soft_reboot_forgets_the_repl_state_but_not_the_flash(host):
    host.exec_raw("x = 5\nf = open('/kept.txt', 'w')\nf.write('kept')\nf.close()")
    host.write(b"\x04")
    assert host.read_until(b"raw REPL; CTRL-B to exit\r\n>") == (
        b"OK\r\nMPY: soft reboot\r\nraw REPL; CTRL-B to exit\r\n>"
    )
    out, err = host.exec_raw("print(open('/kept.txt').read())\nprint(x)")
    assert out == "kept\r\n" and "NameError" in err


def test_host_calls_info_rtc_stage_run_and_read_back_the_run_log(hub, host):
    info = host.call("h.info()")
    assert info["ok"] and info["chip"] == "esp32s3" and info["firmware"].startswith("2.7.1")
    assert info["accepts_mpy"] is False  # a virtual hub runs source, and says so
    assert info["log_slots"] == 10 and info["compression"] == ["zlib"]
    assert info["free_bytes"] > 0
    assert host.call("h.set_rtc(1767225600000)")["epoch_ms"] >= 1767225600000

    payload = base64.b64encode(zlib.compress(DRIVE.encode())).decode()
    staged = host.call(
        f"h.stage({payload!r}, '/program.py', compression='zlib', size={len(DRIVE)}, "
        f"crc32={zlib.crc32(DRIVE.encode())})"
    )
    assert staged == {
        "ok": True,
        "path": "/program.py",
        "bytes": len(DRIVE),
        "crc32": zlib.crc32(DRIVE.encode()),
    }

    out, err = host.exec_raw("import openbricks.host_calls as h\nh.run('/program.py')", timeout_s=60)
    assert not err, err
    assert "drove until True" in out
    result = result_of(out)
    assert result["outcome"] == "finished" and result["run"] == 0
    assert hub.control("status")["pose"]["x_mm"] > 100  # the simulated robot really drove

    assert host.call("h.runs()")["runs"][0]["index"] == 0
    log = host.call("h.read_run(0)")["text"].splitlines()
    assert log[1].split(" ", 1)[1].startswith("started: host run | firmware 2.7.1")
    assert all(int(line.split(" ", 1)[0]) >= 1767225600000 for line in log)
    assert log[-1].split(" ", 1)[1].startswith("stopped: finished after")
    with open(flash(hub, "openbricks_logs", "slot_0.log")) as f:
        assert "drove until True" in f.read()


def test_every_run_starts_from_the_worlds_start_pose(hub, host):
    host.call(f"h.stage({base64.b64encode(DRIVE.encode()).decode()!r}, '/program.py')")
    poses = []
    for _ in range(3):
        out, err = host.exec_raw("import openbricks.host_calls as h\nh.run('/program.py')", timeout_s=60)
        assert result_of(out)["outcome"] == "finished", err
        poses.append(hub.control("status")["pose"])
    # Without the reset the robot would end 1.5 s of driving further on at every run.
    assert all(300 < pose["x_mm"] < 500 for pose in poses), poses
    # Python costs hub time, and the launcher's own work before the program (its run log's slot)
    # differs a little from run to run, so the wheels start at slightly different instants.
    assert abs(poses[2]["x_mm"] - poses[1]["x_mm"]) < 15 and abs(poses[2]["y_mm"] - poses[1]["y_mm"]) < 15


def test_upload_then_start_with_the_program_button(hub, host):
    program = "import time\nprint('started by the button')\ntime.sleep_ms(200)\nprint('finished')\n"
    host.call(f"h.stage({base64.b64encode(program.encode()).decode()!r}, '/program.py')")
    # Hand the hub back to the launcher, as the host does before it disconnects.
    host.write(b"import openbricks.host_calls as h\nh.idle()\x04")
    assert host.read_exactly(2) == b"OK"
    assert result_of(host.read_until(b"\n").decode())["idle"] is True
    assert hub.control("click")["ok"]
    output = host.read_until(b"finished\r\n", timeout_s=30).decode()
    assert "started by the button" in output
    wait_until(lambda: not hub.control("status")["running"])
    # The next host session takes the hub back. A Ctrl-C that lands while the launcher is still
    # tearing the run down counts as a late stop of that run (as on a hub), so a host repeats it
    # until the idle() call ends.
    for _ in range(5):
        host.write(b"\x03")
        try:
            host.read_until(b"\x04", timeout_s=2)
            break
        except AssertionError:
            continue
    host.read_until(b"\x04")
    host.read_until(b">")
    (run,) = host.call("h.runs()")["runs"]
    log = host.call(f"h.read_run({run['index']})")["text"]
    assert "started: button press" in log and "stopped: finished after" in log


def hub_ticks_ms(host):
    out, err = host.exec_raw("import time\nprint(time.ticks_ms())")
    assert not err, err
    return int(out)


def test_an_idle_hub_keeps_to_real_time_after_hosts_interrupt_it(host):
    """Every host that connects interrupts the launcher's idle loop with a Ctrl-C, often while the
    hub is waiting for the wall clock to catch up; from then on the idle hub must still wait, not
    run its physics flat out (a core each, and a clock that races ahead of its RTC)."""
    for _ in range(3):
        before = hub_ticks_ms(host)
        host.write(b"import openbricks.host_calls as h\nh.idle()\x04")
        assert host.read_exactly(2) == b"OK"
        assert result_of(host.read_until(b"\n").decode())["idle"] is True
        time.sleep(1.0)
        host.write(b"\x03")
        host.read_until(b"\x04")
        host.read_until(b"\x04")
        host.read_until(b">")
        elapsed_ms = hub_ticks_ms(host) - before
        assert 700 < elapsed_ms < 2500, f"1 s of wall time at the launcher took {elapsed_ms} ms of hub time"


def test_the_rtc_keeps_the_hosts_time_while_the_hub_waits_at_its_prompt(host):
    """Simulated time stands still at the prompt, but the RTC is the hub's wall clock: set from the
    host's, it must still read the host's time after the hub has waited, or every run log stamped
    after a pause would be set back by it."""
    host_ms = int(time.time() * 1000)
    host.call(f"h.set_rtc({host_ms})")
    time.sleep(1.5)
    out, err = host.exec_raw("from openbricks import log\nprint(log.epoch_ms())")
    assert not err, err
    assert abs(int(out) - int(time.time() * 1000)) < 300


def test_the_rtc_keeps_real_time_when_the_computer_could_not_keep_the_hub_up_with_it(tmp_path):
    """At real-time speed a hub that gets no CPU for a while (a loaded computer; here the process is
    stopped for a second) falls behind in simulated time, but its RTC must not: it is the clock the
    run logs are stamped with."""
    hub = HubProcess(tmp_path / "RobotB", "RobotB")
    link = Host(hub.pty)
    try:
        link.enter_raw()
        link.call(f"h.set_rtc({int(time.time() * 1000)})")
        link.write(b"import time\nfrom openbricks import log\ntime.sleep_ms(2000)\nprint(log.epoch_ms())\x04")
        assert link.read_exactly(2) == b"OK"
        time.sleep(0.5)
        os.kill(hub.proc.pid, signal.SIGSTOP)
        time.sleep(1.0)
        os.kill(hub.proc.pid, signal.SIGCONT)
        out = link.read_until(b"\x04", timeout_s=30)[:-1].decode()
        assert abs(int(out) - int(time.time() * 1000)) < 300
        link.read_until(b"\x04")
    finally:
        link.close()
        assert hub.stop() == 0, hub.stderr()


def test_run_logs_and_the_hub_name_survive_a_restart_of_the_hub(tmp_path):
    first = HubProcess(tmp_path / "RobotB", "RobotB", "--speed", "max")
    try:
        link = Host(first.pty)
        link.enter_raw()
        link.call(f"h.stage({base64.b64encode(b'print(7)').decode()!r}, '/program.py')")
        assert link.call("h.run('/program.py')")["outcome"] == "finished"
        link.close()
    finally:
        assert first.stop() == 0, first.stderr()
    second = HubProcess(tmp_path / "RobotB", "RobotB", "--speed", "max")
    try:
        link = Host(second.pty)
        link.enter_raw()
        assert [run["index"] for run in link.call("h.runs()")["runs"]] == [0]
        assert "7" in link.call("h.read_run(0)")["text"]
        out, _ = link.exec_raw("from openbricks import bluetooth\nprint(bluetooth.hub_name())")
        assert out == "RobotB\r\n"
        link.close()
    finally:
        assert second.stop() == 0, second.stderr()


def test_a_second_hub_on_the_same_directory_is_refused(hub):
    import subprocess
    import sys

    from .hubproc import child_env

    done = subprocess.run(
        [sys.executable, "-m", "openbricks_sim.virtual_hub", "--name", "RobotA", "--dir", hub.directory],
        capture_output=True,
        timeout=60,
        env=child_env(),
        cwd=os.path.dirname(hub.directory),
    )
    assert done.returncode == 2 and b"already running" in done.stderr


def test_a_run_past_its_time_limit_is_stopped_and_logged(tmp_path):
    limited = HubProcess(tmp_path / "RobotC", "RobotC", "--speed", "max", "--run-limit-ms", "500")
    try:
        link = Host(limited.pty)
        link.enter_raw()
        link.call(f"h.stage({base64.b64encode(ENDLESS.encode()).decode()!r}, '/program.py')")
        out, err = link.exec_raw("import openbricks.host_calls as h\nh.run('/program.py')")
        assert result_of(out)["outcome"] == "error"
        assert "RunLimitExceeded" in out
        log = link.call("h.read_run(0)")["text"]
        assert "stopped: RunLimitExceeded: the run passed the virtual hub's limit of 500 ms" in log
        link.close()
    finally:
        assert limited.stop() == 0, limited.stderr()


def test_machine_reset_reboots_into_the_friendly_repl(host):
    host.write(b"import machine\nmachine.reset()\x04")
    assert host.read_exactly(2) == b"OK"
    time.sleep(0.5)
    host.write(b"\r\x03")  # main.py runs again after a hard reset: interrupt it
    banner = host.read_until(b">>> ").decode()
    assert "virtual hub RobotA" in banner


def test_stopping_the_hub_mid_run_ends_the_run_cleanly_and_logs_it(tmp_path):
    running = HubProcess(tmp_path / "RobotD", "RobotD")
    try:
        link = Host(running.pty)
        link.enter_raw()
        program = "import time\nprint('going')\nwhile True:\n    time.sleep_ms(100)\n"
        link.call(f"h.stage({base64.b64encode(program.encode()).decode()!r}, '/program.py')")
        link.write(b"import openbricks.host_calls as h\nh.idle()\x04")
        link.read_until(b'"idle": true}')
        running.control("click")
        link.read_until(b"going\r\n", timeout_s=30)
        time.sleep(0.3)
        with open(f"/proc/{running.proc.pid}/status") as status:
            peak_kb = int(status.read().split("VmHWM:")[1].split()[0])
        assert peak_kb < 120 * 1024, "the product's memory bar for a virtual-hub process"
        link.close()
    finally:
        assert running.stop() == 0, running.stderr()
    with open(tmp_path / "RobotD" / "flash" / "openbricks_logs" / "slot_0.log") as f:
        last = f.read().splitlines()[-1]
    assert last.split(" ", 1)[1].startswith("stopped: HubShutdown: the virtual hub is shutting down after")


def test_a_hub_on_stdio_speaks_the_same_protocol(tmp_path):
    import subprocess
    import sys

    from .hubproc import child_env

    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "openbricks_sim.virtual_hub",
            "--name",
            "Piped",
            "--dir",
            str(tmp_path / "Piped"),
        ],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=child_env(),
        cwd=tmp_path,
    )
    try:
        out, err = proc.communicate(b"\r\x03\r\x01print('piped', 6 * 7)\x04", timeout=60)
    except subprocess.TimeoutExpired:
        proc.kill()
        raise
    assert proc.returncode == 0, err.decode()
    assert b"raw REPL; CTRL-B to exit\r\n>OKpiped 42\r\n\x04\x04>" in out


def test_a_hub_nobody_listens_to_keeps_running_its_program(hub, tmp_path):
    link = Host(hub.pty)
    link.enter_raw()
    program = "for i in range(5000):\n    print('line', i, 'of output nobody reads')\nprint('end')\n"
    link.call(f"h.stage({base64.b64encode(program.encode()).decode()!r}, '/program.py')")
    link.write(b"import openbricks.host_calls as h\nh.idle()\x04")
    link.read_until(b'"idle": true}')
    link.close()  # the host walks away; the pty keeps whatever the hub writes until it is full
    hub.control("click")
    wait_until(lambda: hub.control("status")["runs_started"] == 1, timeout_s=30)
    wait_until(lambda: not hub.control("status")["running"], timeout_s=30)
    with open(flash(hub, "openbricks_logs", "slot_0.log")) as f:
        log = f.read()
    assert "line 0 of output nobody reads" in log and "stopped: finished after" in log


def test_the_friendly_repl_prints_expression_values_and_tracebacks(host):
    host.write(b"\x02")
    assert host.read_until(b">>> ").endswith(
        b"virtual hub RobotA; openbricks virtual hub (simulated) with ESP32S3"
        b'\r\nType "help()" for more information.\r\n>>> '
    )
    host.write(b"6 * 7\r")
    assert host.read_until(b">>> ") == b"6 * 7\r\n42\r\n>>> "
    host.write(b"undefined_name\r")
    assert b"NameError: name 'undefined_name' is not defined\r\n>>> " in host.read_until(b">>> ")


def test_a_deep_hub_directory_still_gets_a_control_socket(tmp_path):
    deep = tmp_path / ("d" * 60) / ("e" * 60) / "RobotE"
    process = HubProcess(deep, "RobotE")
    try:
        status = process.control("status")
        assert status["ok"] and status["control"] == process.control_path
        assert not process.control_path.startswith(str(deep))
    finally:
        assert process.stop() == 0, process.stderr()
    assert not os.path.exists(process.control_path)


def test_a_users_boot_py_and_main_py_on_the_flash_run_at_reset(hub, host):
    host.exec_raw(
        "f = open('/boot.py', 'w')\nf.write('print(\"user boot\")\\n1/0\\n')\nf.close()\n"
        "f = open('/main.py', 'w')\nf.write('print(\"user main\")\\n')\nf.close()"
    )
    host.write(b"import machine\nmachine.reset()\x04")
    assert host.read_exactly(2) == b"OK"
    text = host.read_until(b">>> ").decode()
    assert text.index("user boot") < text.index("ZeroDivisionError") < text.index("user main")
