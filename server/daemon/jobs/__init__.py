"""Jobs of the daemon: long operations on devices (flashing a hub, scanning or re-IDing servos) that run
beside the hub actors, report progress on the event stream and are kept as history.

- `registry.py`: the job record, its states (`queued/running/done/failed/cancelled`) and the registry
  that runs jobs as asyncio tasks, stores them and publishes `job` events.
- `flash.py`: one flash job per USB port, run in parallel with a bound.
- `servos.py`: servo scans and re-IDs through a hub or a USB adapter.
"""
