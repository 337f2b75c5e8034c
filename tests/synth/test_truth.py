"""The ground truth of renders lands on what is drawn: notches on ink, numbers on ink, needle angle
(for scales rising either way)."""

from __future__ import annotations

import math
from dataclasses import replace

import cv2
import numpy as np
import pytest

from gauged.synth.crop import render_crop
from gauged.synth.projection import apply_homography, pose_homography, to_cv
from gauged.synth.scene import render_frame

SEEDS = range(12)
DIRECTIONS = ("cw", "ccw")  # scales rising clockwise (the default) and counter-clockwise


def _bilinear(img: np.ndarray, x: float, y: float) -> np.ndarray:
    """Sample ``img`` at a project-convention point (pixel centres at +0.5)."""
    patch = cv2.getRectSubPix(img, (1, 1), (x - 0.5, y - 0.5))
    return patch.reshape(-1).astype(float)


def _inkness(pixel: np.ndarray, face: np.ndarray, ink: np.ndarray) -> float:
    """Where ``pixel`` lies between the face colour (0) and the ink colour (1)."""
    d = ink - face
    return float(np.dot(pixel - face, d) / max(np.dot(d, d), 1e-9))


def _notches_on_ink(sample, kind: str) -> tuple[int, int]:
    """(notch points of ``kind`` ("majors" or "minors") checked, those on ink) of a clean 512 px
    render; scales with too little contrast, points at the edge and points by the needle are skipped."""
    near_needle = cv2.dilate((sample.needle_mask > 0).astype(np.uint8), np.ones((7, 7), np.uint8))
    face = np.asarray(sample.params.face.color, float)
    checked, on_ink = 0, 0
    for scale_truth, scale in zip(sample.truth["scales"], sample.params.scales):
        ink = np.asarray(scale.color, float)
        if np.linalg.norm(ink - face) < 60:
            continue  # too little contrast to tell ink from face in colour alone
        for notch in scale_truth[kind]:
            x, y = notch["point"]
            if not (2 <= x < 510 and 2 <= y < 510) or near_needle[int(y), int(x)]:
                continue
            checked += 1
            on_ink += _inkness(_bilinear(sample.image, x, y), face, ink) > 0.3
    return checked, on_ink


@pytest.mark.parametrize("direction", DIRECTIONS)
@pytest.mark.parametrize("seed", SEEDS)
def test_truth_major_notches_land_on_ink(seed: int, direction: str) -> None:
    checked, on_ink = _notches_on_ink(render_crop(seed, size=512, clean=True, direction=direction), "majors")
    assert checked >= 3
    assert on_ink / checked >= 0.95, f"{on_ink}/{checked} notch points on ink"


@pytest.mark.parametrize("direction", DIRECTIONS)
@pytest.mark.parametrize("seed", SEEDS)
def test_truth_number_boxes_hold_their_ink(seed: int, direction: str) -> None:
    sample = render_crop(seed, size=512, clean=True, direction=direction)
    face = np.asarray(sample.params.face.color, float)
    for scale_truth, scale in zip(sample.truth["scales"], sample.params.scales):
        ink = np.asarray(scale.numbers.color, float)
        if np.linalg.norm(ink - face) < 60:
            continue
        d = (ink - face) / np.dot(ink - face, ink - face)
        inkness = (sample.image.astype(float) - face) @ d
        for number in scale_truth["numbers"]:
            x0, y0, x1, y1 = (int(round(v)) for v in number["box"])
            if x0 < 0 or y0 < 0 or x1 > 512 or y1 > 512 or (x1 - x0) * (y1 - y0) < 16:
                continue
            inside = inkness[y0:y1, x0:x1]
            assert (inside > 0.5).mean() > 0.08, f"number {number['text']} box holds no ink"
            # the box is tight: a 4 px ring just outside it holds less ink (per pixel) than the inside
            outer = inkness[max(0, y0 - 4):y1 + 4, max(0, x0 - 4):x1 + 4]
            ring_ink = (outer > 0.5).sum() - (inside > 0.5).sum()
            ring_area = outer.size - inside.size
            assert ring_ink / max(ring_area, 1) < (inside > 0.5).mean()


def _needle_pixels(sample) -> np.ndarray:
    """Pixels where the needle is drawn: difference of two renders with a black and a white needle."""
    pl = sample.spec.gauges[0]
    images = []
    for color in ((0, 0, 0), (255, 255, 255)):
        needle = replace(pl.params.needle, color=color, hub_color=color, shadow_strength=0.0)
        spec = replace(sample.spec, gauges=(replace(pl, params=replace(pl.params, needle=needle)),) + sample.spec.gauges[1:])
        images.append(render_frame(spec, output_scale=sample.output_scale).image.astype(float))
    return np.abs(images[1] - images[0]).mean(axis=2) / 255.0


def _axis_angle(weight: np.ndarray, pivot: np.ndarray, direction: np.ndarray, min_radius: float) -> float:
    """Angle of the weighted principal axis through ``pivot`` of the pixels on ``direction``'s side."""
    ys, xs = np.nonzero(weight > 0.05)
    pts = np.column_stack([xs + 0.5, ys + 0.5]) - pivot
    w = weight[ys, xs]
    keep = (np.linalg.norm(pts, axis=1) > min_radius) & (pts @ direction > 0)
    assert keep.sum() > 20
    pts, w = pts[keep], w[keep]
    _, evecs = np.linalg.eigh((pts * w[:, None]).T @ pts)
    axis = evecs[:, 1] * np.sign(evecs[:, 1] @ direction)
    return math.atan2(axis[1], axis[0])


@pytest.mark.parametrize("direction", DIRECTIONS)
@pytest.mark.parametrize("seed", range(16))
def test_truth_reading_points_along_drawn_needle(seed: int, direction: str) -> None:
    sample = render_crop(seed, size=448, clean=True, direction=direction)
    truth, params = sample.truth, sample.params
    pl = sample.spec.gauges[0]
    # the true reading converted back through the primary scale: its point on the scale circle
    scale = params.primary
    angle = scale.angle_of(truth["value"])
    h = np.diag([sample.output_scale, sample.output_scale, 1.0]) @ pose_homography(pl.pose)
    pivot, on_scale = apply_homography(h, np.array([[0.0, 0.0], scale.radius * np.array([math.cos(angle), math.sin(angle)])]))
    expected = math.atan2(on_scale[1] - pivot[1], on_scale[0] - pivot[0])
    assert abs(math.remainder(expected - truth["needle"]["angle"], 2 * math.pi)) < 1e-5

    weight = _needle_pixels(sample)
    hub_px = params.needle.hub_radius * pl.pose.diameter_px / 2 * sample.output_scale
    if pl.pose.tilt < math.radians(40):
        # in the image: a wide needle seen very obliquely is no longer symmetric about its axis,
        # so the principal axis is only a fair test of the image angle at moderate tilt
        fitted = _axis_angle(weight, pivot, np.array([math.cos(expected), math.sin(expected)]), 1.5 * hub_px + 3)
        error = abs(math.degrees(math.remainder(fitted - expected, 2 * math.pi)))
        assert error < 0.2, f"needle drawn at {math.degrees(fitted):.3f} deg in the image, truth {math.degrees(expected):.3f}"
    # on the rectified dial (any tilt): warp the drawn needle back to the frontal view
    rf = 200.0
    to_dial = np.array([[rf, 0.0, 300.0], [0.0, rf, 300.0], [0.0, 0.0, 1.0]]) @ np.linalg.inv(h)
    frontal = cv2.warpPerspective(weight.astype(np.float32), to_cv(to_dial), (600, 600), flags=cv2.INTER_LINEAR)
    fitted = _axis_angle(frontal, np.array([300.0, 300.0]), np.array([math.cos(angle), math.sin(angle)]),
                         1.5 * rf * params.needle.hub_radius + 3)
    error = abs(math.degrees(math.remainder(fitted - angle, 2 * math.pi)))
    assert error < 0.2, f"needle drawn at {math.degrees(fitted):.3f} deg on the dial, truth {math.degrees(angle):.3f}"


@pytest.mark.parametrize("direction", DIRECTIONS)
@pytest.mark.parametrize("seed", range(6))
def test_truth_needle_mask_matches_drawn_needle(seed: int, direction: str) -> None:
    sample = render_crop(seed, size=448, clean=True, direction=direction)
    drawn = _needle_pixels(sample) > 0.5
    mask = sample.needle_mask > 0
    # the hub is drawn in both renders but is not part of the mask: compare outside the hub only
    inter = (drawn & mask).sum()
    assert inter / max(mask.sum(), 1) > 0.9


def test_truth_scale_points_lie_on_scale_ellipse() -> None:
    for seed in range(8):
        truth = render_crop(seed, size=448).truth
        for scale in truth["scales"]:
            e = scale["ellipse"]
            c, s = math.cos(e["theta"]), math.sin(e["theta"])
            for major in scale["majors"] + [{"point": scale["start"]}, {"point": scale["end"]}]:
                dx, dy = major["point"][0] - e["cx"], major["point"][1] - e["cy"]
                u, v = (dx * c + dy * s) / e["a"], (-dx * s + dy * c) / e["b"]
                assert abs(u * u + v * v - 1.0) < 0.01


def test_crop_records_say_at_what_share_of_their_resolution_they_were_captured() -> None:
    from gauged.synth.dataset import render_item

    # seed 3: sample 0 is rendered at 24 px and upsampled to 64, sample 4 at its full size
    far = render_item(("crop", 3, 0, 0, 0, 64, False))[1]
    near = render_item(("crop", 3, 4, 0, 0, 64, False))[1]
    assert math.isclose(far["render_scale"], 24 / 64, abs_tol=1e-4)
    assert near["render_scale"] == 1.0
    assert render_item(("scene", 3, 0, 160, 120, 64, False))[1]["render_scale"] == 1.0


@pytest.mark.parametrize("seed", [129, 131, 132])
def test_notches_behind_an_occluder_are_marked_hidden(seed: int) -> None:
    from gauged.synth.crop import sample_crop_spec

    spec, scale = sample_crop_spec(np.random.default_rng(seed), 256)
    assert spec.occluders == 1
    covered = render_frame(spec, output_scale=scale)
    bare = render_frame(replace(spec, occluders=0), output_scale=scale)

    def majors(result):
        return [m for s in result.truths[0].to_dict()["scales"] for m in s["majors"]]

    size = covered.image.shape[0]
    inside = [0 <= m["point"][0] < size and 0 <= m["point"][1] < size for m in majors(bare)]
    assert [m["visible"] for m in majors(bare)] == inside  # nothing hides them but the frame edge
    hidden = [m for m in majors(covered) if not m["visible"] and 0 <= m["point"][0] < size and 0 <= m["point"][1] < size]
    assert hidden
    change = np.abs(covered.image.astype(int) - bare.image.astype(int)).max(axis=2)
    for m in hidden:  # each hidden notch lies where the occluder changed the picture
        x, y = (int(v) for v in m["point"])
        assert change[max(0, y - 1):y + 2, max(0, x - 1):x + 2].max() > 30


def test_training_labels_keep_only_the_notches_the_image_shows() -> None:
    from gauged.training.prerender import synth_points

    truth = render_crop(132, 256, masks=False).truth
    scales = truth["scales"]
    seen = [m["point"] for s in scales for m in s["majors"] if m["visible"]]
    assert 0 < len(seen) < sum(len(s["majors"]) for s in scales)
    assert synth_points(truth)["major"] == seen
    primary = scales[0]
    hidden_start = dict(truth, scales=[dict(primary, start_visible=False)] + scales[1:])
    assert synth_points(hidden_start)["start"] == []  # labelled: no start to be seen
    old = dict(truth, scales=[{k: v for k, v in primary.items() if not k.endswith("_visible")}])
    assert synth_points(old)["start"] == [primary["start"]]  # records from before visibility count as seen


@pytest.mark.parametrize("direction", DIRECTIONS)
@pytest.mark.parametrize("seed", SEEDS)
def test_truth_minor_notches_land_on_ink(seed: int, direction: str) -> None:
    sample = render_crop(seed, size=512, clean=True, direction=direction)
    for scale_truth, scale in zip(sample.truth["scales"], sample.params.scales):
        if scale.minor_style == "none":
            assert scale_truth["minors"] == []
    checked, on_ink = _notches_on_ink(sample, "minors")
    if checked:  # 9 of the 12 seeds have minor notches in contrast
        assert on_ink / checked >= 0.9, f"{on_ink}/{checked} minor notch points on ink"


def test_training_labels_carry_the_seen_minor_notches() -> None:
    from gauged.training.prerender import synth_points

    truth = render_crop(7, 256, masks=False).truth
    minors = [m["point"] for s in truth["scales"] for m in s["minors"] if m["visible"]]
    assert len(minors) > 10
    assert synth_points(truth)["minor"] == minors
    old = dict(truth, scales=[{k: v for k, v in s.items() if k != "minors"} for s in truth["scales"]])
    assert synth_points(old)["minor"] is None  # records from before minor notches: not labelled
