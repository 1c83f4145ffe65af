"""One error shape for every 4xx and 5xx the daemon sends: `{"error", "message", "hint"}`.

A client (the browser console, the CLI, a team's script) handles failures one way: `error` is a stable
code to branch on, `message` says what went wrong in words a user can act on, `hint` what to do next.
Routers raise `ApiError`; FastAPI's own 404/405/422 and any unexpected exception are turned into the same
shape here, so no traceback or framework-specific body ever reaches a client.
"""

from __future__ import annotations

import logging
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import BaseModel
from starlette.exceptions import HTTPException as StarletteHTTPException

log = logging.getLogger("openbricks.console")


class ErrorBody(BaseModel):
    """The body of every error response."""

    error: str  # stable machine-readable code, e.g. "not_found", "hub_busy", "syntax_error"
    message: str
    hint: str | None = None
    detail: dict[str, Any] | None = (
        None  # structured extras (a syntax error's file/line, a busy hub's holder)
    )


class ApiError(Exception):
    """Raise from a route (or anything it calls) to answer with `status` and the error shape."""

    def __init__(
        self,
        status: int,
        error: str,
        message: str,
        hint: str | None = None,
        detail: dict[str, Any] | None = None,
    ):
        super().__init__(message)
        self.status = status
        self.body = ErrorBody(error=error, message=message, hint=hint, detail=detail)

    @classmethod
    def not_found(cls, what: str, hint: str | None = None) -> ApiError:
        return cls(404, "not_found", f"{what} not found", hint)

    @classmethod
    def conflict(cls, error: str, message: str, hint: str | None = None, detail=None) -> ApiError:
        return cls(409, error, message, hint, detail)

    @classmethod
    def invalid(cls, error: str, message: str, hint: str | None = None, detail=None) -> ApiError:
        return cls(422, error, message, hint, detail)


def error_response(status: int, body: ErrorBody, headers: dict[str, str] | None = None) -> JSONResponse:
    return JSONResponse(body.model_dump(exclude_none=True), status_code=status, headers=headers)


# Documented on every route so clients and the schema fuzzer know the error shape.
ERROR_RESPONSES: dict[int | str, dict[str, Any]] = {
    code: {"model": ErrorBody, "description": text}
    for code, text in (
        (400, "Bad request"),
        (401, "No valid token"),
        (403, "Refused: wrong role, Host or Origin"),
        (404, "Not found"),
        (409, "Conflict (e.g. the hub is busy)"),
        (413, "Too large"),
        (422, "Invalid input"),
        (500, "Internal error"),
    )
}

_STATUS_CODES = {
    400: "bad_request",
    401: "unauthorized",
    403: "forbidden",
    404: "not_found",
    405: "method_not_allowed",
    406: "not_acceptable",
    413: "too_large",
    415: "unsupported_media_type",
}


def _describe_validation(exc: RequestValidationError) -> tuple[str, dict[str, Any]]:
    errors = exc.errors()
    first = errors[0] if errors else {}
    loc = [str(p) for p in first.get("loc", ())]
    part = loc.pop(0) if loc and loc[0] in ("body", "query", "path", "header", "cookie") else "body"
    where = ".".join(loc) or part
    if part not in ("body", where):
        where = f"{where} (in the {part})"
    what = first.get("msg", "invalid value")
    if first.get("type") == "json_invalid":
        return "the request body is not valid JSON", {"errors": len(errors)}
    more = f" (and {len(errors) - 1} more)" if len(errors) > 1 else ""
    return f"{where}: {what}{more}", {"field": where, "errors": len(errors)}


async def _api_error(request: Request, exc: ApiError) -> JSONResponse:
    return error_response(exc.status, exc.body)


async def _validation_error(request: Request, exc: RequestValidationError) -> JSONResponse:
    message, detail = _describe_validation(exc)
    return error_response(
        422,
        ErrorBody(
            error="invalid_request",
            message=message,
            hint="see the request's schema at /docs",
            detail=detail,
        ),
    )


async def _http_error(request: Request, exc: StarletteHTTPException) -> JSONResponse:
    code = _STATUS_CODES.get(exc.status_code, "http_error")
    if exc.status_code == 404:
        body = ErrorBody(
            error=code,
            message=f"no such endpoint: {request.url.path}",
            hint="the API is listed at /docs",
        )
    elif exc.status_code == 405:
        allowed = (getattr(exc, "headers", None) or {}).get("Allow", "")
        body = ErrorBody(
            error=code,
            message=f"{request.method} is not allowed on {request.url.path}",
            hint=f"it takes {allowed}" if allowed else "the API is listed at /docs",
        )
    elif exc.status_code == 400 and request.method in ("POST", "PUT", "PATCH"):
        # FastAPI's words for a body it could not decode (bytes that are not UTF-8, say).
        body = ErrorBody(
            error=code,
            message="the request body could not be read: send UTF-8 JSON",
            hint="see the request's schema at /docs",
        )
    else:
        body = ErrorBody(error=code, message=str(exc.detail))
    return error_response(exc.status_code, body, getattr(exc, "headers", None))


async def _unexpected(request: Request, exc: Exception) -> JSONResponse:
    log.exception("unexpected error on %s %s", request.method, request.url.path)
    return error_response(
        500,
        ErrorBody(
            error="internal",
            message="the console hit an unexpected error; the request was not completed",
            hint="the daemon's terminal shows the details; please report it",
        ),
    )


def install(app: FastAPI) -> None:
    app.add_exception_handler(ApiError, _api_error)
    app.add_exception_handler(RequestValidationError, _validation_error)
    app.add_exception_handler(StarletteHTTPException, _http_error)
    app.add_exception_handler(Exception, _unexpected)
