"""The minus net's data and its validation figure, on constructed truths."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from gauged.reader.ocr.minus_net import INPUT_WIDTH
from gauged.training.minus_lines import MARGINS, _truth_cuts


def test_every_number_but_0_is_cut_at_its_true_quad_with_its_printed_sign(tmp_path):
    from gauged.synth.crop import render_crop

    for seed in range(5_000_100, 5_000_160):  # a render with negative numbers (the calibration seeds' range)
        sample = render_crop(seed, 448, masks=False, direction="ccw")
        texts = [n["text"].replace("\u2212", "-") for s in sample.truth["scales"] for n in s["numbers"]]
        if any(t.startswith("-") for t in texts):
            break
    else:
        pytest.fail("no counter-clockwise render with negative numbers among 60 seeds")
    cv2.imwrite(str(tmp_path / "a.jpg"), sample.image)
    label = {"image": "a.jpg", "gauges": [sample.truth]}
    rows = _truth_cuts((str(tmp_path), json.dumps(label), 0))
    expected = [t.startswith("-") for t in texts if float(t.lstrip("-").replace(",", ".")) != 0]
    assert [r["minus"] for r in rows] == expected
    assert all(r["x"].shape == (len(MARGINS), 32, INPUT_WIDTH) and r["x"].dtype == np.uint8 for r in rows)


def test_the_operating_point_is_the_recall_where_half_a_percent_of_the_numbers_without_pass():
    pytest.importorskip("torch")
    from gauged.training.minus_train import operating_point

    without = np.linspace(-10, 0, 1000)  # 0.5% of them (5) lie above -0.05
    printed = np.array([-1.0, 0.5, 2.0, 3.0])
    faces = np.zeros(1004, bool)
    faces[:1000:2] = True  # every other number without faces the ticks: left out, 500 remain
    odds = np.concatenate([without, printed])
    minus = np.concatenate([np.zeros(1000, bool), np.ones(4, bool)])
    point = operating_point(odds, minus, faces)
    assert point["without"] == 500 and point["minus"] == 4
    assert -0.2 < point["threshold"] < 0 and point["recall"] == 0.75
