"""Servo-ID through the console: through a virtual hub the daemon holds (its simulated bus carries the
robot's two ST-3032 servos, ids 1 and 2) and through a USB adapter (fake servos behind a pty), with
`openbricks servo-id`'s rules and words; every scan and re-ID is a job in the history."""

from __future__ import annotations

import pytest

from openbricks_server.daemon.config import DaemonConfig
from tests.server.daemon.conftest import Daemon, start_daemon
from tests.server.daemon.routers.test_hubs import ENDLESS, wait_idle
from tests.server.servo_rig import ServoRig

pytestmark = pytest.mark.e2e

# A full scan pings 254 ids (a few seconds); a loaded machine can take several times that.
SERVO_REQUEST_TIMEOUT_S = 180
USB_ANSWER_S = 0.04  # per servo answer: the fake servos' thread answers late on a loaded machine


@pytest.fixture
def hub_daemon(tmp_path, monkeypatch):
    monkeypatch.setenv("OPENBRICKS_DATA_DIR", str(tmp_path / "data"))
    running = Daemon(DaemonConfig(host="127.0.0.1", port=0, virtual=1, ble=False, data_dir=tmp_path / "data"))
    yield running
    running.stop()


def test_scan_and_re_id_through_a_hub_with_the_clis_rules_and_words(hub_daemon):
    with hub_daemon.client() as api:
        api.timeout = SERVO_REQUEST_TIMEOUT_S
        wait_idle(api, ["SimHub-1"])
        scan = api.post("/api/servos/scan", json={"hub": "SimHub-1"})
        assert scan.status_code == 200, scan.text
        assert scan.json()["ids"] == [1, 2]
        assert scan.json()["message"] == "servo ids on SimHub-1's servo bus: 1, 2"
        guess = api.post("/api/servos/set-id", json={"hub": "SimHub-1", "new_id": 7})
        assert guess.status_code == 422 and guess.json()["error"] == "servo_refused"
        assert "2 servos answer (ids 1, 2): pass old_id to say which one" in guess.json()["message"]
        taken = api.post("/api/servos/set-id", json={"hub": "SimHub-1", "new_id": 1, "old_id": 2})
        assert taken.status_code == 422 and "id 1 is already taken" in taken.json()["message"]
        wrong = api.post("/api/servos/set-id", json={"hub": "SimHub-1", "new_id": 300, "old_id": 2})
        assert wrong.status_code == 422 and "new id 300: servo bus ids are 0..253" in wrong.json()["message"]
        done = api.post("/api/servos/set-id", json={"hub": "SimHub-1", "new_id": 7, "old_id": 2})
        assert done.status_code == 200, done.text
        assert (
            done.json()["message"] == "servo 2 is now id 7 (read back from the servo); ids on the bus: 1, 7"
        )
        assert (done.json()["changed"], done.json()["ids"]) == (True, [1, 7])
        assert api.post("/api/servos/scan", json={"hub": "virtual:SimHub-1"}).json()["ids"] == [1, 7]
        jobs = api.get("/api/jobs").json()
        assert [(j["kind"], j["state"]) for j in jobs] == [
            ("servo_scan", "done"),
            ("servo_set_id", "done"),
            ("servo_set_id", "failed"),
            ("servo_set_id", "failed"),
            ("servo_scan", "done"),
        ]  # the id out of range was refused before any job began
        assert jobs[1]["result"]["message"].startswith("servo 2 is now id 7") and jobs[1]["who"] == "local"
        assert "pass old_id" in jobs[3]["message"]
        # the hub is one operation at a time: a scan while a program runs is refused, naming the holder
        assert api.post("/api/hubs/SimHub-1/run", json={"source": ENDLESS}).status_code == 200
        busy = api.post("/api/servos/scan", json={"hub": "SimHub-1"})
        assert busy.status_code == 409 and "SimHub-1 is busy: run by local" in busy.json()["message"]
        api.post("/api/hubs/SimHub-1/stop")


def test_scan_and_re_id_over_a_usb_adapter_that_hears_its_own_requests(tmp_path):
    rig = ServoRig([3], echo=True)
    daemon = start_daemon(tmp_path / "data")
    try:
        with daemon.client() as api:
            api.timeout = SERVO_REQUEST_TIMEOUT_S
            scan = api.post("/api/servos/scan", json={"port": rig.port, "timeout_s": USB_ANSWER_S})
            assert scan.status_code == 200, scan.text
            assert scan.json()["message"] == f"servo ids on the bus on {rig.port}: 3"
            done = api.post(
                "/api/servos/set-id", json={"port": rig.port, "new_id": 12, "timeout_s": USB_ANSWER_S}
            ).json()
            assert done["message"] == "servo 3 is now id 12 (read back from the servo); ids on the bus: 12"
            assert rig.ids() == [12]
            same = api.post(
                "/api/servos/set-id", json={"port": rig.port, "new_id": 12, "timeout_s": USB_ANSWER_S}
            ).json()
            assert same["message"] == "servo 12 already has id 12; nothing to change"
            missing = api.post("/api/servos/scan", json={"port": str(tmp_path / "ttyUSB9")})
            assert missing.status_code == 422 and "cannot open" in missing.json()["message"]
            both = api.post("/api/servos/scan", json={"port": rig.port, "hub": "SimHub-1"})
            assert both.status_code == 422 and "give either `hub`" in both.json()["message"]
    finally:
        daemon.stop()
        rig.close()
