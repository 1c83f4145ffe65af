"""Who may talk to the console: the sign-in cookie, Bearer tokens, Host and Origin checks, roles (walked
over the whole OpenAPI schema), the audit log, and the refusal to listen on a network without tokens."""

import json
import os
import re
import subprocess
import sys

import httpx
import pytest
from websockets.exceptions import InvalidStatus

from openbricks_server.daemon.routers.events import COMMANDS
from openbricks_server.daemon.routers.pages import INDEX

MUTATING = {"post", "put", "patch", "delete"}


def test_the_printed_url_is_traded_for_an_httponly_strict_cookie_and_a_clean_url(daemon):
    with httpx.Client(base_url=daemon.url) as browser:
        signed = browser.get(f"/?token={daemon.token}", follow_redirects=False)
        assert signed.status_code == 303 and signed.headers["location"] == "/"
        cookie = signed.headers["set-cookie"]
        assert "HttpOnly" in cookie and "SameSite=Strict" in cookie and daemon.token in cookie
        page = browser.get("/")
        if INDEX.is_file():  # the browser console, built by `make web`, with its assets
            assert 'id="app"' in page.text
            asset = re.search(r'src="\./(assets/[^"]+)"', page.text).group(1)
            assert browser.get(f"/{asset}").status_code == 200
            assert httpx.get(f"{daemon.url}/{asset}").status_code == 401  # not without signing in
        else:
            assert "Signed in as <b>local</b> (operator)" in page.text
        me = browser.get("/api/auth/me").json()
        assert me == {"label": "local", "role": "operator", "via": "cookie"}
        kept = browser.get(f"/docs?token={daemon.token}&x=1", follow_redirects=False)
        assert kept.headers["location"] == "/docs?x=1"


def test_without_a_token_only_the_sign_in_page_answers(daemon):
    with httpx.Client(base_url=daemon.url) as anonymous:
        assert "Not signed in" in anonymous.get("/").text
        for path in ("/api/runs", "/docs", "/openapi.json", "/api/nope"):
            refused = anonymous.get(path)
            assert refused.status_code == 401 and refused.json()["error"] == "unauthorized", path
        wrong = anonymous.get("/?token=not-the-token", follow_redirects=False)
        assert wrong.status_code == 401 and wrong.json()["error"] == "bad_token"
        assert anonymous.get("/api/runs", headers={"Authorization": "Bearer nope"}).status_code == 401


def test_a_browser_with_a_bad_token_gets_a_page_to_read_not_json(daemon):
    """A student opening an old link sees what happened and what to do; scripts keep the JSON."""
    html = {"Accept": "text/html,application/xhtml+xml,*/*;q=0.8"}
    with httpx.Client(base_url=daemon.url, headers=html) as browser:
        wrong = browser.get("/?token=expired-or-mistyped", follow_redirects=False)
        assert wrong.status_code == 401 and wrong.headers["content-type"].startswith("text/html")
        assert "The token in this URL is not valid" in wrong.text and "/?token=" in wrong.text
        assert '"error"' not in wrong.text
        # The page's own API calls (and scripts) still get the one error shape.
        assert browser.get("/api/runs").json()["error"] == "unauthorized"


def test_bearer_tokens_work_for_scripts(daemon, viewer):
    assert viewer.get("/api/auth/me").json() == {"label": "mentor", "role": "viewer", "via": "bearer"}


@pytest.mark.parametrize("host", ["evil.example", "127.0.0.1.nip.io", "attacker:8765", ""])
def test_a_request_for_another_host_name_is_refused(daemon, host):
    with daemon.client() as client:
        refused = client.get("/api/system/health", headers={"Host": host})
    assert refused.status_code == 403 and refused.json()["error"] == "host_not_allowed"


@pytest.mark.parametrize("host", ["localhost", "127.0.0.1", "LOCALHOST"])
def test_loopback_names_are_allowed(daemon, host):
    with daemon.client() as client:
        assert client.get("/api/system/health", headers={"Host": f"{host}:{daemon.config.port}"}).is_success


def test_a_foreign_origin_cannot_change_anything(daemon):
    with httpx.Client(base_url=daemon.url) as browser:
        browser.get(f"/?token={daemon.token}")
        body = {"source": "print(1)\n"}
        foreign = browser.put("/api/programs/a.py", json=body, headers={"Origin": "http://evil.example"})
        assert foreign.status_code == 403 and foreign.json()["error"] == "origin_not_allowed"
        missing = browser.put("/api/programs/a.py", json=body)
        assert missing.status_code == 403 and missing.json()["error"] == "origin_required"
        own = browser.put("/api/programs/a.py", json=body, headers={"Origin": daemon.url})
        assert own.status_code == 200
        assert browser.get("/api/programs", headers={"Origin": "http://evil.example"}).is_success  # reads
    with daemon.client() as script:
        assert script.put("/api/programs/b.py", json=body).status_code == 200  # Bearer, no Origin
        foreign = script.put("/api/programs/b.py", json=body, headers={"Origin": "http://evil.example"})
        assert foreign.status_code == 403


def test_a_websocket_from_a_foreign_origin_is_refused(daemon):
    with pytest.raises(InvalidStatus) as refused:
        with daemon.websocket(origin="http://evil.example"):
            pass
    assert refused.value.response.status_code == 403
    assert json.loads(refused.value.response.body)["error"] == "origin_not_allowed"
    with daemon.websocket() as ws:
        assert json.loads(ws.recv(timeout=30))["type"] == "hello"


def _example(schema, spec):
    """A minimal valid value for a JSON schema (enough to get past validation to the role check)."""
    if "$ref" in schema:
        return _example(spec["components"]["schemas"][schema["$ref"].split("/")[-1]], spec)
    if "anyOf" in schema:
        return _example(schema["anyOf"][0], spec)
    kind = schema.get("type")
    if kind == "object":
        return {
            k: _example(v, spec)
            for k, v in schema.get("properties", {}).items()
            if k in schema.get("required", [])
        }
    if "enum" in schema:
        return schema["enum"][0]
    return {"string": "x", "integer": 1, "number": 1, "boolean": True, "array": []}.get(kind)


def test_the_viewer_is_refused_with_a_reason_on_every_mutating_route(daemon, viewer, operator):
    spec = operator.get("/openapi.json").json()
    tried = []
    for path, operations in spec["paths"].items():
        for method, operation in operations.items():
            if method not in MUTATING:
                continue
            url = re.sub(r"\{[^}]+\}", "sample.py", path)
            body = operation.get("requestBody", {}).get("content", {}).get("application/json", {})
            payload = _example(body["schema"], spec) if body else None
            refused = viewer.request(method.upper(), url, json=payload)
            assert refused.status_code == 403, (method, path, refused.text)
            error = refused.json()
            assert error["error"] == "operator_required" and "viewer" in error["message"] and error["hint"]
            tried.append(f"{method.upper()} {path}")
    assert len(tried) >= 4  # the walk saw the mutating routes (programs, tokens ...)
    audit = operator.get("/api/system/audit", params={"limit": 1000}).json()
    refused_actions = {e["action"] for e in audit if e["who"] == "mentor" and e["status"] == 403}
    assert len(refused_actions) == len(tried)


def test_the_viewer_is_refused_every_mutating_websocket_command(daemon, viewer_token):
    mutating = [name for name, command in COMMANDS.items() if command.mutating]
    assert "stop_all" in mutating
    with daemon.websocket(token=viewer_token) as ws:
        json.loads(ws.recv(timeout=30))
        for name in mutating:
            ws.send(json.dumps({"cmd": name, "id": name}))
            reply = json.loads(ws.recv(timeout=30))
            while reply["type"] != "reply":
                reply = json.loads(ws.recv(timeout=30))
            assert reply["data"]["ok"] is False and reply["data"]["error"]["error"] == "operator_required"


def test_every_mutating_call_is_audited_with_who_role_what_and_result(daemon, operator):
    with daemon.websocket() as ws:
        json.loads(ws.recv(timeout=30))
        ws.send(json.dumps({"cmd": "stop_all", "id": 1}))
        reply = json.loads(ws.recv(timeout=30))
    assert reply["data"] == {"id": 1, "cmd": "stop_all", "ok": True, "result": {"hubs": []}}
    operator.put("/api/programs/a.py", json={"source": "print(1)\n"})
    operator.put("/api/programs/a.py", json={"source": "if x\n"})
    operator.delete("/api/programs/missing.py")
    operator.get("/api/programs")  # reads are not audited
    entries = operator.get("/api/system/audit").json()
    assert [(e["who"], e["role"], e["action"], e["status"]) for e in reversed(entries)] == [
        ("local", "operator", "WS stop_all", 200),
        ("local", "operator", "PUT /api/programs/a.py", 200),
        ("local", "operator", "PUT /api/programs/a.py", 422),
        ("local", "operator", "DELETE /api/programs/missing.py", 404),
    ]


def test_operators_mint_and_revoke_tokens(daemon, operator):
    minted = operator.post("/api/auth/tokens", json={"role": "viewer", "label": "coach"})
    assert minted.status_code == 201 and minted.json()["label"] == "coach"
    token = minted.json()["token"]
    with daemon.client(token) as coach:
        assert coach.get("/api/auth/me").json()["role"] == "viewer"
        assert operator.post("/api/auth/tokens", json={"role": "viewer", "label": "coach"}).status_code == 409
        assert operator.delete("/api/auth/tokens/coach").status_code == 204
        assert coach.get("/api/auth/me").status_code == 401


def _console(tmp_path, *args, timeout=30):
    env = dict(os.environ, OPENBRICKS_RUNTIME_DIR=str(tmp_path / "run"), OPENBRICKS_DATA_DIR=str(tmp_path))
    return subprocess.run(
        [sys.executable, "-m", "openbricks_server.cli", "console", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=env,
    )


@pytest.mark.e2e
def test_a_network_bind_refuses_to_start_until_a_token_exists(tmp_path):
    data = str(tmp_path / "data")
    refused = _console(tmp_path, "--host", "0.0.0.0", "--port", "0", "--data-dir", data, "--virtual", "0")
    assert refused.returncode == 1
    assert "refusing to listen on 0.0.0.0" in refused.stderr and "console token" in refused.stderr
    assert "Traceback" not in refused.stderr
    minted = _console(tmp_path, "token", "--role", "viewer", "--data-dir", data)
    assert minted.returncode == 0, minted.stderr
    assert "viewer token 'viewer-1'" in minted.stdout


def test_a_websocket_upgrade_for_another_host_name_is_refused(daemon):
    import socket

    request = (
        "GET /api/events HTTP/1.1\r\nHost: evil.example:80\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
        "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n"
        f"Origin: http://evil.example\r\nAuthorization: Bearer {daemon.token}\r\n\r\n"
    )
    with socket.create_connection(("127.0.0.1", daemon.config.port), timeout=10) as sock:
        sock.sendall(request.encode())
        answer = sock.recv(4096).decode("latin-1")
    assert answer.startswith("HTTP/1.1 403") and "host_not_allowed" in answer
