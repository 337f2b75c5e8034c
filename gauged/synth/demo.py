"""The bundled demo recording: two fixed cameras, five gauges, 60 s, one alarm excursion.

``cam1`` sees ``boiler-pressure`` (0-10 bar; above 8 bar from about 21 s to 43 s and above 9 bar
from about 28 s to 41 s, then back near 6), ``feedwater-temp`` (0-120 degC, slow oscillation) and ``steam-header`` (0-16 bar
with an inner psi scale, steps). ``cam2`` sees ``pump-discharge`` (0-160 psi, black face, seen
obliquely, pulsating) and ``tank-vacuum`` (-1-0 bar, slow drift). Everything is fixed here, so
``gauged synth plant-demo --out recordings/plant-demo.mcap`` rebuilds the file byte for byte (with the same
versions of numpy, OpenCV, Pillow and mcap).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from gauged.synth.camera import CameraParams
from gauged.synth.params import GaugeParams, GlassParams
from gauged.synth.projection import Pose
from gauged.synth.ranges import Division, RangeSpec
from gauged.synth.sampling import sample_gauge
from gauged.synth.scene import GaugePlacement, SceneSpec
from gauged.synth.sequence import CameraSequence, Timeline

# Sizes keep the file near 6 MB: a 960x540 JPEG of gauges costs about 45 kB even on a plain wall.
CAM1_SIZE, CAM2_SIZE, FPS, SECONDS, QUALITY = (800, 450), (640, 360), 2.0, 60.0, 75
ALARM_HIGH, ALARM_HIGH_HIGH = 8.0, 9.0


def _gauge(seed: int, lo: float, hi: float, division: Division, unit: str, *, secondary: bool = False,
           dark: bool | None = None, plain: bool = False) -> GaugeParams:
    """A readable gauge of a fixed range: drawn clean, then given a mild glass and needle shadow.
    ``plain`` asks for the most common look: black print, upright numbers, a black or red needle."""
    for attempt in range(200):
        rng = np.random.default_rng([seed, attempt])
        params = sample_gauge(rng, clean=True, range_spec=RangeSpec(lo, hi, (division,), (unit,)), unit=unit,
                              secondary=secondary)
        s = params.primary
        is_dark = sum(params.face.color) < 300
        if (abs(s.end_angle - s.start_angle - math.radians(270)) < 1e-6 and s.numbers.size > 0.09
                and (dark is None or dark == is_dark) and (len(params.scales) == 2) == secondary
                and params.needle.shape in ("tapered", "lance") and not s.decimal_comma
                and (not plain or (s.color == (18, 18, 18) and s.number_orientation == "upright"
                                   and params.needle.color in ((18, 18, 18), (30, 30, 200), (40, 50, 220))))):
            break
    else:
        raise RuntimeError(f"no readable gauge found for seed {seed}")
    light = rng.uniform(0, 2 * math.pi)
    glass = GlassParams(glare=0.12, glare_center=(-0.35, -0.45), glare_size=(0.5, 0.2), glare_angle=0.4, reflections=0,
                        dirt=0.05, specks=0, scratches=0, condensation=0.0, fog=0.0, rim_shadow=0.3, light_angle=light)
    needle = replace(params.needle, shadow_strength=0.3, shadow_blur=0.015)
    return replace(params, glass=glass, needle=needle)


def _place(params: GaugeParams, gauge_id: str, size: tuple[int, int], x: float, y: float, diameter: float,
           tilt_deg: float, axis_deg: float) -> GaugePlacement:
    """Place a gauge; ``x``, ``y``, ``diameter`` are fractions of the frame width."""
    w = size[0]
    pose = Pose((x * w, y * w), diameter * w, math.radians(tilt_deg), math.radians(axis_deg), 0.0, 1.5 * w)
    return GaugePlacement(params, pose, gauge_id, 1.0, (0.05, -0.08), 1.0, 0.35)


CAMERA = CameraParams(exposure=1.0, gamma=1.0, white_balance=(1.0, 1.0, 1.0), vignette=0.15, noise=0.4)


def boiler_pressure() -> Timeline:
    """Steady near 6 bar, up past 8 (about 21 s) and 9 (about 28 s), held at 9.3, back to 6.2 by 48 s."""
    return Timeline(((0.0, 6.0), (10.0, 6.1), (25.0, 8.6), (30.0, 9.3), (40.0, 9.3), (48.0, 6.2), (60.0, 6.0)),
                    noise=0.04, seed=11)


def demo_sequences() -> list[CameraSequence]:
    boiler = _gauge(1, 0, 10, Division(1, 1, 0.2), "bar", dark=False, plain=True)
    feed = _gauge(2, 0, 120, Division(20, 10, 2), "degC")
    header = _gauge(3, 0, 16, Division(2, 1, 0.5), "bar", secondary=True, dark=False)
    pump = _gauge(4, 0, 160, Division(20, 20, 5), "psi", dark=True)
    vacuum = _gauge(5, -1, 0, Division(0.2, 0.1, 0.02), "bar", dark=False)
    cam1 = SceneSpec(*CAM1_SIZE, "wall", 101, (
        _place(boiler, "boiler-pressure", CAM1_SIZE, 0.345, 0.29, 0.31, 12, 20),
        _place(feed, "feedwater-temp", CAM1_SIZE, 0.76, 0.177, 0.177, 25, 100),
        _place(header, "steam-header", CAM1_SIZE, 0.77, 0.42, 0.177, 18, 250),
    ), CAMERA)
    cam2 = SceneSpec(*CAM2_SIZE, "wall", 202, (
        _place(pump, "pump-discharge", CAM2_SIZE, 0.333, 0.28, 0.29, 35, 10),
        _place(vacuum, "tank-vacuum", CAM2_SIZE, 0.75, 0.31, 0.23, 15, 160),
    ), CAMERA)
    t1 = (("boiler-pressure", boiler_pressure()),
          ("feedwater-temp", Timeline(((0.0, 74.0),), amplitude=6.0, period=30.0, noise=0.3, seed=12)),
          ("steam-header", Timeline(((0.0, 10.0), (15.0, 10.0), (15.0, 12.0), (35.0, 12.0), (35.0, 11.0)),
                                    noise=0.05, seed=13)))
    t2 = (("pump-discharge", Timeline(((0.0, 95.0),), amplitude=8.0, period=4.0, noise=1.5, seed=14)),
          ("tank-vacuum", Timeline(((0.0, -0.55), (60.0, -0.75)), noise=0.005, seed=15)))
    return [CameraSequence("cam1", cam1, t1, FPS, SECONDS, jitter_px=0.8, light=0.08, light_period_s=45.0, seed=21),
            CameraSequence("cam2", cam2, t2, FPS, SECONDS, jitter_px=0.6, light=0.12, light_period_s=30.0,
                           phase_s=0.25, seed=22)]
