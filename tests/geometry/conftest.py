"""Fixtures for the geometry tests: a pinhole camera looking at a tilted circular dial."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

Projector = Callable[[np.ndarray], np.ndarray]


def _tilted_dial(radius: float, distance: float, tilt_deg: float, focal: float = 1000.0) -> Projector:
    """Map dial-plane angles (N,) to image points (N, 2) px for a dial tilted about the image x axis.

    The dial (radius and distance in the same units) sits on the optical axis; the principal point
    is (500, 500). Angle 0 is image +x and angles grow clockwise on screen, like dial angles. Angle
    ``nan`` is not used; the dial centre is ``project(None)``.
    """
    tilt = np.radians(tilt_deg)

    def project(angles: np.ndarray | None) -> np.ndarray:
        if angles is None:
            x, y = np.zeros(1), np.zeros(1)
        else:
            x, y = radius * np.cos(angles), radius * np.sin(angles)
        xc, yc, zc = x, y * np.cos(tilt), distance + y * np.sin(tilt)
        return np.stack([focal * xc / zc + 500.0, focal * yc / zc + 500.0], axis=1)

    return project


@pytest.fixture
def tilted_dial() -> Callable[[float, float, float], Projector]:
    """``tilted_dial(radius, distance, tilt_deg)`` -> a projector from dial angles to pixels."""
    return _tilted_dial
