"""Angle arithmetic for a dial: wrapping, the wrap-around ("zero") angle of a scale, unwrapping.

All angles are radians in the image convention of :mod:`gauged.types` (positive = clockwise on
screen). A scale runs clockwise from its start notch to its end notch; the part of the circle that is
*not* scale is the gap. The zero angle is the middle of the gap, so unwrapping every angle into
``[zero, zero + 2 pi)`` makes the whole scale one continuous, increasing interval with the
discontinuity as far from it as possible (half a gap beyond each end).

Example:
    >>> import math
    >>> zero = wrap_angle(math.radians(135), math.radians(45))   # a 270 degree dial, gap at the bottom
    >>> round(math.degrees(zero), 6)
    90.0
    >>> round(math.degrees(unwrap(math.radians(45), zero)), 6)    # the end of the scale
    405.0
"""

from __future__ import annotations

import math

import numpy as np

TWO_PI = 2.0 * math.pi


def wrap_to_pi(angle: np.ndarray | float) -> np.ndarray | float:
    """Wrap angles (radians) into ``(-pi, pi]``; arrays keep their shape, floats stay floats."""
    wrapped = np.pi - np.mod(np.pi - np.asarray(angle, dtype=float), TWO_PI)
    return float(wrapped) if np.ndim(wrapped) == 0 else wrapped


def scale_span(start: float, end: float) -> float:
    """Clockwise angular extent (radians, in ``[0, 2 pi)``) of a scale running from ``start`` to ``end``."""
    return float(np.mod(end - start, TWO_PI))


def wrap_angle(start: float, end: float) -> float:
    """The wrap-around angle of a scale: the midpoint of the gap from ``end`` clockwise to ``start``.

    ``start`` and ``end`` are the notch angles (radians, any branch); the scale runs clockwise
    (increasing angle) from ``start`` to ``end``. The result is in ``(-pi, pi]``. When
    ``start == end`` (no measurable gap) the zero is put opposite the notch, i.e. the scale is read
    as empty and the gap as the whole circle; callers that meet 360 degree dials must say so.
    """
    gap = TWO_PI - scale_span(start, end)
    return float(wrap_to_pi(end + 0.5 * gap))


def unwrap(angle: np.ndarray | float, zero: float) -> np.ndarray | float:
    """Map angles into ``[zero, zero + 2 pi)``; the same rule as :meth:`gauged.types.ScaleModel.unwrap`."""
    unwrapped = zero + np.mod(np.asarray(angle, dtype=float) - zero, TWO_PI)
    return float(unwrapped) if np.ndim(unwrapped) == 0 else unwrapped


def angle_difference(a: np.ndarray | float, b: np.ndarray | float) -> np.ndarray | float:
    """Signed smallest difference ``a - b`` in ``(-pi, pi]`` (radians); broadcasts."""
    return wrap_to_pi(np.asarray(a, dtype=float) - np.asarray(b, dtype=float))
