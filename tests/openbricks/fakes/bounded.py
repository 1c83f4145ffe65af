"""Traffic logs the fakes keep for tests to inspect, bounded: a bus engine on the 1 kHz tick writes
several packets every millisecond, which would fill a MicroPython heap within seconds."""

LIMIT = 1024


def append(entries, item):
    """Append `item`, dropping the oldest LIMIT entries once there are twice as many."""
    entries.append(item)
    if len(entries) > 2 * LIMIT:
        del entries[:LIMIT]
