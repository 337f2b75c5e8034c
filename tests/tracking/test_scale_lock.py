from __future__ import annotations

import math

import numpy as np

from gauged.geometry.angles import wrap_angle
from gauged.reader.stages.ellipse import ScaleArc
from gauged.tracking.scale_lock import Candidate, ScaleLock, fuse
from gauged.types import Ellipse, ScaleModel

S = 1_000_000_000


def candidate(dx: float = 0.0, lo: float = 0.0, hi: float = 10.0, unit: str = "bar", start_deg: float = 135.0) -> Candidate:
    ellipse = Ellipse(128 + dx, 128, 100, 98, 0.1)
    start, end = math.radians(start_deg), math.radians(start_deg + 270)
    zero = wrap_angle(start, end)
    arc = ScaleArc(ellipse, (128 + dx, 128), start, end, zero, np.zeros((0, 2)), 0.5, False)
    unwrapped = zero + (start - zero) % (2 * math.pi)
    slope = (hi - lo) / math.radians(270)
    scale = ScaleModel(ellipse, slope, lo - slope * unwrapped, zero, lo, hi, unit, inliers=5)
    return Candidate((20, 20, 236, 236), arc, scale)


def test_fuse_takes_median_of_the_agreeing_majority():
    fused = fuse([candidate(dx=d) for d in (-1, 0, 1)] + [candidate(lo=0, hi=16)])
    assert fused is not None
    assert fused.arc.ellipse.cx == 128 and fused.scale.max_value == 10
    assert abs(fused.scale.value_at(math.radians(135 + 135)) - 5.0) < 1e-9  # mid-scale reads half the range


def test_fuse_refuses_without_majority():
    assert fuse([candidate(hi=10), candidate(hi=16), candidate(hi=25), candidate(hi=40)]) is None


def test_fuse_handles_angles_across_the_wrap():
    fused = fuse([candidate(start_deg=d) for d in (179.0, 180.5, -179.5)])
    assert abs(math.remainder(fused.arc.start_angle - math.pi, 2 * math.pi)) < math.radians(1)


def test_scale_lock_locks_after_enough_agreeing_reads_and_rechecks():
    lock = ScaleLock(frames=3, recheck_every_s=10)
    for i in range(2):
        c = candidate()
        assert not lock.offer(c.box, c.arc, c.scale, i * S)
    c = candidate()
    assert lock.offer(c.box, c.arc, c.scale, 2 * S) and lock.is_locked
    assert not lock.recheck_due(5 * S) and lock.recheck_due(12 * S)
    lock.offer(c.box, c.arc, c.scale, 12 * S)  # agreeing re-check renews the lock
    assert lock.is_locked and not lock.recheck_due(13 * S)
    other = candidate(hi=16)
    lock.offer(other.box, other.arc, other.scale, 30 * S)  # disagreeing re-check releases it
    assert not lock.is_locked and lock.releases == 1


def test_scale_lock_released_after_repeated_movement():
    lock = ScaleLock(frames=1, move_tolerance_px=5, move_strikes=3)
    c = candidate()
    lock.offer(c.box, c.arc, c.scale, 0)
    assert not lock.observe_pivot((140.0, 128.0), (128.0, 128.0))
    assert not lock.observe_pivot((128.0, 129.0), (128.0, 128.0))  # back in place: strikes reset
    assert not lock.observe_pivot(None, (128.0, 128.0))
    assert not lock.observe_pivot((150.0, 128.0), (128.0, 128.0))
    assert lock.observe_pivot((150.0, 128.0), (128.0, 128.0)) and not lock.is_locked


def test_a_full_circle_scale_is_never_locked():
    """fuse() rebuilds a scale from the arc's ends, which a full-circle scale has not: such a gauge is
    read in full on every frame."""
    from dataclasses import replace

    lock = ScaleLock(frames=2, recheck_every_s=10)
    for i in range(4):
        c = candidate()
        assert not lock.offer(c.box, c.arc, replace(c.scale, full_circle=True), i * S)
    assert not lock.is_locked and lock.candidates == []
