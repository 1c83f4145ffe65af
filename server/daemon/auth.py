"""Who may talk to the daemon, and what they may do: tokens, the sign-in cookie, Host/Origin, roles.

The model Jupyter made familiar, plus roles:
- A token exists even on loopback. Each start mints a local operator token, printed once in the URL
  (`/?token=...`) and written to the runtime file for the CLI. More tokens are minted with
  `openbricks console token --role viewer|operator` and stored hashed.
- A GET carrying `?token=` is traded for an HttpOnly, SameSite=Strict cookie and redirected to the same
  URL without it, so the token does not linger in the address bar or history. Scripts send
  `Authorization: Bearer <token>` instead.
- Every request's Host header must name this daemon (loopback names, plus `--allow-host` names for a
  non-loopback bind): a page on another site that rebinds its DNS to 127.0.0.1 is refused.
- A state-changing request or a WebSocket upgrade signed in by the cookie must come with this daemon's
  own Origin, so a page the user happens to visit cannot post to the console in their name. A request
  authenticated by a Bearer header needs no Origin (no browser attaches that header on its own to a
  cross-site request), but a foreign Origin is refused there too.
- Roles: a viewer reads everything; every mutating route depends on `require_operator` and every
  mutating WebSocket command calls `operator_action`: one check, audited (who, role, what, when, result).
"""

from __future__ import annotations

import hmac
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Literal
from urllib.parse import parse_qsl, urlencode

from fastapi import Depends, Request
from fastapi.exceptions import RequestValidationError
from fastapi.security import HTTPBearer
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.requests import HTTPConnection
from starlette.types import ASGIApp, Receive, Scope, Send

from openbricks_server.daemon.config import DaemonConfig
from openbricks_server.daemon.errors import ApiError, ErrorBody, error_response
from openbricks_server.daemon.store import Store
from openbricks_server.daemon.store.tokens import new_token

Role = Literal["viewer", "operator"]
MUTATING_METHODS = frozenset({"POST", "PUT", "PATCH", "DELETE"})
LOCAL_LABEL = "local"  # the per-start operator token's name in the audit log
# Paths that answer without a token: the landing page says how to sign in.
PUBLIC_PATHS = frozenset({"/"})


@dataclass(frozen=True)
class Caller:
    """Who made a request: the token's label (the audit log's "who"), its role, and how it was sent."""

    label: str
    role: Role
    via: Literal["cookie", "bearer"]


class Auth:
    """The daemon's token registry: the per-start local token in memory, minted ones in the store."""

    def __init__(self, config: DaemonConfig, store: Store):
        self.config = config
        self.store = store
        self.local_token = new_token()
        self.cookie_name = f"openbricks-console-{config.port}"  # cookies ignore ports: one per daemon

    def identify(self, token: str) -> tuple[str, Role] | None:
        if hmac.compare_digest(token.encode(), self.local_token.encode()):
            return LOCAL_LABEL, "operator"
        return self.store.tokens.lookup(token)

    def host_allowed(self, host_header: str | None) -> bool:
        return host_header is not None and host_name(host_header) in self.config.host_names


def host_name(host_header: str) -> str:
    """The name part of a Host header: `[::1]:8765` -> `::1`, `Localhost:8765` -> `localhost`."""
    host = host_header.strip().lower()
    if host.startswith("["):
        return host[1 : host.find("]")] if "]" in host else host
    return host.rsplit(":", 1)[0] if host.count(":") == 1 else host


def refusal(status: int, error: str, message: str, hint: str) -> tuple[int, ErrorBody]:
    return status, ErrorBody(error=error, message=message, hint=hint)


class AuthMiddleware:
    """Host, token and Origin checks in front of every route; the caller lands in `request.state.caller`."""

    def __init__(self, app: ASGIApp):
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        auth: Auth = scope["app"].state.ctx.auth
        conn = HTTPConnection(scope)
        host = conn.headers.get("host")
        if not auth.host_allowed(host):
            allowed = ", ".join(sorted(auth.config.host_names))
            await _refuse(
                scope,
                send,
                *refusal(
                    403,
                    "host_not_allowed",
                    f"this console does not answer to the host name {host!r}",
                    f"open it as one of: {allowed}; for a network name start it with --allow-host NAME",
                ),
            )
            return
        method = scope.get("method", "GET")
        url_token = conn.query_params.get("token")
        if url_token is not None and scope["type"] == "http" and method in ("GET", "HEAD"):
            await self._sign_in(scope, send, auth, url_token)
            return
        caller = self._caller(conn, auth)
        if caller is None and scope["type"] == "http" and scope["path"] in PUBLIC_PATHS:
            await self.app(scope, receive, send)
            return
        if caller is None:
            await _refuse(
                scope,
                send,
                *refusal(
                    401,
                    "unauthorized",
                    "no valid token: this console needs one even on this computer",
                    "open the URL the console printed (http://...:PORT/?token=...), or send "
                    "'Authorization: Bearer <token>'",
                ),
            )
            return
        if scope["type"] == "websocket" or method in MUTATING_METHODS:
            problem = _origin_problem(conn.headers.get("origin"), host, caller)
            if problem:
                await _refuse(scope, send, *problem)
                return
        scope.setdefault("state", {})["caller"] = caller
        await self.app(scope, receive, send)

    @staticmethod
    def _caller(conn: HTTPConnection, auth: Auth) -> Caller | None:
        header = conn.headers.get("authorization", "")
        scheme, _, value = header.partition(" ")
        if scheme.lower() == "bearer" and value.strip():
            found = auth.identify(value.strip())
            return Caller(found[0], found[1], "bearer") if found else None
        cookie = conn.cookies.get(auth.cookie_name)
        if cookie:
            found = auth.identify(cookie)
            return Caller(found[0], found[1], "cookie") if found else None
        return None

    @staticmethod
    async def _sign_in(scope: Scope, send: Send, auth: Auth, token: str) -> None:
        if auth.identify(token) is None:
            await _refuse(
                scope,
                send,
                *refusal(
                    401,
                    "bad_token",
                    "the token in this URL is not valid",
                    "the console prints a new URL each time it starts: open the latest one",
                ),
            )
            return
        query = urlencode(
            [(k, v) for k, v in parse_qsl(scope.get("query_string", b"").decode()) if k != "token"]
        )
        path = scope.get("raw_path") or scope["path"].encode()
        location = path.decode("latin-1") + (f"?{query}" if query else "")
        cookie = f"{auth.cookie_name}={token}; HttpOnly; SameSite=Strict; Path=/"
        await send(
            {
                "type": "http.response.start",
                "status": 303,
                "headers": [
                    (b"location", location.encode()),
                    (b"set-cookie", cookie.encode()),
                    (b"cache-control", b"no-store"),
                    (b"referrer-policy", b"no-referrer"),
                    (b"content-length", b"0"),
                ],
            }
        )
        await send({"type": "http.response.body", "body": b""})


def _origin_problem(origin: str | None, host: str | None, caller: Caller) -> tuple[int, ErrorBody] | None:
    own = f"http://{host}".lower()
    if origin is None:
        if caller.via == "bearer":
            return None
        return refusal(
            403,
            "origin_required",
            "a state-changing request signed in by the browser cookie must carry an Origin header",
            "send it from the console's own page, or use 'Authorization: Bearer <token>' from a script",
        )
    if origin.lower() != own:
        return refusal(
            403,
            "origin_not_allowed",
            f"requests from {origin} may not change this console (its own origin is {own})",
            "use the console's own page, or a script with 'Authorization: Bearer <token>' and no Origin",
        )
    return None


def _wants_page(scope: Scope) -> bool:
    """A browser opening a page (not a script, not the page's own API calls): it gets a page to read."""
    if scope.get("method") not in ("GET", "HEAD") or scope["path"].startswith(("/api/", "/openapi")):
        return False
    accept = HTTPConnection(scope).headers.get("accept", "")
    return "text/html" in accept


async def _refuse(scope: Scope, send: Send, status: int, body: ErrorBody) -> None:
    if scope["type"] == "http":
        if _wants_page(scope):
            from openbricks_server.daemon.routers.pages import refusal_page  # the pages' look lives there

            await refusal_page(status, body.message, body.hint or "")(scope, _no_receive, send)
            return
        response = error_response(status, body)
        await response(scope, _no_receive, send)
        return
    # A WebSocket refused before it is accepted: an HTTP answer with the error body where the server
    # supports it, else a plain close (the client sees HTTP 403).
    if "websocket.http.response" in scope.get("extensions", {}):
        response = error_response(status, body)
        await send(
            {"type": "websocket.http.response.start", "status": status, "headers": response.raw_headers}
        )
        await send({"type": "websocket.http.response.body", "body": response.body})
    else:
        await send({"type": "websocket.close", "code": 1008, "reason": body.message[:120]})


async def _no_receive():  # error responses never read the request body
    return {"type": "http.disconnect"}


# Shown in the OpenAPI schema (the Authorize button at /docs); the middleware does the checking.
_bearer_scheme = HTTPBearer(auto_error=False, description="A console token (or the sign-in cookie)")


def require_viewer(conn: HTTPConnection, _scheme=Depends(_bearer_scheme)) -> Caller:
    """The signed-in caller (any role): every route depends on this."""
    caller = conn.scope.get("state", {}).get("caller")
    if caller is None:  # only the public landing page gets here unsigned, and it does not depend on this
        raise ApiError(401, "unauthorized", "no valid token", "open the URL the console printed")
    return caller


@contextmanager
def operator_action(conn: HTTPConnection, caller: Caller, action: str) -> Iterator[None]:
    """The one role check: refuses a viewer with 403 and a reason, and audits every attempt's result."""
    audit = conn.app.state.ctx.store.audit
    if caller.role != "operator":
        audit.add(caller.label, caller.role, action, 403)
        raise ApiError(
            403,
            "operator_required",
            f"{action} changes the console; token {caller.label!r} is a viewer's (read-only)",
            "use an operator token (`openbricks console token --role operator` mints one)",
        )
    try:
        yield
    except ApiError as exc:
        audit.add(caller.label, caller.role, action, exc.status)
        raise
    except RequestValidationError:
        audit.add(caller.label, caller.role, action, 422)
        raise
    except StarletteHTTPException as exc:
        audit.add(caller.label, caller.role, action, exc.status_code)
        raise
    except Exception:
        audit.add(caller.label, caller.role, action, 500)
        raise
    audit.add(caller.label, caller.role, action, getattr(conn.state, "audit_status", 200))


STARTED = 202  # the audit status of a request that started jobs: each job's own entry says how it ended


def audit_as_started(request: Request) -> None:
    """A route that starts jobs calls this: its request is audited as started, not done, and each job's
    end is audited with its real outcome (JobRegistry), so a failed flash never reads "done"."""
    request.state.audit_status = STARTED


async def require_operator(request: Request, caller: Caller = Depends(require_viewer)):
    """Every mutating route depends on this (create_app refuses to build an app where one does not)."""
    with operator_action(request, caller, f"{request.method} {request.url.path}"):
        yield caller
