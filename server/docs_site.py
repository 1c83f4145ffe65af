"""The offline documentation: the Sphinx site `make docs` builds into this package (docs_html/).

The site ships inside the wheel like the console's pages, so `openbricks docs` and the console's
/manual/ serve it with no network. A topic is a page's name (`install`, `drivebase`) or its path in
the site (`api/motors`).
"""

from __future__ import annotations

import difflib
import os
from pathlib import Path

from openbricks_server.errors import CliError, UsageError

DOCS_DIR_ENV = "OPENBRICKS_DOCS_DIR"
# Sphinx's own pages, not topics a person asks for.
_GENERATED = {"genindex", "search", "py-modindex"}


def site_dir() -> Path:
    """The built site: $OPENBRICKS_DOCS_DIR when set, else the copy inside this package."""
    override = os.environ.get(DOCS_DIR_ENV)
    return Path(override) if override else Path(__file__).resolve().parent / "docs_html"


def topics(folder: Path | None = None) -> dict[str, Path]:
    """Every page by its path in the site without .html (`api/motors`)."""
    folder = site_dir() if folder is None else folder
    if not folder.is_dir():
        return {}
    pages = {}
    for page in sorted(folder.rglob("*.html")):
        name = page.relative_to(folder).with_suffix("").as_posix()
        if not name.startswith("_") and name not in _GENERATED:
            pages[name] = page
    return pages


def page_for(topic: str | None) -> Path:
    """The HTML file of `topic` (the index for None)."""
    folder = site_dir()
    pages = topics(folder)
    if not pages:
        raise CliError(
            f"the documentation is not built (no pages in {folder}): `make docs` builds it in a checkout; "
            f"or point {DOCS_DIR_ENV} at a built site"
        )
    if topic is None:
        return pages["index"]
    wanted = topic.lower().strip("/").removesuffix(".html").removesuffix(".md")
    for name in (wanted, wanted + "/index"):  # `api` is the API reference's own index page
        if name in pages:
            return pages[name]
    by_stem = {name.rsplit("/", 1)[-1]: name for name in pages if name.rsplit("/", 1)[-1] != "index"}
    if wanted in by_stem:
        return pages[by_stem[wanted]]
    close = difflib.get_close_matches(wanted, list(by_stem), n=3)
    hint = f"did you mean {', '.join(close)}? " if close else ""
    raise UsageError(f"no docs page {topic!r}; {hint}pages: {', '.join(sorted(by_stem))}")
