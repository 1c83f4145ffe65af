"""What a hub operation can refuse or fail with, as the API reports it: a status code, a short code,
a message that says what happened, and a hint that says what to do."""

from __future__ import annotations


class HubOperationError(Exception):
    status = 500
    error = "hub_error"

    def __init__(self, message: str, hint: str = "", **detail):
        super().__init__(message)
        self.message = message
        self.hint = hint
        self.detail = detail


class HubNotFoundError(HubOperationError):
    status = 404
    error = "hub_not_found"


class HubBusyError(HubOperationError):
    """Another operation holds the hub: refused at once, never queued behind it."""

    status = 409
    error = "hub_busy"


class HubOfflineError(HubOperationError):
    status = 409
    error = "hub_offline"


class ProgramRejectedError(HubOperationError):
    """The program cannot be sent as it is (syntax error, too big, not text)."""

    status = 422
    error = "program_invalid"


class HubRefusedError(HubOperationError):
    """The hub answered, and said no (nothing staged, a run log that is gone, a bad argument)."""

    status = 422
    error = "hub_refused"


class LogNotFoundError(HubOperationError):
    """The run log asked for is not on the hub: it never existed, or a newer run took its slot."""

    status = 404
    error = "log_not_found"


class HubLinkError(HubOperationError):
    """The link failed during the operation (dropped, timed out)."""

    status = 503
    error = "hub_link"
