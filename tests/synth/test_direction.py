"""Scales whose values rise counter-clockwise: parameters, sampling, drawing, truth and training labels.

Known truths are constructed (a gauge and its mirror image, a render at a known value) and read back
from the parameters, the drawn dial and the projected truth record.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gauged.synth.crop import render_crop
from gauged.synth.dataset import render_item
from gauged.synth.dial import draw_dial, scale_marks
from gauged.synth.params import ScaleParams, TextStyle
from gauged.synth.projection import apply_homography, pose_homography
from gauged.synth.ranges import convert, format_number, grid
from gauged.synth.sampling import CCW_SHARE, DIRECTIONS, reverse_direction, sample_gauge
from gauged.synth.scene import render_scene
from gauged.synth.sequence import needle_state
from gauged.training.targets import arc_end_points

TAU = 2 * math.pi


def _scale(start: float, end: float, lo: float = -1.0, hi: float = 0.0) -> ScaleParams:
    return ScaleParams(role="primary", min=lo, max=hi, unit="bar", unit_text="bar", start_angle=start, end_angle=end,
                       radius=0.8, label_step=0.2, major_step=0.1, minor_step=0.02, tick_side="in", major_style="line",
                       minor_style="line", major_length=0.1, minor_length=0.05, major_width=0.02, minor_width=0.01,
                       baseline=False, baseline_width=0.01, color=(20, 20, 20), numbers=TextStyle("sans", 0.1, (20, 20, 20)),
                       number_side="in", number_gap=0.03, number_orientation="upright", decimals=1)


def _gauges(direction: str, seeds=range(200), **kw):
    return [sample_gauge(np.random.default_rng(s), direction=direction, **kw) for s in seeds]


def _cw_angle(a_from: float, a_to: float) -> float:
    """Angle turned clockwise on screen from ``a_from`` to ``a_to``, in [0, 2 pi)."""
    return (a_to - a_from) % TAU


def _cross(u: np.ndarray, v: np.ndarray) -> float:
    """> 0 when ``v`` lies clockwise of ``u`` on screen (y down), for turns below 180 degrees."""
    return float(u[0] * v[1] - u[1] * v[0])


# --- parameters ----------------------------------------------------------------------------------

@settings(max_examples=80, deadline=None)
@given(start=st.floats(-math.pi, math.pi), sweep=st.floats(0.5, 5.8), ccw=st.booleans(),
       lo=st.floats(-100, 100), span=st.floats(0.01, 500), t=st.floats(-0.2, 1.2))
def test_scale_angle_of_and_value_at_round_trip_in_both_directions(start, sweep, ccw, lo, span, t):
    scale = _scale(start, start - sweep if ccw else start + sweep, lo, lo + span)
    v = lo + t * span
    assert scale.value_at(scale.angle_of(v)) == pytest.approx(v, abs=1e-9 * max(1.0, abs(v), span))
    assert scale.direction == ("ccw" if ccw else "cw")
    assert scale.sweep == pytest.approx(sweep)
    first, last = scale.arc
    assert _cw_angle(first, last) == pytest.approx(sweep % TAU)
    # a value rising moves the angle counter-clockwise exactly when the scale is ccw
    assert (scale.angle_of(lo + span) < scale.angle_of(lo)) == ccw
    assert (scale.below_min(0.1) > scale.start_angle) == ccw  # the stop pin side


def test_reverse_direction_keeps_the_arc_and_moves_the_minimum_to_the_other_end():
    for params in _gauges("cw", range(40), secondary=True):
        back = reverse_direction(params)
        assert back.primary.arc == pytest.approx(params.primary.arc)
        for s, r in zip(params.scales, back.scales):
            assert (s.direction, r.direction) == ("cw", "ccw")
            # every scale's ends stay where the primary scale shows the same values
            for v in (s.min, s.max):
                p_value = params.primary.value_at(s.angle_of(v))
                assert r.angle_of(v) == pytest.approx(back.primary.angle_of(p_value))
        assert back.rest_value == pytest.approx(params.rest_value)
        assert back.needle_angle == pytest.approx(sum(params.primary.arc) - params.needle_angle)
        if params.stop_pin is not None:  # past the minimum, on the other side of the arc
            assert params.stop_pin[0] < params.primary.start_angle
            assert back.stop_pin[0] > back.primary.start_angle
        again = reverse_direction(back)
        assert again.primary.start_angle == pytest.approx(params.primary.start_angle)


# --- sampling ------------------------------------------------------------------------------------

def test_ccw_sampling_runs_every_scale_counter_clockwise():
    for params in _gauges("ccw", range(100)):
        assert {s.direction for s in params.scales} == {"ccw"}


def test_mixed_sampling_runs_a_share_counter_clockwise():
    share = np.mean([p.primary.direction == "ccw" for p in _gauges("mixed", range(400))])
    assert abs(share - CCW_SHARE) < 0.08
    for params in _gauges("mixed", range(100)):  # a gauge's scales agree
        assert len({s.direction for s in params.scales}) == 1


def test_sampling_rejects_an_unknown_direction():
    with pytest.raises(ValueError, match="direction"):
        sample_gauge(np.random.default_rng(0), direction="anticlockwise")


def test_ccw_sampling_prints_negative_and_decimal_numbers():
    texts = set()
    for params in _gauges("ccw"):
        for s in params.scales:
            texts |= {format_number(float(v), s.decimals, s.decimal_comma) for v in scale_marks(s)[0]}
    negative = {t for t in texts if t.startswith("-")}
    decimal = {t for t in texts if "." in t or "," in t}
    assert {"-1.0", "-0.5", "-20", "-100", "-0.10"} & negative
    assert len(negative) > 10 and len(decimal) > 20 and {"1.6", "2.5"} <= decimal
    assert negative & decimal  # -0.2, -0.08, ...


# Hashes computed before scales could run counter-clockwise (sha256 prefixes, truth without the
# "direction" key added since). The parameters are numpy's RNG and Python floats only; the render
# hashes also depend on OpenCV and Pillow, so a library upgrade may change them, a code change should not.
PARAMS_300 = "fc02848f061fa5da"
RENDERS = {"crop0": "4a16f980c2a85ac4", "crop1": "f26c96bb7dad0580", "crop2": "4b57ae9f55fed9f9",
           "scene0": "158433d1b3c94969", "item0": "c9138c57a1f8a9bc"}


def _h(*parts) -> str:
    m = hashlib.sha256()
    for p in parts:
        m.update(p if isinstance(p, bytes) else p.encode())
    return m.hexdigest()[:16]


def _without_direction(o):
    if isinstance(o, dict):
        return {k: _without_direction(v) for k, v in o.items() if k != "direction"}
    if isinstance(o, list):
        return [_without_direction(v) for v in o]
    return o


def test_default_direction_draws_the_parameters_it_drew_before_directions_existed():
    per_seed = [_h(repr(sample_gauge(np.random.default_rng(s)))) for s in range(300)]
    assert _h("".join(per_seed)) == PARAMS_300


def test_default_direction_renders_the_bytes_it_rendered_before_directions_existed():
    got = {}
    for s in range(3):
        c = render_crop(s, size=192)
        got[f"crop{s}"] = _h(c.image.tobytes(), c.needle_mask.tobytes(), json.dumps(_without_direction(c.truth)))
    sc = render_scene(0, 480, 270)
    got["scene0"] = _h(sc.image.tobytes(), json.dumps(_without_direction(sc.record)))
    img, rec, _ = render_item(("crop", 9, 0, 0, 0, 128, False))
    got["item0"] = _h(img.tobytes(), json.dumps(_without_direction(rec)))
    assert got == RENDERS


def test_render_item_takes_the_direction_as_an_optional_eighth_field():
    old = render_item(("crop", 4, 1, 0, 0, 96, True))
    cw = render_item(("crop", 4, 1, 0, 0, 96, True, "cw"))
    ccw = render_item(("crop", 4, 1, 0, 0, 96, True, "ccw"))
    assert old[0].tobytes() == cw[0].tobytes() and old[1] == cw[1]
    assert cw[1]["gauges"][0]["scales"][0]["direction"] == "cw"
    assert ccw[1]["gauges"][0]["scales"][0]["direction"] == "ccw"


# --- drawing and truth ---------------------------------------------------------------------------

def _rectified_angles(sample, points) -> np.ndarray:
    """Dial angles (face frame) of image points of the crop's gauge."""
    h = np.diag([sample.output_scale, sample.output_scale, 1.0]) @ pose_homography(sample.spec.gauges[0].pose)
    face = apply_homography(np.linalg.inv(h), np.asarray(points, float).reshape(-1, 2))
    return np.arctan2(face[:, 1], face[:, 0])


def _unwrap_near(angle: float, centre: float) -> float:
    return centre + math.remainder(angle - centre, TAU)


@pytest.mark.parametrize("seed", range(10))
def test_ccw_truth_min_notch_lies_clockwise_after_max_and_needle_reads_the_value(seed: int) -> None:
    sample = render_crop(seed, size=448, clean=True, direction="ccw")
    truth, params = sample.truth, sample.params
    for scale_truth, scale in zip(truth["scales"], params.scales):
        assert scale_truth["direction"] == "ccw" and scale_truth["sweep_deg"] > 0
        a_min, a_max = _rectified_angles(sample, [scale_truth["start"], scale_truth["end"]])
        assert _cw_angle(a_max, a_min) == pytest.approx(math.radians(scale_truth["sweep_deg"]), abs=1e-3)
    # the drawn needle's angle, read back through the primary scale, is the true value
    (tip,) = _rectified_angles(sample, [truth["needle"]["tip"]])
    primary = params.primary
    angle = _unwrap_near(float(tip), (primary.start_angle + primary.end_angle) / 2)
    assert primary.value_at(angle) == pytest.approx(truth["value"], abs=1e-4 * (primary.max - primary.min))
    assert truth["scales"][0]["reading"] == pytest.approx(truth["value"], rel=1e-6, abs=1e-9)
    assert (truth["min"], truth["max"]) == (primary.min, primary.max)
    assert truth["needle"]["at_stop"] == (truth["value"] < primary.min)


def test_ccw_truth_numbers_and_majors_rise_counter_clockwise_in_the_image():
    checked = 0
    for seed in range(24):
        truth = render_crop(seed, size=256, direction="ccw").truth
        pivot = np.asarray(truth["pivot"])
        for scale in truth["scales"]:
            numbers = sorted(scale["numbers"], key=lambda n: n["value"])
            for n in numbers:
                assert float(n["text"].replace(",", ".")) == pytest.approx(n["value"])
            centres = [np.array([(n["box"][0] + n["box"][2]) / 2, (n["box"][1] + n["box"][3]) / 2]) - pivot
                       for n in numbers]
            majors = [np.asarray(m["point"]) - pivot for m in sorted(scale["majors"], key=lambda m: m["value"])]
            for points in (centres, majors):
                for u, v in itertools.pairwise(points):
                    assert _cross(u, v) < 0  # the next larger value lies counter-clockwise
                    checked += 1
    assert checked > 200


def test_secondary_scale_follows_the_primary_direction_and_reads_the_same_needle():
    found = 0
    for seed in range(60):
        params = sample_gauge(np.random.default_rng(seed), clean=True, direction="ccw", secondary=True)
        if len(params.scales) < 2:
            continue
        found += 1
        primary, secondary = params.scales
        assert secondary.direction == primary.direction == "ccw"
        factor, offset = convert(primary.unit, secondary.unit)
        # the same angle reads the converted value on the inner scale
        assert secondary.value_at(params.needle_angle) == pytest.approx(factor * params.value + offset, rel=1e-6, abs=1e-6)
    assert found >= 10


def test_ccw_bands_are_drawn_over_their_values():
    checked = 0
    for seed in range(120):
        params = sample_gauge(np.random.default_rng(seed), clean=True, direction="ccw")
        scale = params.primary
        if not scale.bands:
            continue
        rf = 150.0
        dial = draw_dial(params, rf)
        c = dial.size / 2
        step = scale.minor_step if scale.minor_style != "none" else scale.major_step
        mids = grid(scale.min, scale.max, step)[:-1] + step / 2  # between notches: clear of ticks
        for v in mids:
            bands = [b for b in scale.bands if min(b.start, b.end) + step / 4 < v < max(b.start, b.end) - step / 4]
            inside = [b for b in scale.bands if min(b.start, b.end) - step / 4 <= v <= max(b.start, b.end) + step / 4]
            band = scale.bands[0]
            r = (band.inner + band.outer) / 2
            a = scale.angle_of(float(v))
            x, y = c + rf * r * math.cos(a), c + rf * r * math.sin(a)
            pixel = dial.image[int(y), int(x)].astype(int)
            for b in bands:
                assert np.abs(pixel - b.color).max() < 40, f"seed {seed}: band {b} not at value {v}"
            if not inside:
                assert all(np.abs(pixel - b.color).max() > 40 for b in scale.bands), f"seed {seed}: band colour at {v}"
            checked += 1
        if checked > 300:
            break
    assert checked > 100


def test_ccw_needle_rests_past_the_minimum_on_the_stop_pin_side():
    rested = 0
    for params in _gauges("ccw", range(300)):
        s = params.primary
        if params.stop_pin is not None:
            assert 0 < params.stop_pin[0] - s.start_angle < 0.6  # just clockwise past the minimum
        value, at_stop = needle_state(params, s.min - (s.max - s.min))
        assert at_stop and value == pytest.approx(params.rest_value) and value < s.min
        resting = params.with_value(value, at_stop=True)
        assert resting.needle_angle == pytest.approx(s.start_angle + params.stop_gap)
        if params.at_stop:
            rested += 1
            assert params.value == pytest.approx(params.rest_value)
    assert rested > 5


# --- training labels -----------------------------------------------------------------------------

@pytest.mark.parametrize("direction", ["cw", "ccw"])
def test_arc_end_points_are_the_clockwise_first_and_last_ends(direction: str) -> None:
    for seed in range(6):
        sample = render_crop(seed, size=256, clean=True, direction=direction)
        scale = sample.truth["scales"][0]
        labels = arc_end_points(scale)
        if direction == "cw":  # unchanged: the truth's own start and end
            assert labels == {"start": [scale["start"]], "end": [scale["end"]]}
        first, last = _rectified_angles(sample, [labels["start"][0], labels["end"][0]])
        assert _cw_angle(first, last) == pytest.approx(math.radians(scale["sweep_deg"]), abs=1e-3)


def test_arc_end_points_keep_hidden_and_missing_ends():
    ccw = {"start": [1.0, 2.0], "end": [3.0, 4.0], "direction": "ccw", "end_visible": False}
    assert arc_end_points(ccw) == {"start": [], "end": [[1.0, 2.0]]}
    old = {"start": [1.0, 2.0], "end": [3.0, 4.0]}  # records from before directions are clockwise
    assert arc_end_points(old) == {"start": [[1.0, 2.0]], "end": [[3.0, 4.0]]}
    assert arc_end_points({}) == {"start": None, "end": None}


def test_directions_are_the_cli_choices():
    from gauged.commands import synth

    assert synth.DIRECTIONS == DIRECTIONS
    assert f"{CCW_SHARE:g}" in synth.DIRECTION_HELP


def test_reverse_direction_of_a_constructed_gauge_mirrors_the_printed_numbers():
    params = replace(_gauges("cw", [3])[0], value=-0.4)
    params = replace(params, scales=(replace(_scale(math.radians(135), math.radians(405)), role="primary"),))
    ccw = reverse_direction(params)
    s = ccw.primary
    assert (s.start_angle, s.end_angle) == pytest.approx((math.radians(405), math.radians(135)))
    # -1 bar at the lower right, 0 at the lower left, -0.5 straight up; -0.4 a little left of it
    assert s.angle_of(-0.5) % TAU == pytest.approx(math.radians(270))
    assert ccw.needle_angle % TAU < math.radians(270)
    assert s.value_at(ccw.needle_angle) == pytest.approx(-0.4)
