"""The simulator's 3D view in the browser: a run mirrored into a viser scene, with run controls.

    from openbricks_sim.job import SimJob
    from openbricks_sim.viewer import serve_run
    serve_run(SimJob("square.py", world="wro"), port=8080, on_ready=print)   # `sim run --viewer`

`SimViewer` is the reusable part (one server, one simulation at a time, any number of browsers);
`serve_run` (sim run --viewer) and `launch` (sim preview) are the command-line sessions around it.
Needs the `sim` extra (viser, mjviser).
"""

try:
    import mjviser  # noqa: F401
    import viser  # noqa: F401
except ImportError as exc:  # pragma: no cover - depends on the installation
    raise ImportError(
        f"the simulator's 3D viewer needs viser and mjviser ({exc}): install the sim extra, "
        "pip install 'openbricks[sim]'"
    ) from exc

from .session import launch, print_url, serve_run
from .viewer import DEFAULT_HOST, DEFAULT_PORT, RemoteBindError, SimViewer

__all__ = ["DEFAULT_HOST", "DEFAULT_PORT", "RemoteBindError", "SimViewer", "launch", "print_url", "serve_run"]
