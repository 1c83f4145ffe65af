"""`openbricks docs [topic]`: open the offline documentation in the browser."""

from __future__ import annotations

import sys

from openbricks_server.docs_site import page_for
from openbricks_server.errors import EXIT_OK


def main(args) -> int:
    import webbrowser

    page = page_for(args.topic)
    url = page.as_uri()
    if not webbrowser.open(url):
        print(f"no browser could be started; open {url} yourself", file=sys.stderr)
    else:
        print(f"opened {url}", file=sys.stderr)
    return EXIT_OK
