"""The daemon caps glibc's malloc arenas, unless MALLOC_ARENA_MAX says otherwise."""

import os
import platform
import subprocess
import sys

import pytest

CALL = "from gauged.daemon.malloc_arenas import limit_malloc_arenas; print(limit_malloc_arenas())"


def _call(env_arenas: str | None) -> str:
    env = {k: v for k, v in os.environ.items() if k != "MALLOC_ARENA_MAX"}
    if env_arenas is not None:
        env["MALLOC_ARENA_MAX"] = env_arenas
    return subprocess.run([sys.executable, "-c", CALL], env=env, capture_output=True, text=True,
                          check=True).stdout.strip()


@pytest.mark.skipif(platform.libc_ver()[0] != "glibc", reason="mallopt(M_ARENA_MAX) is glibc's")
def test_arenas_are_capped_on_glibc():
    assert _call(None) == "True"


def test_malloc_arena_max_in_the_environment_wins():
    assert _call("4") == "False"
