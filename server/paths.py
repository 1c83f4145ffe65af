"""Where the host keeps its files: every user-directory path goes through this module.

Two roots, each overridable so tests (and users with odd setups) can move them:

- the data dir (``OPENBRICKS_DATA_DIR``; default ``~/.local/share/openbricks`` on Linux): state that must
  survive, such as hub locks and the virtual-hub registry;
- the cache dir (``OPENBRICKS_CACHE_DIR``; default ``~/.cache/openbricks``): things that can be fetched
  again, such as fetched firmware releases and rendered docs;
- the runtime dir (``OPENBRICKS_RUNTIME_DIR``; default ``$XDG_RUNTIME_DIR/openbricks`` on Linux): what
  only lives while a process runs, such as the console daemon's URL and local token.

Directories are created on first use, not at import, so `openbricks --help` touches no disk.
"""

from __future__ import annotations

import os
from pathlib import Path

APP_NAME = "openbricks"
DATA_DIR_ENV = "OPENBRICKS_DATA_DIR"
CACHE_DIR_ENV = "OPENBRICKS_CACHE_DIR"
RUNTIME_DIR_ENV = "OPENBRICKS_RUNTIME_DIR"


def _from_env_or(env: str, default) -> Path:
    value = os.environ.get(env)
    return Path(value).expanduser() if value else default()


def data_dir() -> Path:
    """Root of the state that must survive restarts."""
    import platformdirs

    return _from_env_or(DATA_DIR_ENV, lambda: platformdirs.user_data_path(APP_NAME, appauthor=False))


def cache_dir() -> Path:
    """Root of what can be rebuilt or fetched again."""
    import platformdirs

    return _from_env_or(CACHE_DIR_ENV, lambda: platformdirs.user_cache_path(APP_NAME, appauthor=False))


def runtime_dir() -> Path:
    """Root of what lives only while a process runs (gone after a reboot on most systems)."""
    import warnings

    import platformdirs

    with warnings.catch_warnings():
        # Without XDG_RUNTIME_DIR (a container, `su`, an ssh session on some systems) platformdirs
        # warns, naming its own source line, and falls back to /tmp/runtime-UID: the fallback is
        # right, the warning is noise at every command.
        warnings.simplefilter("ignore")
        return _from_env_or(
            RUNTIME_DIR_ENV, lambda: platformdirs.user_runtime_path(APP_NAME, appauthor=False)
        )


def ensure(path: Path) -> Path:
    """`path`, created (with parents) if missing."""
    path.mkdir(parents=True, exist_ok=True)
    return path


def locks_dir() -> Path:
    """One lock file per hub name: two commands (or the daemon) never talk to one hub at once."""
    return ensure(data_dir() / "locks")


def virtual_hubs_dir() -> Path:
    """Virtual hubs announce themselves here, one folder per hub (the simulator computes the same path)."""
    return data_dir() / "virtual-hubs"


def firmware_cache_dir() -> Path:
    """Fetched firmware releases, by version; not created here, so that looking finds nothing rather
    than leaving an empty folder behind."""
    return cache_dir() / "firmware"
