"""Virtual hubs are found by name in the user data dir; dead ones are ignored."""

import fcntl
import json
import socket
import threading

import pytest

from openbricks_server.link import discovery
from openbricks_server.paths import virtual_hubs_dir


@pytest.fixture(autouse=True)
def data_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("OPENBRICKS_DATA_DIR", str(tmp_path))
    return tmp_path


def fake_hub(folder, name, pty, hold_lock=True):
    """A folder laid out as a running virtual hub: a held lock and a control socket answering status."""
    folder.mkdir(parents=True)
    lock = open(folder / discovery.LOCK_FILE, "a+")  # noqa: SIM115 - held while the fake hub "runs"
    if hold_lock:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    server.bind(str(folder / discovery.CONTROL_SOCKET))
    server.listen()

    def serve():
        while True:
            try:
                conn, _ = server.accept()
            except OSError:
                return
            with conn:
                conn.recv(4096)
                reply = {"ok": True, "name": name, "pty": pty, "running": False}
                conn.sendall(json.dumps(reply).encode() + b"\n")

    threading.Thread(target=serve, daemon=True).start()
    return lock, server


def test_live_hubs_are_found_and_stale_folders_ignored(data_dir):
    root = virtual_hubs_dir()
    held = [
        fake_hub(root / "RobotA", "RobotA", "/dev/pts/7"),
        fake_hub(root / "Gone", "Gone", "/dev/pts/8", False),
    ]
    (root / "Empty").mkdir()
    try:
        assert [hub.name for hub in discovery.virtual_hubs()] == ["RobotA"]
        assert discovery.find_virtual_hub("RobotA").pty == "/dev/pts/7"
        assert discovery.find_virtual_hub("Gone") is None
    finally:
        for lock, server in held:
            lock.close()
            server.close()


def test_the_registry_is_where_the_simulator_puts_its_hubs(data_dir):
    from openbricks_sim.virtual_hub.__main__ import hubs_dir

    assert str(virtual_hubs_dir()) == hubs_dir()


def test_the_file_names_match_the_simulators():
    from openbricks_sim.virtual_hub import control, hub

    assert (discovery.LOCK_FILE, discovery.CONTROL_SOCKET) == (hub.LOCK_FILE, control.SOCKET_NAME)
