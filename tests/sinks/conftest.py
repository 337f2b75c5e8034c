"""Fixtures of the sink tests: readings, and real Zenoh sessions on loopback."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
import zenoh

from tests.zenoh_loopback import free_port, peer_config, zenoh_pair_sessions  # noqa: F401 (re-exported)
from gauged.types import Quality, Reading, ScaleInfo, StageFailure

T0 = 1_700_000_000_000_000_000


def make_reading(i: int = 0, gauge: str = "boiler-pressure", value: float | None = 4.5,
                 quality: Quality = Quality.GOOD, unit: str | None = "bar", locked: bool = True) -> Reading:
    """A reading of frame ``i``: 100 ms of frame time apart."""
    failure = None if value is not None else StageFailure("needle", "no_needle", "no line found")
    return Reading(gauge=gauge, camera="cam1", stamp_ns=T0 + i * 100_000_000, value=value,
                   raw_value=value, unit=unit, quality=quality, confidence=0.9,
                   scale=ScaleInfo(0.0, 10.0, unit, locked), failure=failure)




@pytest.fixture
def zenoh_pair() -> Iterator[tuple[zenoh.Session, zenoh.Session]]:
    """(daemon session listening on loopback, peer session connected to it); both closed after."""
    yield from zenoh_pair_sessions()


@pytest.fixture
def reading():
    """``reading(i=0, gauge=..., value=4.5, quality=GOOD, unit="bar", locked=True) -> Reading``."""
    return make_reading
