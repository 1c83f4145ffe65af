"""Errors meant for the person at the terminal.

Anything a user can cause (a wrong name, a missing file, a busy hub, a dropped link) is raised as a
``CliError``: the CLI prints its message as one clear line and exits with its status, never a traceback.
A ``UsageError`` is a wrong argument found after parsing (a servo id out of range, a bad hub path): it
exits 2 with the command's usage line, exactly like the errors argparse finds itself.
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


class UsageError(CliError):
    """A wrong argument: the command could never succeed with it, whatever the hub or the bus says."""

    exit_status = EXIT_USAGE
