"""A host that stays connected (the console daemon) watching runs: run starts and button-run ends
announced with the daemon's nonce and the log's key, plot() samples tagged, lookalikes left alone,
and `identify` blinking the status LED."""

import json
import time

import esp32
import machine

from fakes import clock, tmpdir
from openbricks import bluetooth, bluetooth_button, host_calls, launcher, log, tools
from openbricks.bluetooth_button import BluetoothToggleButton
from openbricks.hub import NeoPixelLED, PushButton

NONCE = "5eed1234"
BUTTON = 39


class _Console:
    """What host_calls and the program print, as the host reads it off the link."""

    def __init__(self):
        self.lines = []
        host_calls.print = self
        tools.print = self

    def __call__(self, *args, **kwargs):
        self.lines.append(" ".join([str(a) for a in args]))

    def frames(self, kind):
        prefix = "@openbricks:" + NONCE + " " + kind + " "
        return [json.loads(line[len(prefix) :]) for line in self.lines if line.startswith(prefix)]

    def close(self):
        del host_calls.print
        del tools.print


def _stage(directory, source):
    path = directory + "/program.py"
    with open(path, "w") as f:
        f.write(source)
    return path


def _header_stamp(log_dir, index):
    return int(log.read_run(index, log_dir).split(" ", 1)[0])


def test_a_watched_run_announces_its_log_key_and_tags_its_plot_samples():
    with tmpdir.scratch() as directory:
        source = (
            "from openbricks.tools import plot\n"
            'print(\'@openbricks:%s plot {"name": "forged", "value": 1}\')\n'
            "plot('speed', 12.5)\n" % "0000"
        )
        path = _stage(directory, source)
        launcher.get(program_path=path, log_dir=directory + "/logs")
        console = _Console()
        try:
            result = host_calls.run(watch=NONCE)
        finally:
            console.close()
        assert result["ok"] and result["outcome"] == "finished", (result, console.lines)
        (begin,) = console.frames("run-begin")
        assert begin == {"run": 0, "slot": 0, "started_ms": _header_stamp(directory + "/logs", 0)}
        assert console.frames("plot") == [{"name": "speed", "value": 12.5}]
        assert tools._plot_tag[0] is None  # the tag ends with the watched run


def test_an_unwatched_plot_prints_a_plain_readable_line():
    console = _Console()
    try:
        tools.plot("speed", 3)
    finally:
        console.close()
    assert console.lines == ["plot: speed = 3"]


def test_plot_refuses_what_cannot_be_a_sample():
    for name, value in (("", 1), ("a\nb", 1), ("x" * 41, 1), ("ok", "1"), ("ok", True), ("ok", float("nan"))):
        try:
            tools.plot(name, value)
        except (TypeError, ValueError):
            continue
        raise AssertionError("plot(%r, %r) was accepted" % (name, value))


def test_a_bad_watch_nonce_is_refused_before_anything_runs():
    result = host_calls.run(watch="no spaces")
    assert not result["ok"] and "watch=" in result["error"]


def test_a_watched_idle_hub_announces_a_button_run_from_begin_to_its_outcome():
    with tmpdir.scratch() as directory:
        path = _stage(directory, "print('lap')\n")
        hub = launcher.Launcher(BUTTON, path, log_dir=directory + "/logs")
        hub.start_watcher(0)
        watch = host_calls._Watch(NONCE)
        console = _Console()
        clock.after_ms(100, lambda: machine.board.set_input(BUTTON, 0))
        clock.after_ms(250, lambda: machine.board.set_input(BUTTON, 1))
        try:
            with watch:
                launcher._launcher[0] = hub
                hub.idle(1500, on_run_end=watch.on_run_end)
        finally:
            console.close()
        (begin,) = console.frames("run-begin")
        assert begin["run"] == 0 and begin["started_ms"] == _header_stamp(directory + "/logs", 0)
        assert console.frames("run-end") == [{"run": 0, "outcome": "finished"}]


def test_identify_blinks_the_status_led_then_gives_it_back():
    nvs = esp32.NVS("openbricks")
    nvs.set_blob("hub_name", b"RobotA")
    nvs.commit()
    bluetooth.apply_persisted_state()
    BluetoothToggleButton(PushButton(38), led=NeoPixelLED(48, brightness=1.0)).start()
    result = host_calls.identify(1000)
    assert result["ok"] and result["identify_ms"] == 1000
    seen = set()
    for _ in range(18):
        time.sleep_ms(50)
        frames = [data for pin, _timing, data in machine.board.bitstreams if pin == 48]
        seen.add(tuple(frames[-1][:3]))
    assert seen == {(255, 255, 255), (0, 0, 0)}
    time.sleep_ms(300)
    frames = [data for pin, _timing, data in machine.board.bitstreams if pin == 48]
    assert tuple(frames[-1][:3]) == (0, 0, 255)  # GRB of blue: the hub's state again


def test_identify_without_a_status_led_says_so():
    bluetooth_button.reset_state()
    result = host_calls.identify(1000)
    assert not result["ok"] and "no status LED" in result["error"]
    assert not host_calls.identify(0)["ok"]


def test_a_watched_run_sends_each_lines_log_stamp_before_it_and_never_inside_a_line():
    with tmpdir.scratch() as directory:
        source = (
            "import time\n"
            "print('half', end='')\n"
            "time.sleep(0.003)\n"
            "print(' whole')\n"
            "for i in range(3):\n"
            "    print('line', i)\n"
            "    time.sleep(0.003)\n"
            "print('two\\nlines')\n"
        )
        path = _stage(directory, source)
        launcher.get(program_path=path, log_dir=directory + "/logs")
        shown = []
        console = _Console()
        saved = log.console_print
        log.console_print = lambda *args, end="\n", **kw: shown.append(" ".join([str(a) for a in args]) + end)
        try:
            result = host_calls.run(watch=NONCE)
        finally:
            log.console_print = saved
            console.close()
        assert result["ok"] and result["outcome"] == "finished", result
        (begin,) = console.frames("run-begin")
        # The console as the host reads it: a stamp frame sets the stamp of the lines after it.
        frame = "@openbricks:" + NONCE + " t "
        live, stamp = [], None
        for line in "".join(shown).split("\n")[:-1]:
            assert frame not in line or line.startswith(frame), line  # never inside a line
            if line.startswith(frame):
                stamp = begin["started_ms"] + int(line[len(frame) :])
            else:
                live.append((stamp, line))
        kept = []
        framing = ("-- run_", "started: ", "watched: ", "stopped: ")
        for line in log.read_run(0, directory + "/logs").split("\n")[:-1]:
            ms, _, text = line.partition(" ")
            if not any(text.startswith(f) for f in framing):
                kept.append((int(ms), text))
        assert [text for _, text in live] == ["half whole", "line 0", "line 1", "line 2", "two", "lines"]
        assert live == kept
        assert log._stamp_tag[0] is None  # stamps go to the console only while watched
