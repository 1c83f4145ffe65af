"""`openbricks completion SHELL`: the shell code that completes openbricks' commands and options.

argcomplete does the completing: the printed code runs `openbricks` with argcomplete's environment
set whenever the user presses Tab, and cli.main answers from the real parser, so completion always
knows every command and option the installed version has.
"""

from __future__ import annotations

from openbricks_server.errors import EXIT_OK


def main(args) -> int:
    import argcomplete

    print(argcomplete.shellcode(["openbricks"], shell=args.shell))
    return EXIT_OK
