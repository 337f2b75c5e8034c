"""Fewer glibc malloc arenas for the daemon's threads (camera workers, Zenoh, onnxruntime).

glibc gives each thread that allocates concurrently an arena of its own (up to 8 per core), and
memory freed in one arena is not reused by another: under the load test (``bench/bench_load.py``,
4 cameras x 4 gauges) the daemon's peak RSS was 502 MB with the default and 446 MB with two
arenas, at the same latency. ``MALLOC_ARENA_MAX`` in the environment, when set, wins.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import logging
import os

log = logging.getLogger(__name__)

M_ARENA_MAX = -8  # glibc's mallopt parameter number (malloc.h)
DAEMON_ARENAS = 2


def limit_malloc_arenas(arenas: int = DAEMON_ARENAS) -> bool:
    """Cap glibc's malloc arenas at ``arenas`` for threads started from now on; True when applied.

    False, and nothing changed, where the C library is not glibc or ``MALLOC_ARENA_MAX`` is set.
    """
    if os.environ.get("MALLOC_ARENA_MAX"):
        return False
    name = ctypes.util.find_library("c")
    if name is None:
        return False
    try:
        libc = ctypes.CDLL(name)
        mallopt = libc.mallopt
    except (OSError, AttributeError):  # musl and others have no mallopt
        return False
    mallopt.argtypes = (ctypes.c_int, ctypes.c_int)
    applied = bool(mallopt(M_ARENA_MAX, int(arenas)))
    if not applied:
        log.debug("mallopt(M_ARENA_MAX, %d) was refused", arenas)
    return applied
