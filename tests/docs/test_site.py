"""The documentation site as `make docs` built it into the package (server/docs_html): every API name the
manual's chapter 7 documents has a reference entry, every internal link and image resolves, and every
code listing is a file under examples/ that a test runs."""

import re
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest
from sphinx.util.inventory import InventoryFile

from openbricks_server.docs_site import site_dir, topics

from .manual_names import api_names, manual_path

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
EXAMPLES = ROOT / "examples"
# The tests that run example programs in the simulator, and the host scripts against a real console.
LISTING_TESTS = [
    ROOT / "tests/sim/test_examples.py",
    ROOT / "tests/sim/test_manual_listings.py",
    ROOT / "tests/web/test_console_script_example.py",
    ROOT / "tests/server/daemon/routers/test_flash_script_example.py",
]


@pytest.fixture(scope="module")
def site():
    folder = site_dir()
    assert (folder / "index.html").is_file(), f"the site is not built in {folder}: run `make docs`"
    return folder


def test_every_chapter_7_name_of_the_manual_has_a_reference_entry(site):
    with open(site / "objects.inv", "rb") as inventory:
        entries = InventoryFile.load(inventory, "", lambda base, uri: uri)
    documented = {name for role, items in entries.items() if role.startswith("py:") for name in items}
    wanted = api_names(manual_path().read_text(encoding="utf-8"))
    assert len(wanted) > 200  # the chapter was read, not an empty match
    missing = [name for name in wanted if name not in documented]
    assert not missing, f"chapter-7 names with no entry in the API reference: {missing}"


class _Links(HTMLParser):
    def __init__(self):
        super().__init__()
        self.targets: list[str] = []
        self.ids: set[str] = set()

    def handle_starttag(self, tag, attrs):
        values = dict(attrs)
        if values.get("id"):
            self.ids.add(values["id"])
        for attribute in ("href", "src"):
            if values.get(attribute) and not (tag == "link" and values.get("rel") == "canonical"):
                self.targets.append(values[attribute])


def _parse(page: Path) -> _Links:
    links = _Links()
    links.feed(page.read_text(encoding="utf-8"))
    return links


def test_every_internal_link_and_image_of_every_page_resolves(site):
    pages = sorted(site.rglob("*.html"))
    parsed = {page: _parse(page) for page in pages}
    broken = []
    for page, links in parsed.items():
        for target in links.targets:
            parts = urlsplit(target)
            if parts.scheme or parts.netloc or target.startswith(("mailto:", "javascript:")):
                continue
            path = (page.parent / unquote(parts.path)).resolve() if parts.path else page
            if path.is_dir():
                path = path / "index.html"
            if not path.is_file():
                broken.append(f"{page.relative_to(site)}: {target} (no such file)")
            elif parts.fragment and path.suffix == ".html":
                ids = parsed[path].ids if path in parsed else _parse(path).ids
                if unquote(parts.fragment) not in ids:
                    broken.append(f"{page.relative_to(site)}: {target} (no such anchor)")
    assert len(pages) > 20
    assert not broken, "\n".join(broken)


def test_the_site_links_nowhere_outside_itself_but_to_the_project_itself(site):
    """Offline means offline: no page loads a script, a style or a font from the network."""
    for page in site.rglob("*.html"):
        text = page.read_text(encoding="utf-8")
        loaded = re.findall(r'<(?:script|link|img)[^>]+(?:src|href)="(https?:[^"]+)"', text)
        assert not loaded, f"{page.relative_to(site)} loads {loaded}"


def _listings():
    """(page, example path) for every literalinclude in the docs' Markdown."""
    found = []
    for page in sorted(DOCS.rglob("*.md")):
        for target in re.findall(r"^```\{literalinclude\}\s+(\S+)", page.read_text(encoding="utf-8"), re.M):
            found.append((page.relative_to(DOCS), (page.parent / target).resolve()))
    return found


def test_every_code_listing_is_an_example_file_that_a_test_runs():
    listings = _listings()
    assert len(listings) >= 3
    tests = "\n".join(path.read_text(encoding="utf-8") for path in LISTING_TESTS)
    for page, example in listings:
        assert example.is_file(), f"{page} includes {example}, which does not exist"
        assert example.is_relative_to(EXAMPLES), f"{page} includes {example}: listings live under examples/"
        assert f'"{example.name}"' in tests, (
            f"{page} shows examples/{example.relative_to(EXAMPLES)} but no test runs it: "
            "add one to tests/sim/test_examples.py"
        )


def test_program_code_in_the_docs_is_never_inline():
    """A Python block written into a page would be a listing no test runs: it goes in examples/."""
    for page in sorted(DOCS.rglob("*.md")):
        text = page.read_text(encoding="utf-8")
        inline = re.findall(r"^```(?:python|py|python3)\s*$", text, re.M)
        assert not inline, f"{page.relative_to(DOCS)} has a Python block; make it a file under examples/"


def test_every_page_is_a_topic_of_openbricks_docs(site):
    names = topics(site)
    for stem in ("index", "install", "first-robot", "console", "simulator", "api/drivebase", "cli-reference"):
        assert stem in names, stem
