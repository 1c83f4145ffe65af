"""The `openbricks` console script.

Kept import-light: `openbricks --help` must start fast, so subcommands import
their machinery only when they run.
"""

import argparse
import sys

from openbricks import __version__


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="openbricks",
        description="Flash, run and debug programs on openbricks hubs, and simulate them.",
    )
    parser.add_argument("--version", action="version", version=f"openbricks {__version__}")
    parser.add_subparsers(dest="command", metavar="COMMAND")
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
