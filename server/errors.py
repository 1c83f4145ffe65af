"""Errors meant for the person at the terminal.

Anything a user can cause (a wrong name, a missing file, a busy hub, a dropped link) is raised as a
``CliError``: the CLI prints its message as one clear line and exits with its status, never a traceback.
"""

from __future__ import annotations

EXIT_OK = 0
EXIT_FAILED = 1  # the operation (or the user's program) failed
EXIT_USAGE = 2  # argparse's own status for bad arguments
EXIT_INTERRUPTED = 130  # stopped with Ctrl-C, as shells report SIGINT


class CliError(Exception):
    """A failure with a message that says what happened and what to do about it."""

    exit_status = EXIT_FAILED

    def __init__(self, message: str, exit_status: int | None = None):
        super().__init__(message)
        if exit_status is not None:
            self.exit_status = exit_status
