"""Moving scenes: gauge values over time, camera jitter and slowly changing light.

A :class:`Timeline` gives a gauge's true value at any time (piecewise-linear keys, so steps, ramps
and drifts, plus oscillation and smooth noise); a :class:`CameraSequence` is one fixed camera
looking at a :class:`~gauged.synth.scene.SceneSpec` whose needles follow their timelines while the
camera shakes a little and the light drifts. :func:`camera_frames` renders it frame by frame.
Everything is a function of the spec and the frame time, so frames are reproducible one by one.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, replace

import cv2
import numpy as np

from gauged.synth.backgrounds import background
from gauged.synth.params import GaugeParams
from gauged.synth.projection import translation
from gauged.synth.scene import DialCache, SceneSpec, render_frame, sample_scene
from gauged.synth.truth import image_record

EPOCH_NS = 1_704_067_200_000_000_000  # 2024-01-01T00:00:00Z: recordings start here, so files are reproducible


def _smooth_noise(t: float, seed: int, period: float) -> float:
    """A smooth zero-mean signal of unit-ish std: a sum of five sines with seeded frequencies."""
    rng = np.random.default_rng(seed)
    freqs = rng.uniform(0.3, 3.0, 5) / period
    phases = rng.uniform(0, 2 * math.pi, 5)
    return float(np.sum(np.sin(2 * math.pi * freqs * t + phases)) / math.sqrt(2.5))


@dataclass(frozen=True, slots=True)
class Timeline:
    """True value over time (seconds from the start): linear between ``keys`` (a step is two keys at
    the same time), plus ``amplitude * sin(2 pi t / period)`` and smooth noise of std ``noise``."""

    keys: tuple[tuple[float, float], ...]
    amplitude: float = 0.0
    period: float = 10.0
    noise: float = 0.0
    seed: int = 0

    def value(self, t: float) -> float:
        times = [k[0] for k in self.keys]
        values = [k[1] for k in self.keys]
        i = int(np.searchsorted(times, t, side="right"))
        if i == 0:
            base = values[0]
        elif i >= len(times):
            base = values[-1]
        else:
            t0, t1 = times[i - 1], times[i]
            base = values[i] if t1 == t0 else values[i - 1] + (values[i] - values[i - 1]) * (t - t0) / (t1 - t0)
        out = base
        if self.amplitude:
            out += self.amplitude * math.sin(2 * math.pi * t / self.period)
        if self.noise:
            out += self.noise * _smooth_noise(t, self.seed, 4.0)
        return out


def needle_state(params: GaugeParams, value: float) -> tuple[float, bool]:
    """What the needle shows for a true ``value``: below the stop pin it rests on the pin (the
    reading is then the pin's value and ``at_stop`` is set); above the end it stops 4 % past it."""
    scale = params.primary
    rest = params.rest_value
    top = scale.max + 0.04 * (scale.max - scale.min)
    if value <= rest:
        return rest, True
    return min(value, top), False


def sample_timeline(rng: np.random.Generator, lo: float, hi: float, seconds: float) -> Timeline:
    """A random program: steps, ramps, oscillation, noise, or a slow drift past 85 % of the span."""
    span = hi - lo
    kind = int(rng.integers(5))
    start = lo + span * rng.uniform(0.2, 0.6)
    if kind == 0:  # steps
        keys = [(0.0, start)]
        for t in np.sort(rng.uniform(0, seconds, int(rng.integers(1, 4)))):
            keys += [(float(t), keys[-1][1]), (float(t), lo + span * rng.uniform(0.1, 0.9))]
        return Timeline(tuple(keys), noise=span * 0.003, seed=int(rng.integers(2**31)))
    if kind == 1:  # ramps
        times = np.sort(rng.uniform(0, seconds, 3))
        keys = [(0.0, start)] + [(float(t), lo + span * rng.uniform(0.05, 0.95)) for t in times] + [(seconds, start)]
        return Timeline(tuple(keys))
    if kind == 2:  # oscillation
        return Timeline(((0.0, start),), amplitude=span * rng.uniform(0.03, 0.2), period=rng.uniform(3, 20))
    if kind == 3:  # noise
        return Timeline(((0.0, start),), noise=span * rng.uniform(0.01, 0.05), seed=int(rng.integers(2**31)))
    return Timeline(((0.0, lo + span * 0.6), (seconds, lo + span * 0.97)), noise=span * 0.004,
                    seed=int(rng.integers(2**31)))  # slow drift past an alarm limit


@dataclass(frozen=True, slots=True)
class CameraSequence:
    """One camera's moving scene. ``timelines`` pairs gauge ids with their value programs;
    ``jitter_px`` is the camera shake amplitude; ``light`` the relative amplitude of the slow
    exposure change over ``light_period_s``; ``phase_s`` delays this camera's first frame."""

    camera: str
    scene: SceneSpec
    timelines: tuple[tuple[str, Timeline], ...]
    fps: float
    seconds: float
    jitter_px: float = 1.0
    light: float = 0.1
    light_period_s: float = 40.0
    phase_s: float = 0.0
    seed: int = 0


@dataclass
class SequenceFrame:
    """``image`` (H, W, 3) uint8 BGR (not yet compressed); ``record`` the truth of the frame."""

    camera: str
    index: int
    stamp_ns: int
    image: np.ndarray
    record: dict


def jitter_at(seq: CameraSequence, t: float) -> np.ndarray:
    """Camera shake at time ``t``: a small smooth translation and rotation about the frame centre."""
    if seq.jitter_px <= 0:
        return np.eye(3)
    dx = seq.jitter_px * _smooth_noise(t, seq.seed + 1, 3.0)
    dy = seq.jitter_px * _smooth_noise(t, seq.seed + 2, 3.0)
    rot = math.radians(0.15) * seq.jitter_px * _smooth_noise(t, seq.seed + 3, 5.0)
    cx, cy = seq.scene.width / 2, seq.scene.height / 2
    c, s = math.cos(rot), math.sin(rot)
    r = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return translation(cx + dx, cy + dy) @ r @ translation(-cx, -cy)


def frame_stamps(seq: CameraSequence, start_ns: int = EPOCH_NS) -> list[int]:
    """Integer ns stamps of every frame."""
    n = int(math.floor(seq.seconds * seq.fps + 1e-9))
    return [start_ns + int(round((seq.phase_s + k / seq.fps) * 1e9)) for k in range(n)]


def camera_frames(seq: CameraSequence, start_ns: int = EPOCH_NS) -> Iterator[SequenceFrame]:
    """Render every frame of ``seq`` in order (deterministic)."""
    spec = seq.scene
    cache = DialCache()
    bg, _ = background(np.random.default_rng(spec.background_seed), spec.height, spec.width, spec.background)
    timelines = dict(seq.timelines)
    by_id = {g.gauge_id: g.params for g in spec.gauges}
    for k, stamp in enumerate(frame_stamps(seq, start_ns)):
        t = (stamp - start_ns) / 1e9
        values = {gid: needle_state(by_id[gid], tl.value(t)) for gid, tl in timelines.items() if gid in by_id}
        light = 1.0 + seq.light * math.sin(2 * math.pi * t / seq.light_period_s)
        rng = np.random.default_rng([seq.seed, k])
        result = render_frame(spec, cache=cache, values=values, jitter=jitter_at(seq, t), light=light,
                              background_image=bg, noise_rng=rng)
        record = image_record(result.truths, spec.width, spec.height, stamp_ns=stamp, camera=seq.camera)
        yield SequenceFrame(seq.camera, k, stamp, result.image, record)


def encode_jpeg(image: np.ndarray, quality: int) -> bytes:
    ok, buf = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, int(quality)])
    if not ok:
        raise RuntimeError("JPEG encoding failed")
    return buf.tobytes()


def without_compression(spec: SceneSpec) -> SceneSpec:
    """The scene with its camera's JPEG step removed (recordings compress frames themselves)."""
    return replace(spec, camera=replace(spec.camera, jpeg_quality=None))


def random_sequence(rng: np.random.Generator, *, camera: str = "cam1", seconds: float = 60.0, fps: float = 2.0,
                    gauges: int = 3, width: int = 960, height: int = 540, direction: str = "cw") -> CameraSequence:
    """A random fixed-camera scene of ``gauges`` gauges whose values follow random timelines;
    ``direction`` ("cw", "ccw", "mixed") is which way their scales rise."""
    spec = sample_scene(rng, width, height, n_gauges=gauges, direction=direction)
    spec = replace(without_compression(spec), occluders=0)
    timelines = tuple((g.gauge_id, sample_timeline(rng, g.params.primary.min, g.params.primary.max, seconds))
                      for g in spec.gauges)
    return CameraSequence(camera, spec, timelines, fps, seconds, jitter_px=float(rng.uniform(0.0, 2.0)),
                          light=float(rng.uniform(0.0, 0.2)), light_period_s=float(rng.uniform(20, 90)),
                          seed=int(rng.integers(2**31)))
