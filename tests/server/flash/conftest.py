import json
import stat
import sys
from pathlib import Path

import pytest


class FakeEsptool:
    def __init__(self, log: Path):
        self.log = log

    def calls(self) -> list[list[str]]:
        if not self.log.exists():
            return []
        return [json.loads(line) for line in self.log.read_text().splitlines()]

    def commands(self) -> list[str]:
        return [next(a for a in call if a.endswith("-flash") or a == "chip-id") for call in self.calls()]


@pytest.fixture
def fake_esptool(tmp_path, monkeypatch):
    script = tmp_path / "esptool"
    script.write_text(
        f'#!/bin/sh\nexec "{sys.executable}" "{Path(__file__).with_name("fake_esptool.py")}" "$@"\n'
    )
    script.chmod(script.stat().st_mode | stat.S_IXUSR)
    log = tmp_path / "esptool-calls.jsonl"
    monkeypatch.setenv("OPENBRICKS_ESPTOOL", str(script))
    monkeypatch.setenv("FAKE_ESPTOOL_LOG", str(log))
    return FakeEsptool(log)
