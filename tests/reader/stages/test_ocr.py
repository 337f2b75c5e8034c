"""OCR on rendered dials at a known truth: the numbers it reads are the dial's, at the right places."""

from __future__ import annotations

import math
import socket

import cv2
import numpy as np
import pytest

from gauged.geometry.angles import wrap_angle
from gauged.geometry.dial_frame import dial_angle
from gauged.geometry.ellipse_fit import fit_ellipse
from gauged.reader.ocr.engine import OcrEngine, OcrUnavailable, find_model_files
from gauged.reader.ocr.fragments import merge_fragments
from gauged.reader.ocr.numbers import parse_number
from gauged.reader.ocr.text import ctc_greedy, ctc_log_likelihood, db_boxes, order_quad
from gauged.reader.ocr.units import names_unit, printed_units
from gauged.reader.stages.ellipse import ScaleArc
from gauged.types import Ellipse, StageFailure

INSTALL = "pip install --no-deps rapidocr==3.10.0 (or rapidocr-onnxruntime==1.4.4)"
SIZE = 512
CIRCLE = (SIZE / 2, SIZE / 2, 0.34 * SIZE)


@pytest.fixture(scope="module")
def reader():
    from gauged.reader.stages.ocr import ScaleTextReader

    try:
        return ScaleTextReader(threads=2)
    except OcrUnavailable as exc:
        pytest.skip(f"OCR engine not installed ({exc}); install its models with: {INSTALL}")


def render_dial(values, radial=False, ink=(25, 25, 25), face=(228, 230, 225), scale=0.9, unit="bar",
                radius=0.78, img=None, start_deg=135.0, unit_radius=0.45, unit_scale=0.8):
    """A rectified dial: ticks on CIRCLE, numbers at ``radius`` r (0.78) over 270 degrees clockwise
    from ``start_deg`` (lower left: the gap at the bottom), upright or radial (tops outward), drawn on
    a new face or on ``img``. Returns image and number centres."""
    img = np.full((SIZE, SIZE, 3), face, np.uint8) if img is None else img.copy()
    cx, cy, r = CIRCLE
    centres = []
    for i, v in enumerate(values):
        a = math.radians(start_deg + 270 * i / (len(values) - 1))
        u = np.array([math.cos(a), math.sin(a)])
        cv2.line(img, tuple(np.int32((cx, cy) + r * u)), tuple(np.int32((cx, cy) + 1.1 * r * u)), ink, 3)
        text = f"{v:g}"
        (w, h), _ = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, scale, 2)
        c = np.array([cx, cy]) + radius * r * u
        patch = np.zeros((3 * h + w, 3 * h + w), np.uint8)
        pc = patch.shape[0] / 2
        cv2.putText(patch, text, (int(pc - w / 2), int(pc + h / 2)), cv2.FONT_HERSHEY_SIMPLEX, scale, 255, 2, cv2.LINE_AA)
        if radial:
            turn = cv2.getRotationMatrix2D((pc, pc), -(math.degrees(a) + 90), 1.0)
            patch = cv2.warpAffine(patch, turn, patch.shape[::-1])
        x0, y0 = int(c[0] - pc), int(c[1] - pc)
        region = img[y0: y0 + patch.shape[0], x0: x0 + patch.shape[1]]
        alpha = (patch[: region.shape[0], : region.shape[1], None] / 255.0)
        region[:] = (region * (1 - alpha) + np.array(ink) * alpha).astype(np.uint8)
        centres.append(c)
    if unit:
        thick = 2 if unit_scale >= 0.5 else 1
        (w, h), _ = cv2.getTextSize(unit, cv2.FONT_HERSHEY_SIMPLEX, unit_scale, thick)
        cv2.putText(img, unit, (int(cx - w / 2), int(cy + unit_radius * r + h / 2)), cv2.FONT_HERSHEY_SIMPLEX, unit_scale,
                    ink, thick, cv2.LINE_AA)
    return img, np.array(centres)


def read_numbers(texts):
    return [(b, p.value) for b in merge_fragments(texts) if (p := parse_number(b.text)) and not p.fragment]


def polar(p):
    return math.atan2(p[1] - CIRCLE[1], p[0] - CIRCLE[0]), math.dist(p, CIRCLE[:2])


def matched(numbers, values, centres, tol_deg=4.0):
    """How many printed numbers were read with the right value at the right place (the angle on the
    scale circle, which is what the scale fit uses, within ``tol_deg``), and the rest."""
    good, wrong = 0, []
    for box, value in numbers:
        k = int(np.argmin(np.linalg.norm(centres - np.array(box.center), axis=1)))
        (a, r), (at, rt) = polar(box.center), polar(centres[k])
        place = abs(math.remainder(a - at, 2 * math.pi)) < math.radians(tol_deg) and abs(r - rt) < 0.3 * CIRCLE[2]
        if place and abs(values[k] - value) < 1e-9:
            good += 1
        else:
            wrong.append((box.text, box.center))
    return good, wrong


def test_read_upright_numbers_at_their_places(reader):
    values = [0, 10, 20, 30, 40, 50, 60, 70, 80, 90, 100]
    img, centres = render_dial(values)
    texts = reader.read(img, CIRCLE)
    good, wrong = matched(read_numbers(texts), values, centres)
    assert good >= 10 and not wrong, (good, wrong, [t.text for t in texts])
    assert [u.unit for u in printed_units(texts, CIRCLE)] == ["bar"]


def test_a_unit_printed_near_the_centre_is_read(reader):
    # inside the ring's 0.35 r, where the full pass drops other texts (the synthetic engine's main unit)
    img, _ = render_dial([0, 10, 20, 30, 40, 50], unit="kPa", unit_radius=0.22)
    units = printed_units(reader.read(img, CIRCLE), CIRCLE)
    assert [u.unit for u in units] == ["kPa"] and units[0].radius == pytest.approx(0.22, abs=0.05)


@pytest.mark.parametrize("unit_scale", [0.22, 0.25, 0.28])
def test_small_unit_print_is_read_closer_and_only_units_come_back(reader, unit_scale):
    # 4-5 px letters: the look at the face's centre square at 2.4x the ring square's scale finds them
    img, _ = render_dial([0, 10, 20, 30, 40, 50], unit="kPa", unit_radius=0.3, unit_scale=unit_scale)
    texts = reader.read_units_closer(img, CIRCLE)
    assert [u.unit for u in printed_units(texts, CIRCLE)] == ["kPa"] and all(names_unit(t.text) for t in texts)


def test_read_decimals_and_negative_numbers(reader):
    values = [-1, -0.5, 0, 0.5, 1, 1.5, 2, 2.5]
    img, centres = render_dial(values, scale=0.8, unit="MPa")
    texts = reader.read(img, CIRCLE)
    good, wrong = matched(read_numbers(texts), values, centres)
    assert good >= 7 and not wrong, (good, wrong, [t.text for t in texts])
    assert [u.unit for u in printed_units(texts, CIRCLE)] == ["MPa"]


def test_read_dial_turns_radially_printed_numbers_upright(reader):
    values = [0, 50, 100, 150, 200, 250, 300]
    img, centres = render_dial(values, radial=True, unit="psi")
    texts = reader.read_dial(img, CIRCLE)
    good, wrong = matched(read_numbers(texts), values, centres)
    assert good >= 6 and len(wrong) <= 1, (good, wrong, [t.text for t in texts])


def test_read_hints_find_faint_numbers_the_detector_misses(reader):
    values = [0, 1, 2, 3, 4, 5, 6]
    img, centres = render_dial(values, ink=(150, 150, 150), face=(205, 205, 200), scale=0.55, unit="")
    img = cv2.GaussianBlur(img, (5, 5), 1.2)
    without = matched(read_numbers(reader.read(img, CIRCLE)), values, centres)[0]
    good, wrong = matched(read_numbers(reader.read(img, CIRCLE, hints=centres + 2.0)), values, centres)
    assert good >= max(5, without) and not wrong, (without, good, wrong)


def arc_from_labels(labels) -> ScaleArc:
    majors = labels.points["major"]
    ellipse = fit_ellipse(majors, shape="auto")
    start = float(dial_angle(ellipse, labels.points["start"])[0])
    end = float(dial_angle(ellipse, labels.points["end"])[0])
    return ScaleArc(ellipse, ellipse.center, start, end, wrap_angle(start, end), majors, 0.0, False)


def test_read_markers_reads_rendered_dials_in_place(reader):
    from gauged.training.dial_renderer import render_crop

    checked = read_total = correct_total = 0
    for seed in (3, 11, 21, 40, 55, 70):
        image, labels = render_crop(seed, 448)
        arc = arc_from_labels(labels)
        read = reader.read_markers(image, arc, labels.points["numbers"])
        if isinstance(read, StageFailure):
            continue
        markers, _unit = read
        truth = {round(v, 6) for v in np.linspace(labels.min_value, labels.max_value, len(labels.points["major"]))}
        correct = [m for m in markers if round(m.value, 6) in truth]
        read_total, correct_total = read_total + len(markers), correct_total + len(correct)
        for marker in correct:  # a correctly read number sits by its own printed place, in crop pixels
            centre = np.array([(marker.box[0] + marker.box[2]) / 2, (marker.box[1] + marker.box[3]) / 2])
            nearest = np.linalg.norm(labels.points["numbers"] - centre, axis=1).min()
            assert nearest < 0.12 * arc.ellipse.a
        checked += len(correct) >= 3
    assert checked >= 4, "OCR read at least three right numbers on fewer than four of six renders"
    assert correct_total >= 0.85 * read_total, f"{correct_total} of {read_total} numbers read are the dial's"


def test_read_markers_reads_upright_text_of_a_dial_whose_gap_is_not_at_the_bottom(reader, monkeypatch):
    """Numbers printed upright on a face whose scale gap is at the top (synthetic dev 000111): turned
    gap-down, the numbers stand on their heads ("0.8" read "8", "1.6" read "9"); the view the image's
    way up reads them."""
    import gauged.reader.ocr.rectified as rectified

    values = [0, 0.4, 0.8, 1.2, 1.6]
    img, centres = render_dial(values, scale=0.8, unit="", start_deg=315.0)
    e = Ellipse(*CIRCLE[:2], CIRCLE[2], CIRCLE[2], 0.0)
    start, end = math.radians(-45.0), math.radians(-135.0)  # the gap at the top, -90 degrees
    arc = ScaleArc(e, e.center, start, end, wrap_angle(start, end), np.zeros((0, 2)), 0.0, False)

    def right(read):
        assert not isinstance(read, StageFailure), read
        markers, _ = read
        return sum(1 for m in markers if any(abs(m.value - v) < 1e-9 and np.linalg.norm(
            np.array([(m.box[0] + m.box[2]) / 2, (m.box[1] + m.box[3]) / 2]) - c) < 20 for v, c in zip(values, centres)))

    assert right(reader.read_markers(img, arc, centres)) >= 4
    monkeypatch.setattr(rectified, "UPRIGHT_TURN", math.pi)  # gap-down view only, as before
    read = reader.read_markers(img, arc, centres)
    assert isinstance(read, StageFailure) or right(read) < 3


def test_read_markers_keeps_numbers_beyond_an_inferred_gap(reader, monkeypatch):
    """Ends inferred from a notch gap may cut a full-circle dial's numbers in two (a real dial
    indicator: 8 and 9 fell beyond the gap and were dropped as off the progression). With inferred
    ends every number read goes on to the scale stage; with found ends the progression filter runs.
    (In the gap-down view: the view the image's way up, where this dial's gap really is, would read
    every number.)"""
    import gauged.reader.ocr.rectified as rectified

    monkeypatch.setattr(rectified, "UPRIGHT_TURN", math.pi)
    values = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9]
    img, centres = render_dial(values, unit="")
    e = Ellipse(*CIRCLE[:2], CIRCLE[2], CIRCLE[2], 0.0)
    start, end = math.radians(-60.0), math.radians(-120.0)  # a gap at the top, between 4 and 5
    read = {}
    for inferred in (True, False):
        arc = ScaleArc(e, e.center, start, end, wrap_angle(start, end), np.zeros((0, 2)), 0.0, inferred)
        markers = reader.read_markers(img, arc, centres)
        assert not isinstance(markers, StageFailure), markers
        read[inferred] = {m.value for m in markers[0]}
    assert len(read[True]) >= 8 and read[True] & {0, 1, 2, 3, 4} and read[True] & {5, 6, 7, 8, 9}  # both sides
    assert len(read[False]) < len(read[True])


def test_read_markers_no_text_on_a_blank_dial(reader):
    blank = np.full((448, 448, 3), 200, np.uint8)
    e = Ellipse(224, 224, 180, 180, 0)
    arc = ScaleArc(e, e.center, 2.4, 0.8, wrap_angle(2.4, 0.8), np.zeros((0, 2)), 0.0, False)
    failure = reader.read_markers(blank, arc, np.zeros((0, 2)))
    assert not failure and failure.stage == "ocr" and failure.reason == "no_text"


def test_read_markers_no_numbers_when_only_words(reader):
    img = np.full((448, 448, 3), 225, np.uint8)
    cv2.putText(img, "WIKA", (170, 120), cv2.FONT_HERSHEY_SIMPLEX, 1.2, (20, 20, 20), 3, cv2.LINE_AA)
    e = Ellipse(224, 224, 180, 180, 0)
    arc = ScaleArc(e, e.center, 2.4, 0.8, wrap_angle(2.4, 0.8), np.zeros((0, 2)), 0.0, False)
    failure = reader.read_markers(img, arc, np.zeros((0, 2)))
    assert not failure and failure.reason == "no_numbers"


def test_engine_loads_and_reads_without_network(monkeypatch):
    try:
        find_model_files()
    except OcrUnavailable as exc:
        pytest.skip(f"OCR engine not installed ({exc}); {INSTALL}")

    def refuse(*args, **kwargs):
        raise AssertionError("the OCR engine tried to open a network connection")

    monkeypatch.setattr(socket.socket, "connect", refuse)
    monkeypatch.setattr(socket, "create_connection", refuse)
    engine = OcrEngine(threads=1)
    line = np.full((48, 160, 3), 235, np.uint8)
    cv2.putText(line, "160", (30, 36), cv2.FONT_HERSHEY_SIMPLEX, 1.2, (20, 20, 20), 3, cv2.LINE_AA)
    rec = engine.recognize([line])[0]
    assert rec.text == "160" and rec.digits == "160" and rec.score > 0.9


def test_engine_reads_each_distinct_line_once_until_it_forgets():
    try:
        engine = OcrEngine(threads=1, memo=2)
    except OcrUnavailable as exc:
        pytest.skip(f"OCR engine not installed ({exc}); {INSTALL}")
    lines = []
    for text in ("160", "25", "4"):
        line = np.full((48, 120, 3), 235, np.uint8)
        cv2.putText(line, text, (20, 36), cv2.FONT_HERSHEY_SIMPLEX, 1.2, (20, 20, 20), 3, cv2.LINE_AA)
        lines.append(line)
    a, b, a_again = engine.recognize([lines[0], lines[1], lines[0].copy()])
    assert (a.text, b.text) == ("160", "25") and a_again is a  # one network reading for both copies
    assert engine.recognize([lines[1]])[0] is b  # answered from the memo
    engine.recognize([lines[2]])  # the memo holds two lines: the least recently used ("160") goes
    assert engine.recognize([lines[1]])[0] is b and engine.recognize([lines[0]])[0] is not a
    engine.forget()
    fresh = engine.recognize([lines[1]])[0]
    assert fresh is not b and fresh.text == "25"

    # Camera threads share the engine: each has its own memo, which another's forget() leaves alone.
    import threading

    seen = {}

    def other_camera():
        seen["first"] = engine.recognize([lines[1]])[0]
        engine.forget()

    worker = threading.Thread(target=other_camera)
    worker.start()
    worker.join()
    assert seen["first"] is not fresh  # the other thread's memo did not hold this thread's reading
    assert engine.recognize([lines[1]])[0] is fresh  # and its forget() did not empty this one

    # Text detection is remembered the same way: the same image is detected once until forget()
    page = np.full((96, 320, 3), 235, np.uint8)
    cv2.putText(page, "160 bar", (20, 60), cv2.FONT_HERSHEY_SIMPLEX, 1.2, (20, 20, 20), 3, cv2.LINE_AA)
    first = engine.detect(page, max_side=320)
    assert first and engine.detect(page.copy(), max_side=320)[0] is first[0]
    assert engine.detect(page, max_side=256)[0] is not first[0]  # other settings: detected again
    engine.forget()
    again = engine.detect(page, max_side=320)
    assert again[0] is not first[0] and np.allclose(again[0].quad, first[0].quad)


def test_find_model_files_names_missing_and_unknown_packages(monkeypatch):
    from gauged.reader.ocr import engine as ocr_engine

    with pytest.raises(ValueError):
        find_model_files("tesseract")
    monkeypatch.setitem(ocr_engine.MODEL_SETS, "no_such_ocr_package_xyz", ("a.onnx", "b.onnx"))
    with pytest.raises(OcrUnavailable):
        find_model_files("no_such_ocr_package_xyz")


def test_ctc_greedy_merges_repeats_drops_blanks_and_restricts_the_alphabet():
    chars = ["", "1", "6", "0", "字", " "]
    probs = np.full((7, 6), 0.01)
    for t, c in enumerate([1, 1, 0, 4, 3, 3, 0]):  # "1", "1", blank, "字", "0", "0", blank
        probs[t, c] = 0.9
    probs[3, 2] = 0.5  # second best for the CJK column: "6"
    assert ctc_greedy(probs, np.arange(6), chars)[0] == "1字0"
    text, score = ctc_greedy(probs, np.array([0, 1, 2, 3]), chars)
    assert text == "160" and score == pytest.approx((0.9 + 0.5 + 0.9) / 3)
    assert ctc_greedy(np.eye(6)[[0, 0]], np.arange(6), chars) == ("", 0.0)


def _collapse(path):
    """The string a CTC alignment spells: repeats merged, blanks (0) dropped."""
    return [c for k, c in enumerate(path) if c and (k == 0 or c != path[k - 1])]


def test_ctc_log_likelihood_sums_the_probability_of_every_alignment():
    import itertools

    rng = np.random.default_rng(4)
    probs = rng.dirichlet(np.ones(3), size=5)  # 5 columns, blank + 2 characters
    logp = np.log(probs)
    for labels in ([1], [1, 2], [2, 2], [1, 2, 1], []):
        brute = sum(np.prod([probs[t, c] for t, c in enumerate(path)])
                    for path in itertools.product(range(3), repeat=5) if _collapse(path) == labels)
        assert math.exp(ctc_log_likelihood(logp, labels)) == pytest.approx(brute, rel=1e-9)
    # "11" needs a blank between its two characters: three columns at least
    assert ctc_log_likelihood(logp[:2], [1, 1]) == -math.inf


def test_engine_scores_strings_other_than_its_best_reading():
    try:
        engine = OcrEngine(threads=1)
    except OcrUnavailable as exc:
        pytest.skip(f"OCR engine not installed ({exc}); {INSTALL}")
    line = np.full((48, 120, 3), 235, np.uint8)
    cv2.putText(line, "-25", (14, 36), cv2.FONT_HERSHEY_SIMPLEX, 1.2, (20, 20, 20), 3, cv2.LINE_AA)
    rec = engine.recognize([line])[0]
    assert rec.digits == "-25" and rec.digit_logp.shape[1] == len(engine.digit_chars) + 1
    best = engine.log_likelihood(rec, "-25")
    assert best > math.log(0.5)  # the printed string is likely...
    assert best > engine.log_likelihood(rec, "25") + 2 > engine.log_likelihood(rec, "-35") + 2  # ...and others are not
    assert engine.log_likelihood(rec, "-2a") == -math.inf  # a letter is not a number character


def test_db_boxes_finds_rotated_text_regions_and_scales_them():
    prob = np.zeros((100, 200), np.float32)
    cv2.rectangle(prob, (20, 40), (80, 55), 0.9, -1)
    rot = cv2.boxPoints(((150, 50), (40, 12), 30)).astype(np.int32)
    cv2.fillPoly(prob, [rot], 0.8)
    cv2.rectangle(prob, (5, 90), (6, 91), 0.9, -1)  # too small
    quads = sorted(db_boxes(prob, (2.0, 2.0)), key=lambda q: q.quad[:, 0].mean())
    assert len(quads) == 2
    centre = quads[0].quad.mean(axis=0)
    assert centre == pytest.approx([101, 95], abs=3)  # (50.5, 47.5) * 2
    assert quads[0].score == pytest.approx(0.9, abs=0.1)
    width = np.linalg.norm(quads[0].quad[1] - quads[0].quad[0])
    assert width > 2 * 61  # unclipped beyond the 61 px region


def test_order_quad_starts_top_left_clockwise():
    pts = np.float32([[10, 20], [0, 0], [10, 0], [0, 20]])
    assert order_quad(pts).tolist() == [[0, 0], [10, 0], [10, 20], [0, 20]]


def test_polar_strip_maps_strip_pixels_back_onto_the_ring():
    from gauged.reader.ocr.regions import RING, polar_strip

    img = np.full((SIZE, SIZE, 3), 230, np.uint8)
    cx, cy, r = CIRCLE
    dot = (cx + 0.8 * r * math.cos(-math.pi / 2), cy + 0.8 * r * math.sin(-math.pi / 2))  # top of the dial
    cv2.circle(img, (int(dot[0]), int(dot[1])), 4, (0, 0, 0), -1)
    strip, to_image = polar_strip(img, CIRCLE)
    h, w = strip.shape[:2]
    assert w == int(2 * math.pi * 0.8 * r) and h == int((RING[1] - RING[0]) * r)
    ys, xs = np.nonzero(strip[:, :, 0] < 100)
    # clockwise from the gap at the bottom: the top of the dial is half way along the strip
    assert xs.mean() == pytest.approx(w / 2, abs=3)
    assert to_image(np.array([[xs.mean() + 0.5, ys.mean() + 0.5]]))[0] == pytest.approx(dot, abs=2.0)
    start = to_image(np.array([[0.0, 0.0], [0.0, h]]))
    assert start[0] == pytest.approx((cx, cy + RING[1] * r), abs=1e-3)  # outer radius, at the gap
    assert start[1] == pytest.approx((cx, cy + RING[0] * r), abs=1e-3)


def test_ink_box_finds_the_characters_at_a_point():
    from gauged.reader.ocr.regions import ink_box

    win = np.full((120, 120, 3), 210, np.uint8)
    cv2.putText(win, "-12", (30, 70), cv2.FONT_HERSHEY_SIMPLEX, 0.8, (120, 120, 120), 2, cv2.LINE_AA)
    ys, xs = np.nonzero(win[:, :, 0] < 170)
    cv2.line(win, (5, 110), (5, 60), (120, 120, 120), 2)  # a tick far from the number
    ink = ink_box(win, (float(xs.mean()), float(ys.mean())), r=174.0)
    x0, y0, x1, y1 = ink.box
    assert x0 <= xs.min() and x1 >= xs.max() + 1 and y0 <= ys.min() and y1 >= ys.max() + 1  # the whole "-12"
    assert x0 > 10  # not the tick
    assert ink_box(win, (100.0, 20.0), r=174.0) is None  # nothing printed there


def _printed(text: str, turn_deg: float) -> tuple[np.ndarray, tuple[float, float]]:
    """A window with ``text`` printed turned by ``turn_deg`` about its centre, and its first glyph's centre."""
    win = np.full((160, 160, 3), 215, np.uint8)
    for k, glyph in enumerate(text):  # spaced as printed digits are, clear of each other when turned
        cv2.putText(win, glyph, (52 + 24 * k, 92), cv2.FONT_HERSHEY_SIMPLEX, 1.0, (60, 60, 60), 2, cv2.LINE_AA)
    turn = cv2.getRotationMatrix2D((80.0, 80.0), turn_deg, 1.0)
    win = cv2.warpAffine(win, turn, (160, 160), borderValue=(215, 215, 215))
    first = turn @ np.array([62.0, 80.0, 1.0])  # the first glyph's centre, turned with it
    return win, (float(first[0]), float(first[1]))


def test_ink_box_tells_a_glyph_of_a_turned_number():
    """Read alone, the "4" of a "40" printed at 60 degrees is a number of its own: glyphs of a turned
    "30, 40, 50" read "3, 4, 5" made a line ten times too flat (synthetic fresh13 000296, 86% off).
    The ink box says so; an upright number grows to its whole width and a lone digit is just itself."""
    from gauged.reader.ocr.regions import ink_box

    win, first = _printed("40", 60.0)
    ink = ink_box(win, first, r=174.0)
    assert ink is not None and ink.turned_part
    win, first = _printed("40", 0.0)
    ink = ink_box(win, first, r=174.0)
    assert ink is not None and not ink.turned_part
    assert ink.box[2] - ink.box[0] > 1.5 * (ink.box[3] - ink.box[1])  # both digits
    win, first = _printed("5", 60.0)
    ink = ink_box(win, first, r=174.0)
    assert ink is not None and not ink.turned_part


def test_split_spaced_cuts_two_numbers_read_as_one_box():
    from gauged.reader.ocr.dial_text import _split_spaced
    from gauged.reader.ocr.text import TextBox

    quad = np.float32([[0, 0], [70, 0], [70, 20], [0, 20]])
    parts = _split_spaced([TextBox("200 220", 0.9, quad)])
    assert [p.text for p in parts] == ["200", "220"]
    assert parts[0].center[0] == pytest.approx(15, abs=1) and parts[1].center[0] == pytest.approx(55, abs=1)
    assert [p.text for p in _split_spaced([TextBox("1 6", 0.9, quad)])] == ["1 6"]  # one number, kept whole


def test_dedupe_prefers_a_confident_whole_number_to_its_part_read_alone():
    """The ink box at a hint held only the "5" of a tilted "25" and read it with a higher score than
    the detector's "25" (synthetic dev 000098); the whole number wins. A doubtful long reading
    ("4600" for 40 and 60) or a loose box far larger than the part does not."""
    from gauged.reader.ocr.dial_text import _dedupe
    from gauged.reader.ocr.text import TextBox

    def box(text, score, x0, y0, x1, y1):
        return TextBox(text, score, np.float32([[x0, y0], [x1, y0], [x1, y1], [x0, y1]]))

    whole, part = box("25", 0.99, 300, 351, 352, 408), box("5", 1.0, 314, 361, 341, 385)
    assert [b.text for b in _dedupe([part, whole])] == ["25"]
    assert [b.text for b in _dedupe([box("10", 1.0, 100, 100, 140, 130), box("0", 0.9, 120, 102, 138, 128)])] == ["10"]
    doubtful = box("4600", 0.67, 0, 0, 100, 30)
    assert {b.text for b in _dedupe([doubtful, box("60", 1.0, 50, 2, 98, 28)])} == {"4600", "60"}
    loose = box("20", 0.94, 50, 108, 206, 268)  # 160 px around a 40 px "20" and the "0" below it
    assert [b.text for b in _dedupe([loose, box("0", 0.99, 105, 167, 142, 211)])] == ["0"]  # the better score
    same = box("140.", 0.92, 0, 0, 60, 30)  # the same digits: the better score stays, as before
    assert [b.text for b in _dedupe([same, box("140", 0.99, 2, 2, 58, 28)])] == ["140"]


def test_quick_pass_gives_way_when_numbers_outside_the_ring_were_not_hinted(reader):
    """A degC ring inside a degF one (the real thermometer of gauge-readings-dev): the crop model
    hinted only the inner numbers. The quick pass reads them, but the unhinted numbers outside the
    ring send it on to the full pass; with nothing outside it ends there."""
    inner = [-40, -20, 0, 20, 40, 60]
    img, centres = render_dial(inner, unit="C")
    texts, numbers = reader.read_quick(img, CIRCLE, centres)
    assert texts is not None and len(read_numbers(numbers)) >= 4  # nothing outside: quick pass done
    both, _ = render_dial([-40, 0, 40, 80, 120, 160], img=img, unit=None, radius=1.3, scale=0.8)
    texts, numbers = reader.read_quick(both, CIRCLE, centres)
    assert texts is None and len(read_numbers(numbers)) >= 4  # its numbers go on to the full pass


def _int8_detector():
    from gauged.reader.factory import OCR_DET_INT8_MODEL
    from gauged.reader.onnx_model import packaged_model_path

    path = packaged_model_path(OCR_DET_INT8_MODEL)
    if not path.is_file():
        pytest.skip(f"{path} is not shipped; make it with python -m gauged.training.quantize_ocr")
    try:
        find_model_files()
    except OcrUnavailable as exc:
        pytest.skip(f"OCR engine not installed ({exc}); {INSTALL}")
    return path


def test_int8_detector_runs_only_with_the_float_file_it_was_made_from(tmp_path, caplog):
    import onnx

    int8 = _int8_detector()
    engine = OcrEngine(threads=1, int8_detector=int8)
    if engine.model_files[0] != int8:
        pytest.skip(f"the shipped int8 detector was made from another OCR wheel than {find_model_files()[0]}")
    model = onnx.load(str(int8))
    for prop in model.metadata_props:
        if prop.key == "gauged":
            prop.value = prop.value.replace('"source_sha256": "', '"source_sha256": "0')
    other = tmp_path / "other_int8.onnx"
    onnx.save(model, str(other))
    with caplog.at_level("WARNING", logger="gauged.reader.ocr.engine"):
        assert OcrEngine(threads=1, int8_detector=other).model_files[0] == find_model_files()[0]
        assert OcrEngine(threads=1, int8_detector=tmp_path / "missing.onnx").model_files[0] == find_model_files()[0]
    assert "made from another file" in caplog.text and "is missing" in caplog.text


def test_int8_detector_finds_the_texts_the_float_detector_finds():
    int8 = _int8_detector()
    quantized, exact = OcrEngine(threads=2, int8_detector=int8), OcrEngine(threads=2)
    if quantized.model_files[0] != int8:
        pytest.skip("the shipped int8 detector was made from another OCR wheel")
    misplaced, checked = [], 0
    for values, radial in (([0, 10, 20, 30, 40, 50, 60], False), ([0, 0.5, 1, 1.5, 2, 2.5], True),
                           ([-20, 0, 20, 40, 60, 80, 100, 120], False)):
        image, _ = render_dial(values, radial=radial)
        found = np.array([q.quad.mean(axis=0) for q in quantized.detect(image, max_side=384)])
        for box in exact.detect(image, max_side=384):
            if box.score < 0.6:  # at the detector's box threshold (0.5) either model may drop it
                continue
            checked += 1
            centre, width = box.quad.mean(axis=0), float(np.ptp(box.quad[:, 0]))
            shift = float(np.linalg.norm(found - centre, axis=1).min())
            if shift > max(2.0, 0.1 * width):  # px in the 512 px rectified dial
                misplaced.append((centre.round(1).tolist(), round(shift, 1)))
    # Every text the float detector finds clearly, the int8 one finds at the same place. It may add
    # a box (a tick stroke) that the recogniser then reads as no text.
    assert checked >= 25 and misplaced == []


def test_quick_pass_leaves_out_a_lone_turned_glyph_and_gives_way_to_many(reader):
    """One number printed turned among upright ones (its first glyph, read alone, is a number of its
    own) is left out of the quick pass, which still reads the dial: its face detection finds the
    turned "20" whole. A dial printing all its numbers turned goes on to the full pass."""
    values = list(range(0, 101, 10))
    upright, centres = render_dial(values)
    radial, _ = render_dial(values, radial=True)
    mixed = upright.copy()
    cx, cy = centres[2]  # "20", at the left: printed radially it lies on its side
    h = int(0.17 * CIRCLE[2])
    mixed[int(cy - h):int(cy + h), int(cx - h):int(cx + h)] = radial[int(cy - h):int(cy + h), int(cx - h):int(cx + h)]
    numbers, glyphs = reader.read_at_hints(mixed, centres, CIRCLE)
    assert glyphs == 1 and 20 not in [v for _, v in read_numbers(numbers)] and len(numbers) == 10
    texts, _ = reader.read_quick(mixed, CIRCLE, centres)
    assert texts is not None and sorted(v for _, v in read_numbers(texts)) == values
    numbers, glyphs = reader.read_at_hints(radial, centres, CIRCLE)
    assert glyphs > 0.25 * (len(numbers) + glyphs)
    assert reader.read_quick(radial, CIRCLE, centres)[0] is None
