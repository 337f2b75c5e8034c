"""OCR on rendered dials at a known truth: the numbers it reads are the dial's, at the right places."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("rapidocr_onnxruntime", reason="OCR engine not installed (make installs rapidocr-onnxruntime --no-deps)")

from gauged.geometry.angles import wrap_angle  # noqa: E402
from gauged.geometry.dial_frame import dial_angle  # noqa: E402
from gauged.geometry.ellipse_fit import fit_ellipse  # noqa: E402
from gauged.reader.ellipse import ScaleArc  # noqa: E402
from gauged.reader.ocr import ScaleTextReader  # noqa: E402
from gauged.training.dial_renderer import render_crop  # noqa: E402
from gauged.types import StageFailure  # noqa: E402


@pytest.fixture(scope="module")
def reader() -> ScaleTextReader:
    return ScaleTextReader(threads=2)


def arc_from_labels(labels) -> ScaleArc:
    majors = labels.points["major"]
    ellipse = fit_ellipse(majors, shape="auto")
    start = float(dial_angle(ellipse, labels.points["start"])[0])
    end = float(dial_angle(ellipse, labels.points["end"])[0])
    return ScaleArc(ellipse, ellipse.center, start, end, wrap_angle(start, end), majors, 0.0, False)


def test_read_markers_reads_the_dial_numbers_in_place(reader):
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
        for marker in correct:  # a correctly read number sits by its own printed place
            centre = np.array([(marker.box[0] + marker.box[2]) / 2, (marker.box[1] + marker.box[3]) / 2])
            nearest = np.linalg.norm(labels.points["numbers"] - centre, axis=1).min()
            assert nearest < 0.12 * arc.ellipse.a
        checked += len(correct) >= 3
    assert checked >= 2, "OCR read at least three right numbers on fewer than two of six renders"
    assert correct_total >= 0.6 * read_total, f"{correct_total} of {read_total} numbers read are the dial's"


def test_read_markers_no_text_on_a_blank_dial(reader):
    blank = np.full((448, 448, 3), 200, np.uint8)
    from gauged.types import Ellipse

    e = Ellipse(224, 224, 180, 180, 0)
    arc = ScaleArc(e, e.center, 2.4, 0.8, wrap_angle(2.4, 0.8), np.zeros((0, 2)), 0.0, False)
    failure = reader.read_markers(blank, arc, np.zeros((0, 2)))
    assert not failure and failure.stage == "ocr" and failure.reason == "no_text"
