"""A hub's REPL over the API, on a real virtual hub: an expression shows its value, names stay for the
next entry, a traceback is an answer, a viewer is refused and a busy hub names its holder."""

from __future__ import annotations

import pytest

from openbricks_server.daemon.hubs.actor import repl_source
from tests.server.daemon.routers.test_hubs import ENDLESS, start_daemon, wait_idle


def test_an_expression_prints_its_value_and_statements_run_as_written():
    assert repl_source("1+1") == "_ = (1+1\n)\nif _ is not None:\n    print(repr(_))\n"
    assert repl_source("x = 5") == "x = 5"
    assert (
        repl_source("print(1) # note") == "_ = (print(1) # note\n)\nif _ is not None:\n    print(repr(_))\n"
    )
    assert repl_source("if x\n") == "if x\n"  # the hub reports the syntax error in its own words


@pytest.mark.e2e
def test_the_repl_evaluates_on_a_virtual_hub_one_holder_at_a_time(tmp_path):
    daemon = start_daemon(tmp_path / "data", virtual=1)
    try:
        with daemon.client() as api, daemon.client(daemon.ctx.store.tokens.mint("viewer", "m")) as viewer:
            wait_idle(api, ["SimHub-1"])
            assert api.post("/api/hubs/SimHub-1/repl", json={"code": "1+1"}).json() == {
                "hub_id": "virtual:SimHub-1",
                "output": "2\n",
                "error": None,
            }
            assert api.post("/api/hubs/SimHub-1/repl", json={"code": "x = 20"}).json()["output"] == ""
            assert api.post("/api/hubs/SimHub-1/repl", json={"code": "x + 1"}).json()["output"] == "21\n"
            failed = api.post("/api/hubs/SimHub-1/repl", json={"code": "1/0"}).json()
            assert failed["error"].startswith("Traceback") and "ZeroDivisionError" in failed["error"]
            assert viewer.post("/api/hubs/SimHub-1/repl", json={"code": "1"}).status_code == 403
            assert api.post("/api/hubs/SimHub-1/repl", json={"code": ""}).status_code == 422
            api.post("/api/hubs/SimHub-1/run", json={"source": ENDLESS})
            busy = api.post("/api/hubs/SimHub-1/repl", json={"code": "1+1"})
            assert busy.status_code == 409 and busy.json()["detail"]["holder"]["operation"] == "run"
            api.post("/api/hubs/SimHub-1/stop")
    finally:
        daemon.stop()
