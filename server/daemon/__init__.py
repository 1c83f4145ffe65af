"""The console daemon: one process that owns every hub link, the run history and the event stream.

Layout (one module or package per job):
- `app.py`: the FastAPI application factory and its lifespan; `config.py`: what `openbricks console` was
  started with.
- `store/`: SQLite (WAL, versioned migrations) for hubs, programs, runs, output lines, telemetry, audit.
- `events.py`: the event stream (sequence numbers, replay ring, per-client bounded queues).
- `auth.py`: tokens, the cookie exchange, Host/Origin checks, roles.
- `hub_events.py`: the seam through which hub actors report to the store and the event stream.
- `hubs/`: the backend interface real, serial and virtual hubs implement, one actor per hub, the manager.
- `jobs/`: flash and servo jobs (state, steps, progress, result), run beside the hub actors.
- `routers/`: one FastAPI router per resource (hubs, programs, runs, events, auth, system, jobs, serial,
  flash, servos).
"""
