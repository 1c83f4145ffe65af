"""set_hub_name: the flasher names the hub through a host call and verifies it by read-back."""

import json

from openbricks import bluetooth, host_calls


class _Console:
    def __init__(self):
        self.lines = []
        host_calls.print = self

    def __call__(self, *args, **kwargs):
        self.lines.append(" ".join([str(a) for a in args]))

    def results(self):
        marker = host_calls.FRAME_PREFIX + "- result "
        return [json.loads(line[len(marker) :]) for line in self.lines if line.startswith(marker)]

    def close(self):
        del host_calls.print


def test_the_name_is_stored_in_nvs_and_read_back():
    console = _Console()
    try:
        host_calls.set_hub_name("RobotA")
        assert console.results() == [{"ok": True, "hub_name": "RobotA"}]
        assert bluetooth.hub_name() == "RobotA"
    finally:
        console.close()


def test_empty_or_oversized_names_are_refused_and_nothing_changes():
    console = _Console()
    try:
        host_calls.set_hub_name("Before")
        host_calls.set_hub_name("")
        host_calls.set_hub_name("x" * 27)
        failures = console.results()[1:]
        assert [r["ok"] for r in failures] == [False, False]
        assert "1..26 bytes" in failures[1]["error"]
        assert bluetooth.hub_name() == "Before"
    finally:
        console.close()
