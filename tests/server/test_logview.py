"""Run-log stamps become local times; lines split across chunks come out whole."""

import json
import os
import time

import pytest

from openbricks_server.logview import LogRenderer, local_time, print_runs, render_line


@pytest.fixture
def tokyo(monkeypatch):
    monkeypatch.setenv("TZ", "Asia/Tokyo")
    time.tzset()
    yield
    monkeypatch.delenv("TZ")
    time.tzset()


def test_epoch_ms_is_shown_in_the_local_zone_with_milliseconds(tokyo):
    assert local_time(1783950123456) == "2026-07-13 22:42:03.456"
    assert render_line("1783950123456 ambient: 33") == "[2026-07-13 22:42:03.456] ambient: 33"


def test_unstamped_lines_pass_through(tokyo):
    assert render_line('  File "main.py", line 3') == '  File "main.py", line 3'


def test_a_line_split_across_chunks_is_rendered_once_whole(tokyo):
    out = []
    renderer = LogRenderer(out.append)
    for chunk in ["1783950123456 hel", "lo\r\n17839501", "24000 world\n1783950125000 no newline at the end"]:
        renderer.feed(chunk)
    assert out == ["[2026-07-13 22:42:03.456] hello\n", "[2026-07-13 22:42:04.000] world\n"]
    renderer.finish()
    assert out[-1] == "[2026-07-13 22:42:05.000] no newline at the end\n"
    assert os.environ["TZ"] == "Asia/Tokyo"


def test_a_run_listing_as_json_has_stable_keys(capsys):
    print_runs("RobotA", [{"index": 3, "bytes": 120, "extra": 1}], as_json=True)
    assert json.loads(capsys.readouterr().out) == [{"index": 3, "bytes": 120}]
    print_runs("RobotA", [], as_json=True)
    assert json.loads(capsys.readouterr().out) == []
    print_runs("RobotA", [], as_json=False)
    assert capsys.readouterr().out == "RobotA has no run logs yet\n"
