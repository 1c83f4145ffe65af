"""Who the caller is, and the console's tokens (list, mint, revoke) for operators handing out access."""

from __future__ import annotations

import re
from typing import Literal

from fastapi import APIRouter, Depends, Path, Request
from pydantic import BaseModel, Field

from openbricks_server.daemon.auth import LOCAL_LABEL, Caller, require_operator, require_viewer
from openbricks_server.daemon.errors import ApiError
from openbricks_server.daemon.network import lan_addresses, room_command, share_bases
from openbricks_server.daemon.store import LabelTaken

router = APIRouter(prefix="/auth", tags=["auth"], dependencies=[Depends(require_viewer)])

LABEL_PATTERN = r"^[A-Za-z0-9][A-Za-z0-9_.@-]{0,39}$"


class Me(BaseModel):
    label: str
    role: Literal["viewer", "operator"]
    via: Literal["cookie", "bearer"]


class TokenInfo(BaseModel):
    label: str
    role: Literal["viewer", "operator"]
    created_ms: int


class NewToken(BaseModel):
    role: Literal["viewer", "operator"]
    label: str | None = Field(
        None, pattern=LABEL_PATTERN, description="name in the audit log; default viewer-N / operator-N"
    )


class MintedToken(TokenInfo):
    token: str  # shown once: only its hash is stored


@router.get("/me", response_model=Me)
async def me(caller: Caller = Depends(require_viewer)) -> Me:
    return Me(label=caller.label, role=caller.role, via=caller.via)


class ShareInfo(BaseModel):
    host: str  # the address the console listens on (--host)
    port: int
    this_computer_only: bool  # listening on loopback: no other computer can open it
    bases: list[str]  # base URLs another computer can open (a link is BASE/?token=TOKEN)
    lan_addresses: list[str]  # this computer's network addresses
    room_command: str  # how to start the console so that the room reaches it


@router.get("/share", response_model=ShareInfo)
async def share(request: Request) -> ShareInfo:
    """Where another computer or a phone opens this console, for the links the page hands out."""
    config = request.app.state.ctx.config
    lan = lan_addresses()
    return ShareInfo(
        host=config.host,
        port=config.port,
        this_computer_only=config.is_loopback,
        bases=share_bases(config, lan),
        lan_addresses=lan,
        room_command=room_command(config, lan),
    )


@router.get("/tokens", response_model=list[TokenInfo])
async def list_tokens(request: Request) -> list[TokenInfo]:
    return [TokenInfo(**t) for t in request.app.state.ctx.store.tokens.list()]


@router.post("/tokens", response_model=MintedToken, status_code=201)
async def mint_token(body: NewToken, request: Request, caller: Caller = Depends(require_operator)):
    tokens = request.app.state.ctx.store.tokens
    label = body.label or tokens.next_label(body.role)
    if label == LOCAL_LABEL:
        raise ApiError.invalid("label_taken", f"{LOCAL_LABEL!r} names the console's own start-up token")
    try:
        token = tokens.mint(body.role, label)
    except LabelTaken:
        raise ApiError.conflict(
            "label_taken", f"a token labelled {label!r} exists", "pick another label or revoke that token"
        ) from None
    info = next(t for t in tokens.list() if t["label"] == label)
    return MintedToken(**info, token=token)


@router.delete("/tokens/{label}", status_code=204, dependencies=[Depends(require_operator)])
async def revoke_token(request: Request, label: str = Path(pattern=LABEL_PATTERN)) -> None:
    if not request.app.state.ctx.store.tokens.revoke(label):
        raise ApiError.not_found(f"token {label!r}", "GET /api/auth/tokens lists them")


def valid_label(label: str) -> bool:
    return re.fullmatch(LABEL_PATTERN, label) is not None
