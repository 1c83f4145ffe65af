"""`openbricks console`: the daemon that owns every hub link, the run history and the event stream;
`openbricks console token --role viewer|operator` mints an access token for it."""

from __future__ import annotations

import sys
from pathlib import Path

from openbricks_server.errors import EXIT_OK, CliError, UsageError


def _config(args):
    from openbricks_server.daemon.config import DaemonConfig

    return DaemonConfig(
        host=args.host,
        port=args.port,
        virtual=args.virtual,
        world=_world(args.world),
        data_dir=Path(args.data_dir) if args.data_dir else None,
        ble=not args.no_ble,
        allowed_hosts=tuple(args.allow_host or ()),
        serial_ports=tuple(getattr(args, "serial", None) or ()),
    )


def _world(name: str | None) -> str | None:
    """--world as the virtual hubs take it: an alias, or a world/MJCF file by its absolute path (the
    hubs run in their own folders), refused here with the file's own problems before anything starts."""
    if not name:
        return None
    from openbricks_sim.job import UnknownWorldError, world_file

    try:
        path = world_file(name)
    except UnknownWorldError as exc:
        raise UsageError(f"--world: {exc}") from None
    return name if path is None or not Path(name).exists() else str(Path(name).resolve())


def _serve(args) -> int:
    from openbricks_server.daemon.app import StartupRefused
    from openbricks_server.daemon.serve import BindError, run
    from openbricks_server.daemon.store import StoreError

    if args.port < 0 or args.port > 65535:
        raise UsageError(f"--port {args.port} is not a port number (0-65535)")
    if args.virtual < 0:
        raise UsageError(f"--virtual {args.virtual}: give 0 or more virtual hubs")
    try:
        started = run(_config(args), print_line=lambda line: print(line, flush=True))
    except (BindError, StartupRefused, StoreError) as exc:
        raise CliError(str(exc)) from None
    if not started:
        raise CliError("the console did not start; the lines above say why")
    return EXIT_OK


def _mint(args) -> int:
    from openbricks_server.daemon import runtime_file
    from openbricks_server.daemon.routers.auth import valid_label
    from openbricks_server.daemon.store import LabelTaken, Store, StoreError

    config = _config(args)
    if args.label is not None and not valid_label(args.label):
        raise CliError(f"--label {args.label!r}: use 1-40 letters, digits, '_', '.', '@' or '-'")
    try:
        store = Store(config.db_path)
    except StoreError as exc:
        raise CliError(str(exc)) from None
    try:
        label = args.label or store.tokens.next_label(args.role)
        if label == "local":
            raise CliError("--label local names the console's own start-up token; pick another")
        token = store.tokens.mint(args.role, label)
    except LabelTaken:
        raise CliError(f"a token labelled {label!r} exists already; pick another --label") from None
    finally:
        store.close()
    running = runtime_file.read()
    base = running.url if running else f"http://{args.host}:{args.port}"
    print(f"{args.role} token {label!r} (shown only now; the console stores its hash in {config.db_path}):")
    print(token)
    print(f"sign in: {base}/?token={token}")
    print(f"scripts: send 'Authorization: Bearer {token}'", file=sys.stderr)
    return EXIT_OK


def main(args) -> int:
    if getattr(args, "console_command", None) == "token":
        return _mint(args)
    return _serve(args)
