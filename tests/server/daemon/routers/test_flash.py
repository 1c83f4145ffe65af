"""Flash jobs on a real daemon: twenty boards flashed at once through the API, each job reporting its
progress to 100 % on the event stream and its own result, a bad port failing alone; the CLI's safety
gates as job failures. The boards are virtual hubs (their ptys stand in for USB ports, so the name and
provenance really go through each hub's raw REPL) and esptool is the fake that records its calls."""

from __future__ import annotations

import json
import time
from concurrent.futures import ThreadPoolExecutor

import pytest

from tests.server.commands.conftest import HubProcess
from tests.server.daemon.conftest import start_daemon
from tests.server.flash.images import build_image

pytestmark = pytest.mark.e2e

BOARDS = 20
STARTING_AT_ONCE = 2  # boards booting together (a busy machine is slow to start twenty at once)
JOB_TIMEOUT_S = 180


@pytest.fixture(scope="module")
def boards(tmp_path_factory):
    data = tmp_path_factory.mktemp("boards")
    with ThreadPoolExecutor(STARTING_AT_ONCE) as pool:
        started = list(pool.map(lambda i: HubProcess(f"Board{i:02d}", data), range(1, BOARDS + 1)))
    yield started
    with ThreadPoolExecutor(BOARDS) as pool:
        list(pool.map(HubProcess.stop, started))


@pytest.fixture
def daemon(tmp_path):
    running = start_daemon(tmp_path / "data")
    yield running
    running.stop()


def upload(client, chip="esp32s3", version="2.8.0", filename="firmware.bin") -> str:
    answer = client.post(
        "/api/flash/firmware",
        params={"filename": filename},
        content=build_image(chip, version=version),
        headers={"Content-Type": "application/octet-stream"},
    )
    assert answer.status_code == 200, answer.text
    return answer.json()["firmware_id"]


def wait_jobs(client, jobs) -> dict[str, dict]:
    return {
        job["job_id"]: client.get(
            f"/api/flash/{job['job_id']}", params={"wait_s": JOB_TIMEOUT_S}, timeout=JOB_TIMEOUT_S + 30
        ).json()
        for job in jobs
    }


def test_twenty_boards_flash_at_once_each_with_progress_and_a_result_and_a_bad_port_fails_alone(
    daemon, boards, fake_esptool, monkeypatch, tmp_path
):
    bad_port = boards[0].pty + "-unplugged"
    (tmp_path / "bad").write_text("")
    monkeypatch.setenv("FAKE_ESPTOOL_FAIL_PORT", str(tmp_path / "bad"))
    targets = [{"port": board.pty, "name": f"Robot{i:02d}"} for i, board in enumerate(boards, 1)]
    targets.append({"port": str(tmp_path / "bad"), "name": "NoAnswer"})  # esptool cannot reach it
    targets.append({"port": bad_port, "name": "Unplugged"})  # no such port at all
    progress: dict[str, list[float]] = {}
    with daemon.client() as client, daemon.websocket() as ws:
        ws.recv(timeout=30)  # hello
        firmware = upload(client)
        started_s = time.monotonic()
        answer = client.post("/api/flash", json={"targets": targets, "firmware": firmware})
        assert answer.status_code == 200, answer.text
        jobs = answer.json()["jobs"]
        assert len(jobs) == len(targets) and len({j["batch"] for j in jobs}) == 1
        ended = set()
        while len(ended) < len(jobs):
            event = json.loads(ws.recv(timeout=JOB_TIMEOUT_S))
            data = event["data"]
            if event["type"] == "job_progress":
                progress.setdefault(data["label"], []).append(data["progress"])
            elif event["type"] == "job" and data["state"] in ("done", "failed"):
                ended.add(data["job_id"])
        wall_s = time.monotonic() - started_s
        results = wait_jobs(client, jobs)
    print(f"{BOARDS} boards flashed in {wall_s:.1f} s")
    by_port = {job["label"]: job for job in results.values()}
    for i, board in enumerate(boards, 1):
        job = by_port[board.pty]
        assert job["state"] == "done", job
        assert progress[board.pty][-1] == 100.0 and progress[board.pty] == sorted(progress[board.pty])
        assert job["result"]["hub_name"] == f"Robot{i:02d}" and job["result"]["chip"] == "esp32s3"
        assert job["result"]["provenance"] == "customized" and job["result"]["previous_firmware"]
        assert board.nvs_blob("openbricks", "hub_name") == f"Robot{i:02d}".encode()
    no_answer = by_port[str(tmp_path / "bad")]
    assert no_answer["state"] == "failed" and no_answer["result"] is None
    assert "esptool failed probing the chip on" in no_answer["message"]
    assert "hold BOOT while pressing RESET" in no_answer["message"]
    unplugged = by_port[bad_port]
    assert unplugged["state"] == "failed" and "there is no such port" in unplugged["message"]
    writes = [call for call in fake_esptool.calls() if "write-flash" in call]
    assert len(writes) == BOARDS and all(call[-2] == "0x0" for call in writes)


@pytest.fixture
def fresh_board(tmp_path):
    """A board of its own: the shared ones restart after each flash, and one that does not answer in time
    reads as a blank chip (no version to compare)."""
    board = HubProcess("FreshBoard", tmp_path / "boards")
    yield board
    board.stop()


def test_the_clis_safety_gates_fail_the_job_before_anything_is_written(daemon, fresh_board, fake_esptool):
    board = fresh_board
    with daemon.client() as client:
        same = upload(client, version="2.7.1", filename="openbricks-esp32s3-firmware-2.7.1.bin")
        classic = upload(client, chip="esp32")
        target = [{"port": board.pty, "name": "Robot01"}]
        job = client.post("/api/flash", json={"targets": target, "firmware": same}).json()["jobs"][0]
        job = wait_jobs(client, [job])[job["job_id"]]
        assert job["state"] == "failed"
        assert "2.7.1 is the same version as the firmware on the hub" in job["message"]
        assert "send allow_downgrade: true" in job["message"]
        job = client.post("/api/flash", json={"targets": target, "firmware": classic}).json()["jobs"][0]
        job = wait_jobs(client, [job])[job["job_id"]]
        assert job["state"] == "failed" and "is built for esp32 but the board on" in job["message"]
        assert "write-flash" not in fake_esptool.commands()
        body = {"targets": target, "firmware": same, "allow_downgrade": True}
        job = client.post("/api/flash", json=body).json()["jobs"][0]
        assert wait_jobs(client, [job])[job["job_id"]]["state"] == "done"
        assert fake_esptool.commands()[-2:] == ["erase-flash", "write-flash"]


def test_bad_requests_start_nothing(daemon, boards, viewer_token, tmp_path, monkeypatch):
    board = boards[0].pty
    monkeypatch.setenv("OPENBRICKS_CACHE_DIR", str(tmp_path / "cache"))  # no release cached ...
    monkeypatch.delenv("OPENBRICKS_RELEASES_URL", raising=False)  # ... and none to fetch
    cases = [
        ({"targets": []}, 422, "invalid_request"),
        ({"targets": [{"port": board}]}, 422, "name_required"),
        ({"targets": [{"port": board, "name": "x" * 30}]}, 422, "bad_name"),
        ({"targets": [{"port": board, "name": "A"}, {"port": board, "name": "B"}]}, 422, "duplicate_port"),
        ({"targets": [{"port": board, "name": "A"}, {"port": "/dev/x", "name": "A"}]}, 422, "duplicate_name"),
        ({"targets": [{"port": board, "name": "A"}], "firmware": "0123456789abcdef"}, 404, "not_found"),
        ({"targets": [{"hub": "nope", "name": "A"}]}, 422, "bad_target"),
        ({"targets": [{"port": board, "name": "A"}]}, 409, "no_firmware"),  # no image, no release
    ]
    with daemon.client() as client:
        for body, status, error in cases:
            answer = client.post("/api/flash", json=body)
            assert answer.status_code == status and answer.json()["error"] == error, (body, answer.text)
        assert (
            "a Bluetooth advertisement carries at most 26" in client.post("/api/flash", json=cases[2][0]).text
        )
        started_s = time.monotonic()
        no_image = client.post("/api/flash", json=cases[-1][0]).json()
        assert time.monotonic() - started_s < 1  # refused at once, not after a wait on the network
        assert no_image["message"].startswith("no firmware image: upload one (POST /api/flash/firmware")
        assert "firmware/build_firmware.sh" in no_image["message"]
        refused = client.post(
            "/api/flash/firmware",
            content=b"MZ not firmware",
            headers={"Content-Type": "application/octet-stream"},
        )
        assert refused.status_code == 422 and "is not an ESP32 firmware image" in refused.json()["message"]
        assert client.get("/api/flash").json() == []
    with daemon.client(viewer_token) as viewer:
        refused = viewer.post("/api/flash", json={"targets": [{"port": board, "name": "A"}]})
        assert refused.status_code == 403 and refused.json()["error"] == "operator_required"


@pytest.fixture
def viewer_token(daemon):
    return daemon.ctx.store.tokens.mint("viewer", "mentor")


def test_a_usb_hub_the_console_holds_shows_flashing_and_comes_back_under_its_new_name(
    tmp_path, boards, fake_esptool
):
    board = boards[1]
    daemon = start_daemon(tmp_path / "data", serial_ports=(board.pty,))
    try:
        with daemon.client() as client:
            hub_id = f"serial:{board.pty.removeprefix('/dev/').replace('/', '-')}"
            wait_status(client, hub_id, "idle")
            ports = client.get("/api/serial/ports").json()["ports"]
            assert {"port": board.pty, "hub_id": hub_id} in [
                {"port": p["port"], "hub_id": p["hub_id"]} for p in ports
            ]
            with daemon.websocket() as ws:
                ws.recv(timeout=30)
                body = {"targets": [{"hub": hub_id, "name": "RobotZ"}], "allow_downgrade": True}
                body["firmware"] = upload(client)
                job = client.post("/api/flash", json=body).json()["jobs"][0]
                seen = []
                while "flashing" not in seen:
                    event = json.loads(ws.recv(timeout=60))
                    if event["type"] == "hub" and event["hub"] == hub_id:
                        seen.append(event["data"]["status"])
                        holder = event["data"]["holder"]
                busy = client.post(f"/api/hubs/{hub_id}/identify", json={})
                assert busy.status_code == 409 and "flash by local" in busy.json()["message"]
                assert holder["operation"] == "flash"
            done = wait_jobs(client, [job])[job["job_id"]]
            assert done["state"] == "done" and done["result"]["hub_name"] == "RobotZ", done
            hub = wait_status(client, hub_id, "idle")
            assert hub["name"] == "RobotZ"
            assert client.get("/api/serial/ports").json()["ports"][0]["chip"] == "esp32s3"
    finally:
        daemon.stop()


def wait_status(client, hub_id, status, timeout_s=60):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        hub = client.get(f"/api/hubs/{hub_id}").json()
        if hub["status"] == status:
            return hub
        time.sleep(0.1)
    raise AssertionError(f"{hub_id} is {hub['status']}, not {status}: {hub}")


def test_probing_asks_esptool_for_each_ports_chip_at_once(daemon, boards, fake_esptool, tmp_path):
    with daemon.client() as client:
        ports = [boards[2].pty, boards[3].pty, str(tmp_path / "ttyUSB9")]
        probed = client.post("/api/serial/probe", json={"ports": ports})
        assert probed.status_code == 200, probed.text
        found = {p["port"]: (p["chip"], p["error"]) for p in probed.json()["ports"]}
        assert found[boards[2].pty] == ("esp32s3", None) and found[boards[3].pty] == ("esp32s3", None)
        assert found[ports[2]][0] is None and "there is no such port" in found[ports[2]][1]
    assert fake_esptool.commands() == ["chip-id", "chip-id"]
