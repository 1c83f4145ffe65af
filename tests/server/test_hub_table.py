"""`openbricks list` prints the same rows whether it scanned itself or asked the console."""

import json

from openbricks_server.hub_table import HubRow, print_hubs


def test_rows_line_up_as_text_and_keep_their_keys_as_json(capsys):
    rows = [HubRow("RobotA", "virtual", "/dev/pts/4", "idle"), HubRow("Hub-B", "hub", "AA:BB", "-61 dBm")]
    print_hubs(rows, as_json=False, none_found="none")
    assert capsys.readouterr().out.splitlines() == [
        "RobotA  virtual  /dev/pts/4  idle",
        "Hub-B   hub      AA:BB       -61 dBm",
    ]
    print_hubs(rows, as_json=True, none_found="none")
    assert json.loads(capsys.readouterr().out)[1] == {
        "name": "Hub-B",
        "kind": "hub",
        "address": "AA:BB",
        "status": "-61 dBm",
    }


def test_no_hubs_says_so_on_stderr_and_json_stays_parseable(capsys):
    print_hubs([], as_json=True, none_found="no hubs found")
    out, err = capsys.readouterr()
    assert json.loads(out) == [] and err == "no hubs found\n"
