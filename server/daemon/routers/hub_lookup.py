"""The hubs a route reaches: the daemon's hub manager, and what a hub operation refuses as the API's
error answer."""

from __future__ import annotations

from contextlib import contextmanager

from openbricks_server.daemon.errors import ApiError
from openbricks_server.daemon.hubs.actor import HubActor
from openbricks_server.daemon.hubs.errors import HubOperationError


def hub_manager(ctx):
    """The hub manager of the daemon's context; a 503 while it is not running."""
    if ctx.hubs is None:
        raise ApiError(503, "hubs_unavailable", "the hub manager is not running", "restart the console")
    return ctx.hubs


@contextmanager
def hub_errors():
    """A hub operation's refusal or failure (HubOperationError) answered with its status, code and hint."""
    try:
        yield
    except HubOperationError as exc:
        raise ApiError(exc.status, exc.error, exc.message, exc.hint or None, exc.detail or None) from None


def find_hub(ctx, ref: str) -> HubActor:
    """The hub `ref` names (its id, else its current name); a 404 naming the hubs there are otherwise."""
    with hub_errors():
        return hub_manager(ctx).get(ref)
