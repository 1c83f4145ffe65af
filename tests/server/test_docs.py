"""`openbricks docs` renders our own pages offline and hands the page to the browser."""

import os
import stat
import subprocess
import sys
from pathlib import Path


def run_docs(tmp_path, *args, command="docs"):
    record = tmp_path / "opened.txt"
    record.unlink(missing_ok=True)
    browser = tmp_path / "browser"
    browser.write_text(f'#!/bin/sh\necho "$1" >> "{record}"\n')
    browser.chmod(browser.stat().st_mode | stat.S_IXUSR)
    env = dict(os.environ, BROWSER=f"{browser} %s", OPENBRICKS_CACHE_DIR=str(tmp_path / "cache"))
    done = subprocess.run(
        [sys.executable, "-m", "openbricks_server.cli", command, *args],
        capture_output=True,
        text=True,
        env=env,
        timeout=60,
    )
    opened = record.read_text().split() if record.exists() else []
    return done, opened


def test_the_index_opens_with_working_links_between_pages(tmp_path):
    done, opened = run_docs(tmp_path)
    assert done.returncode == 0, done.stderr
    assert len(opened) == 1 and opened[0].endswith("/docs/index.html")
    index = Path(opened[0].removeprefix("file://")).read_text()
    assert 'href="cli.html"' in index and ".md" not in index
    assert (Path(opened[0].removeprefix("file://")).parent / "cli.html").is_file()


def test_a_topic_opens_its_page_and_a_typo_gets_suggestions(tmp_path):
    done, opened = run_docs(tmp_path, "install")
    assert done.returncode == 0 and opened[0].endswith("/install.html")
    assert "openbricks flash --name RobotA" in Path(opened[0].removeprefix("file://")).read_text()
    done, opened = run_docs(tmp_path, "simulater")
    assert done.returncode == 2 and opened == []  # a wrong argument
    assert "no docs page 'simulater'; did you mean simulator?" in done.stderr
    assert "Traceback" not in done.stderr


def test_the_doc_alias_works(tmp_path):
    done, opened = run_docs(tmp_path, "hardware")
    alias, alias_opened = run_docs(tmp_path, "hardware", command="doc")
    assert alias.returncode == 0 and alias_opened[-1] == opened[-1]
