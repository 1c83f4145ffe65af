"""Virtual hubs are found by name in the user data dir; dead ones are ignored."""

import fcntl
import json
import os
import socket
import tempfile
import threading
from pathlib import Path

import pytest

from openbricks_server.link import discovery
from openbricks_server.paths import virtual_hubs_dir


@pytest.fixture(autouse=True)
def data_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("OPENBRICKS_DATA_DIR", str(tmp_path))
    return tmp_path


def fake_hub(folder, name, pty, hold_lock=True, socket_path=None):
    """A folder laid out as a running virtual hub: a held lock (with this pid in it) and a control
    socket answering status, at `socket_path` when given (as for a deep folder), else in the folder."""
    folder.mkdir(parents=True)
    lock = open(folder / discovery.LOCK_FILE, "a+")  # noqa: SIM115 - held while the fake hub "runs"
    if hold_lock:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    lock.write(f"{os.getpid()}\n")
    lock.flush()
    server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    server.bind(str(socket_path or folder / discovery.CONTROL_SOCKET))
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


def endpoint_record(folder, socket_path, pid):
    record = {"format": 1, "name": folder.name, "pid": pid, "pty": "/dev/pts/9", "control": str(socket_path)}
    (folder / discovery.ENDPOINT_FILE).write_text(json.dumps(record))


def test_a_hub_in_a_data_dir_too_deep_for_a_socket_is_found_through_its_endpoint_record(
    data_dir, monkeypatch
):
    deep = data_dir / ("d" * 60) / ("e" * 60)
    monkeypatch.setenv("OPENBRICKS_DATA_DIR", str(deep))
    folder = virtual_hubs_dir() / "DeepBot"
    assert len(str(folder / discovery.CONTROL_SOCKET)) > 108  # no Unix socket can live there
    elsewhere = Path(tempfile.mkdtemp(prefix="ob-test-vhub-")) / "control.sock"
    lock, server = fake_hub(folder, "DeepBot", "/dev/pts/9", socket_path=elsewhere)
    try:
        endpoint_record(folder, elsewhere, os.getpid())
        found = discovery.find_virtual_hub("DeepBot")
        assert found is not None and found.pty == "/dev/pts/9" and found.control_socket == elsewhere
    finally:
        lock.close()
        server.close()
        elsewhere.unlink()
        elsewhere.parent.rmdir()


def test_a_record_left_by_a_killed_hub_is_not_followed(data_dir):
    folder = virtual_hubs_dir() / "RobotB"
    lock, server = fake_hub(folder, "RobotB", "/dev/pts/5")
    try:
        endpoint_record(folder, folder / discovery.CONTROL_SOCKET, os.getpid() + 1)  # not the lock holder
        assert discovery.find_virtual_hub("RobotB") is None
        endpoint_record(folder, folder / discovery.CONTROL_SOCKET, os.getpid())
        assert discovery.find_virtual_hub("RobotB").pty == "/dev/pts/5"
    finally:
        lock.close()
        server.close()


def test_the_registry_is_where_the_simulator_puts_its_hubs(data_dir):
    from openbricks_sim.virtual_hub.__main__ import hubs_dir

    assert str(virtual_hubs_dir()) == hubs_dir()
