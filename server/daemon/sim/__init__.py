"""Simulator runs as jobs of the daemon: each one a child process (`openbricks_sim.console_job`).

- `jobs.py`: `SimJobs`, the service that starts, steers, stops and records sim runs, and `SimRunJob`,
  one child process with its event channel.
- `proxy.py`: the run's 3D view (a viser server on 127.0.0.1 in the child) forwarded through the
  daemon's own port, HTTP and WebSocket, behind the daemon's token.
"""
