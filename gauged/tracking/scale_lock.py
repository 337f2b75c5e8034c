"""The scale lock of one gauge on a fixed camera: estimate the scale over frames, fuse, lock, re-check.

A fixed camera sees the same dial on every frame, so its scale (arc, angle->value map, unit) need not
be read again per frame: after ``frames`` full reads agree, their median is locked and each later
frame needs only the needle. The lock is released when the dial moves in the image (its pivot leaves
the locked position for several frames in a row) or when a scheduled full read disagrees with it.

Pure logic over frame times (ns); no clock reads, no I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from statistics import median

import numpy as np

from gauged.geometry.angles import wrap_angle
from gauged.reader.stages.ellipse import ScaleArc
from gauged.types import Box, Ellipse, ScaleModel

NS_PER_S = 1_000_000_000


@dataclass(frozen=True)
class LockedScale:
    """The fused scale of a gauge, valid for crops cut from ``box`` (crop pixels of that crop)."""

    box: Box
    arc: ScaleArc
    scale: ScaleModel
    locked_ns: int


@dataclass(frozen=True)
class Candidate:
    box: Box
    arc: ScaleArc
    scale: ScaleModel


def _circular_median(angles: list[float]) -> float:
    """Median of angles (radians) taken around their circular mean, so a wrap at +-pi does not split it."""
    mean = math.atan2(sum(math.sin(a) for a in angles), sum(math.cos(a) for a in angles))
    return mean + median(math.remainder(a - mean, 2 * math.pi) for a in angles)


def _same_range(a: ScaleModel, b: ScaleModel, tolerance: float) -> bool:
    span = max(abs(a.max_value - a.min_value), 1e-9)
    return abs(a.min_value - b.min_value) <= tolerance * span and abs(a.max_value - b.max_value) <= tolerance * span


def fuse(candidates: list[Candidate], tolerance: float = 0.05) -> Candidate | None:
    """The median scale of the largest group of candidates that agree on the value range and unit.

    Returns None when no group holds a strict majority (the reads disagree: keep collecting).
    """
    best: list[Candidate] = []
    for pivot in candidates:
        group = [c for c in candidates if c.scale.unit == pivot.scale.unit and _same_range(pivot.scale, c.scale, tolerance)]
        if len(group) > len(best):
            best = group
    if 2 * len(best) <= len(candidates):
        return None
    ellipses = [c.arc.ellipse for c in best]
    # Axis angle theta is defined modulo pi; fuse it as a doubled angle.
    theta = _circular_median([2 * e.theta for e in ellipses]) / 2 % math.pi
    ellipse = Ellipse(median(e.cx for e in ellipses), median(e.cy for e in ellipses), median(e.a for e in ellipses),
                      median(e.b for e in ellipses), theta)
    start = _circular_median([c.arc.start_angle for c in best])
    end = _circular_median([c.arc.end_angle for c in best])
    centre = (median(c.arc.centre[0] for c in best), median(c.arc.centre[1] for c in best))
    reference = best[len(best) // 2]
    arc = replace(reference.arc, ellipse=ellipse, centre=centre, start_angle=start, end_angle=end,
                  zero_angle=wrap_angle(start, end))
    lo, hi = median(c.scale.min_value for c in best), median(c.scale.max_value for c in best)
    span = (arc.end_angle - arc.start_angle) % (2 * math.pi)
    at_start = lo if reference.scale.slope > 0 else hi  # a scale rising counter-clockwise starts at its max
    slope = (hi - lo) / span * (1.0 if reference.scale.slope > 0 else -1.0)
    start_unwrapped = arc.zero_angle + (start - arc.zero_angle) % (2 * math.pi)
    scale = replace(reference.scale, ellipse=ellipse, slope=slope, intercept=at_start - slope * start_unwrapped,
                    zero_angle=arc.zero_angle, min_value=lo, max_value=hi)
    boxes = np.array([c.box for c in best])
    return Candidate(tuple(float(v) for v in np.median(boxes, axis=0)), arc, scale)


class ScaleLock:
    """Collects full reads of one gauge, locks their fused scale, and releases it when the dial moves."""

    def __init__(self, frames: int = 5, recheck_every_s: float = 300.0, move_tolerance_px: float = 8.0,
                 move_strikes: int = 3):
        self.frames = frames
        self.recheck_every_ns = int(recheck_every_s * NS_PER_S)
        self.move_tolerance_px = move_tolerance_px
        self.move_strikes = move_strikes
        self.candidates: list[Candidate] = []
        self.locked: LockedScale | None = None
        self._strikes = 0
        self.releases = 0

    @property
    def is_locked(self) -> bool:
        return self.locked is not None

    def recheck_due(self, stamp_ns: int) -> bool:
        """A full read (with OCR) is due to re-verify the locked scale."""
        return self.locked is not None and stamp_ns - self.locked.locked_ns >= self.recheck_every_ns

    def offer(self, box: Box, arc: ScaleArc, scale: ScaleModel, stamp_ns: int) -> bool:
        """Add a full read. Returns True when this read (re)locked the scale.

        A full-circle scale is not offered: :func:`fuse` rebuilds the scale from the arc's ends, which
        such a scale has not, so its gauge is read in full (OCR included) on every frame.
        """
        if scale.full_circle:
            return False
        if self.locked is not None:
            if _same_range(self.locked.scale, scale, 0.05) and scale.unit == self.locked.scale.unit:
                self.locked = replace(self.locked, locked_ns=stamp_ns)  # re-verified
                return False
            self.release()
            self.candidates = [Candidate(box, arc, scale)]
            return False
        self.candidates.append(Candidate(box, arc, scale))
        self.candidates = self.candidates[-2 * self.frames:]
        if len(self.candidates) < self.frames:
            return False
        fused = fuse(self.candidates)
        if fused is None:
            return False
        self.locked = LockedScale(fused.box, fused.arc, fused.scale, stamp_ns)
        self.candidates = []
        self._strikes = 0
        return True

    def observe_pivot(self, pivot_frame_px: tuple[float, float] | None, locked_pivot_frame_px: tuple[float, float]) -> bool:
        """Check the dial has not moved; returns True when the lock was released because it did."""
        if self.locked is None:
            return False
        moved = pivot_frame_px is None or math.dist(pivot_frame_px, locked_pivot_frame_px) > self.move_tolerance_px
        self._strikes = self._strikes + 1 if moved else 0
        if self._strikes >= self.move_strikes:
            self.release()
            return True
        return False

    def release(self) -> None:
        if self.locked is not None:
            self.releases += 1
        self.locked = None
        self._strikes = 0
