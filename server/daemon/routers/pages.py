"""The page at `/`: the browser console will live here; until then it says how to sign in and where the
API is."""

from __future__ import annotations

from html import escape

from fastapi import APIRouter, Request
from fastapi.responses import HTMLResponse

from openbricks import __version__

router = APIRouter(include_in_schema=False)

_PAGE = """<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>openbricks console</title>
<style>body{{font-family:system-ui,sans-serif;max-width:40em;margin:3em auto;line-height:1.5}}</style>
</head><body><h1>openbricks console</h1>{body}<p><small>openbricks {version}</small></p></body></html>
"""


@router.get("/", response_class=HTMLResponse)
async def landing(request: Request) -> HTMLResponse:
    caller = request.scope.get("state", {}).get("caller")
    if caller is None:
        body = (
            "<p>Not signed in. Open the address <code>openbricks console</code> printed in its terminal "
            "(it ends in <code>/?token=...</code>); the browser then keeps a sign-in cookie.</p>"
        )
    else:
        body = (
            f"<p>Signed in as <b>{escape(caller.label)}</b> ({escape(caller.role)}).</p>"
            "<p>The console's pages are coming. Meanwhile the whole API (hubs, programs, runs, the event "
            'stream) is listed and can be tried at <a href="/docs">/docs</a>.</p>'
        )
    return HTMLResponse(_PAGE.format(body=body, version=escape(__version__)))
