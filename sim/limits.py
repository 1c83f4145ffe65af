"""Resource limits of a process that runs user code (a sim run, a virtual hub).

User code never runs in the daemon or CLI process; the process that does run it caps its own
address space, so a runaway allocation ends in the program's MemoryError, not in the machine
swapping.
"""

import resource

DEFAULT_MEMORY_MB = 1024


def limit_memory(megabytes):
    """Cap this process's address space at `megabytes` (0 or None: leave it as it is)."""
    if not megabytes:
        return
    limit = megabytes * 1024 * 1024
    _soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    if hard != resource.RLIM_INFINITY:
        limit = min(limit, hard)
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
