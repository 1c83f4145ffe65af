"""`openbricks docs` opens the built documentation site offline and hands the page to the browser."""

import html
import os
import re
import stat
import subprocess
import sys
from pathlib import Path

from openbricks_server.docs_site import site_dir


def run_docs(tmp_path, *args, command="docs", env=None):
    record = tmp_path / "opened.txt"
    record.unlink(missing_ok=True)
    browser = tmp_path / "browser"
    browser.write_text(f'#!/bin/sh\necho "$1" >> "{record}"\n')
    browser.chmod(browser.stat().st_mode | stat.S_IXUSR)
    done = subprocess.run(
        [sys.executable, "-m", "openbricks_server.cli", command, *args],
        capture_output=True,
        text=True,
        env=dict(os.environ, BROWSER=f"{browser} %s", **(env or {})),
        timeout=60,
    )
    opened = record.read_text().split() if record.exists() else []
    return done, opened


def opened_page(opened) -> Path:
    return Path(opened[0].removeprefix("file://"))


def text_of(page: Path) -> str:
    """What the browser shows of the page: its text without markup (code is highlighted in spans)."""
    return html.unescape(re.sub(r"<[^>]+>", "", page.read_text()))


def test_the_index_of_the_packaged_site_opens_with_working_links_between_pages(tmp_path):
    done, opened = run_docs(tmp_path)
    assert done.returncode == 0, done.stderr
    assert len(opened) == 1 and opened_page(opened) == site_dir() / "index.html"
    index = opened_page(opened).read_text()
    assert 'href="cli.html"' in index and 'href="api/index.html"' in index
    assert (opened_page(opened).parent / "cli.html").is_file()


def test_a_topic_opens_its_page_by_name_or_path_and_a_typo_gets_suggestions(tmp_path):
    done, opened = run_docs(tmp_path, "install")
    assert done.returncode == 0 and opened[0].endswith("/install.html")
    assert "openbricks flash --name RobotA" in text_of(opened_page(opened))
    done, opened = run_docs(tmp_path, "drivebase")
    assert done.returncode == 0 and opened[0].endswith("/api/drivebase.html")
    assert "straight(distance_mm" in text_of(opened_page(opened))
    done, by_path = run_docs(tmp_path, "api/drivebase")
    assert by_path == opened
    done, opened = run_docs(tmp_path, "api")
    assert done.returncode == 0 and opened[0].endswith("/api/index.html")
    done, opened = run_docs(tmp_path, "simulater")
    assert done.returncode == 2 and opened == []  # a wrong argument
    assert "no docs page 'simulater'; did you mean simulator?" in done.stderr
    assert "Traceback" not in done.stderr


def test_the_doc_alias_works(tmp_path):
    done, opened = run_docs(tmp_path, "hardware")
    alias, alias_opened = run_docs(tmp_path, "hardware", command="doc")
    assert alias.returncode == 0 and alias_opened[-1] == opened[-1]


def test_a_site_that_is_not_built_says_how_to_build_it(tmp_path):
    done, opened = run_docs(tmp_path, env={"OPENBRICKS_DOCS_DIR": str(tmp_path / "nowhere")})
    assert done.returncode == 1 and opened == []
    assert "the documentation is not built" in done.stderr and "make docs" in done.stderr
    assert "Traceback" not in done.stderr


def test_path_prints_where_the_page_is_and_opens_nothing(tmp_path):
    """Where no browser can be started from this process (a server, a script), the file is what is wanted."""
    done, opened = run_docs(tmp_path, "--path")
    assert done.returncode == 0, done.stderr
    assert opened == [] and done.stdout == f"{site_dir() / 'index.html'}\n"
    done, opened = run_docs(tmp_path, "drivebase", "--path")
    assert done.returncode == 0 and opened == []
    assert Path(done.stdout.strip()) == site_dir() / "api" / "drivebase.html"
    done, opened = run_docs(tmp_path, "--path", env={"OPENBRICKS_DOCS_DIR": str(tmp_path / "nowhere")})
    assert done.returncode == 1 and done.stdout == "" and "make docs" in done.stderr
