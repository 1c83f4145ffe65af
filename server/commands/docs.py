"""`openbricks docs [topic]`: open the offline documentation in the browser; `--path` prints where the
page is instead, for a machine with no browser this process can start, or a script."""

from __future__ import annotations

import sys

from openbricks_server.docs_site import page_for
from openbricks_server.errors import EXIT_OK


def main(args) -> int:
    import webbrowser

    page = page_for(args.topic)
    if args.path:
        print(page)
        return EXIT_OK
    url = page.as_uri()
    if not webbrowser.open(url):
        print(f"no browser could be started; open {url} yourself", file=sys.stderr)
    else:
        print(f"opened {url}", file=sys.stderr)
    return EXIT_OK
