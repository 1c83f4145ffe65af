"""The addresses the Share page builds links from: only names the console answers to (its Host check)."""

from __future__ import annotations

from openbricks_server.daemon.config import DaemonConfig
from openbricks_server.daemon.network import lan_addresses, room_command, share_bases

LAN = ["192.168.1.20", "10.0.0.5"]


def test_a_console_on_this_computer_only_offers_no_address_and_says_how_to_open_it_to_the_room():
    config = DaemonConfig()
    assert share_bases(config, LAN) == []
    assert room_command(config, LAN) == "openbricks console --host 0.0.0.0 --allow-host 192.168.1.20"
    elsewhere = room_command(DaemonConfig(port=9000), [])
    assert elsewhere.endswith("--allow-host THIS-COMPUTERS-ADDRESS --port 9000")


def test_on_every_address_only_the_allowed_names_are_offered():
    config = DaemonConfig(host="0.0.0.0", allowed_hosts=("192.168.1.20", "Laptop.local", "localhost"))
    assert share_bases(config, LAN) == ["http://192.168.1.20:8765", "http://laptop.local:8765"]
    assert share_bases(DaemonConfig(host="0.0.0.0"), LAN) == []  # it answers to none of them


def test_on_one_address_that_address_is_offered():
    assert share_bases(DaemonConfig(host="192.168.1.20", port=9000), LAN) == ["http://192.168.1.20:9000"]
    assert share_bases(DaemonConfig(host="fd00::7"), LAN) == ["http://[fd00::7]:8765"]


def test_this_computers_addresses_leave_out_loopback():
    assert all(not a.startswith("127.") for a in lan_addresses())
