"""Tokens are passed on command lines (`--token TOKEN`), so none may look like an option."""

from unittest import mock

from openbricks_server.daemon.store import tokens


def test_a_token_never_starts_with_a_dash():
    drawn = iter(["-startswithadash", "--again", "fine-token_1"])
    with mock.patch.object(tokens.secrets, "token_urlsafe", lambda _n: next(drawn)):
        assert tokens.new_token() == "fine-token_1"
    assert not any(tokens.new_token().startswith("-") for _ in range(500))
