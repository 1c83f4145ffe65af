"""The offline documentation: Markdown pages in `docs/`, rendered to HTML in the cache dir on demand.

Pages are rendered again only when their source is newer than the HTML, so `openbricks docs` opens at
once after the first time. Links between pages (`cli.md`) are rewritten to the rendered files.
"""

from __future__ import annotations

import difflib
import html
import os
import re
import sys
from pathlib import Path

from openbricks_server.errors import CliError, UsageError
from openbricks_server.paths import docs_cache_dir

DOCS_DIR_ENV = "OPENBRICKS_DOCS_DIR"
_MD_LINK = re.compile(r'href="([A-Za-z0-9_-]+)\.md(#[^"]*)?"')
_STYLE = (
    "body{font:16px/1.5 system-ui,sans-serif;max-width:52em;margin:2em auto;padding:0 1em;color:#222}"
    "code,pre{font-family:ui-monospace,monospace;background:#f4f4f4}pre{padding:.8em;overflow:auto}"
    "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:.3em .6em;text-align:left}"
    "nav{margin-bottom:1.5em}"
)


def source_dir() -> Path:
    override = os.environ.get(DOCS_DIR_ENV)
    if override:
        return Path(override)
    # A source checkout or editable install: the package sits in <repo>/server next to <repo>/docs.
    checkout = Path(__file__).resolve().parent.parent / "docs"
    if checkout.is_dir():
        return checkout
    # A wheel install (pip, pipx): setup.py puts the pages under <prefix>/share/openbricks/docs.
    return Path(sys.prefix) / "share" / "openbricks" / "docs"


def topics() -> list[str]:
    folder = source_dir()
    return sorted(p.stem for p in folder.glob("*.md")) if folder.is_dir() else []


def page_for(topic: str | None) -> Path:
    """The rendered HTML file of `topic` (the index for None), rendering whatever is stale."""
    folder = source_dir()
    available = topics()
    if not available:
        raise CliError(f"the documentation is not installed (no pages in {folder}); set {DOCS_DIR_ENV}")
    wanted = "index" if topic is None else topic.lower().removesuffix(".md")
    if wanted not in available:
        close = difflib.get_close_matches(wanted, available, n=3)
        hint = f"did you mean {', '.join(close)}? " if close else ""
        raise UsageError(f"no docs page {topic!r}; {hint}pages: {', '.join(available)}")
    out = docs_cache_dir()
    for name in available:
        _render_if_stale(folder / f"{name}.md", out / f"{name}.html")
    return out / f"{wanted}.html"


def _render_if_stale(source: Path, target: Path) -> None:
    if target.exists() and target.stat().st_mtime >= source.stat().st_mtime:
        return
    from markdown_it import MarkdownIt

    text = source.read_text(encoding="utf-8")
    body = MarkdownIt("commonmark").enable("table").render(text)
    body = _MD_LINK.sub(lambda m: f'href="{m.group(1)}.html{m.group(2) or ""}"', body)
    title = next((line[2:].strip() for line in text.splitlines() if line.startswith("# ")), source.stem)
    page = (
        '<!doctype html>\n<html lang="en"><head><meta charset="utf-8">'
        f"<title>{html.escape(title)} - openbricks</title><style>{_STYLE}</style></head>\n"
        '<body><nav><a href="index.html">openbricks docs</a></nav>\n'
        f"{body}</body></html>\n"
    )
    tmp = target.with_name(target.name + ".tmp")
    tmp.write_text(page, encoding="utf-8")
    os.replace(tmp, target)
