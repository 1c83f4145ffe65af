"""The browser console at `/`: the page built from `web/` into `openbricks_server/daemon/static` (by
`make web`; shipped in the wheel), or, before the page is built or before signing in, a short page that
says how to sign in and where the API is. The documentation site (`make docs`) at /manual/."""

from __future__ import annotations

from html import escape
from pathlib import Path

from fastapi import APIRouter, FastAPI, Request
from fastapi.responses import FileResponse, HTMLResponse
from fastapi.staticfiles import StaticFiles

from openbricks import __version__
from openbricks_server.docs_site import site_dir

STATIC_DIR = Path(__file__).resolve().parent.parent / "static"
INDEX = STATIC_DIR / "index.html"
ASSETS_DIR = STATIC_DIR / "assets"

MANUAL_PATH = "/manual"  # not /docs: that is the API's own page

router = APIRouter(include_in_schema=False)

_PAGE = """<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>openbricks console</title>
<style>body{{font-family:system-ui,sans-serif;max-width:40em;margin:3em auto;line-height:1.5}}</style>
</head><body><h1>openbricks console</h1>{body}<p><small>openbricks {version}</small></p></body></html>
"""


def refusal_page(status: int, message: str, hint: str) -> HTMLResponse:
    """A refused sign-in as a browser shows it: what happened and what to do, not the API's JSON."""
    body = (
        f"<p><b>{escape(message[:1].upper() + message[1:])}.</b></p>"
        f"<p>{escape(hint[:1].upper() + hint[1:])}.</p>"
        "<p>The address to open is the one <code>openbricks console</code> printed in its terminal when it "
        "started (it ends in <code>/?token=...</code>). A teammate's or mentor's link comes from the "
        "console's Share page.</p>"
    )
    return HTMLResponse(
        _PAGE.format(body=body, version=escape(__version__)),
        status_code=status,
        headers={"cache-control": "no-store"},
    )


@router.get("/", response_class=HTMLResponse)
async def landing(request: Request):
    caller = request.scope.get("state", {}).get("caller")
    if caller is None:
        body = (
            "<p>Not signed in. Open the address <code>openbricks console</code> printed in its terminal "
            "(it ends in <code>/?token=...</code>); the browser then keeps a sign-in cookie.</p>"
        )
    elif INDEX.is_file():
        return FileResponse(INDEX, headers={"cache-control": "no-cache"})
    else:
        body = (
            f"<p>Signed in as <b>{escape(caller.label)}</b> ({escape(caller.role)}).</p>"
            "<p>The console's pages are not built in this checkout (<code>make web</code> builds them). "
            "The whole API (hubs, programs, runs, the event stream) is listed and can be tried at "
            '<a href="/docs">/docs</a>.</p>'
        )
    return HTMLResponse(_PAGE.format(body=body, version=escape(__version__)))


def mount_manual(app: FastAPI) -> None:
    """The documentation site at /manual/, from the package; a page saying how to build it when it is not."""
    site = site_dir()
    if (site / "index.html").is_file():
        app.mount(MANUAL_PATH, StaticFiles(directory=site, html=True), name="manual")
        return

    @app.get(MANUAL_PATH + "/", include_in_schema=False, response_class=HTMLResponse)
    async def manual_not_built():
        body = (
            "<p>The manual is not built in this checkout (<code>make docs</code> builds it into the "
            "package). "
            'The API is listed at <a href="/docs">/docs</a>.</p>'
        )
        return HTMLResponse(_PAGE.format(body=body, version=escape(__version__)), status_code=404)
