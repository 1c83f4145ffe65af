"""The one error the check reports: a message that says what failed, where, and how to fix it."""


class CheckError(Exception):
    pass
