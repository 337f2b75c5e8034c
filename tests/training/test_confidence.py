"""Fitting the confidence calibration recovers a term that separates right from wrong readings."""

from __future__ import annotations

import json

import numpy as np

from gauged.reader.evidence import Calibration
from gauged.training.confidence import auc, main, rows


def _eval_file(path, rng, count=400):
    images = []
    for _ in range(count):
        right = rng.random() < 0.7
        error = rng.uniform(0, 0.01) if right else rng.uniform(0.06, 0.5)
        mask = rng.normal(0.9 if right else 0.6, 0.05)
        images.append({"value": 1.0, "relative_error": error,
                       "evidence": {"trust": float(rng.random()), "needle_mask": float(mask), "constant": 1.0}})
    images.append({"value": None, "relative_error": None, "evidence": None})  # a refusal is left out
    path.write_text(json.dumps({"images": images}))
    return path


def test_fit_finds_the_separating_term_and_check_reports_it(tmp_path, capsys):
    rng = np.random.default_rng(0)
    train, held = _eval_file(tmp_path / "train.json", rng), _eval_file(tmp_path / "held.json", rng)
    out = tmp_path / "confidence.json"

    assert main(["fit", "--evals", str(train), "--out", str(out)]) == 0
    calibration = Calibration.load(out)
    terms, errors, trust = rows([held])
    assert len(errors) == 400  # the refusal is not a row
    scores = np.array([calibration.probability(t) for t in terms])
    assert auc(scores, errors)[0] > 0.99 and abs(auc(trust, errors)[0] - 0.5) < 0.1
    weights = dict(zip(calibration.terms, calibration.weights))
    assert weights["needle_mask"] > 1.0 and weights["constant"] == 0.0

    assert main(["check", "--evals", str(held), "--calibration", str(out)]) == 0
    printed = capsys.readouterr().out.splitlines()[-1]
    assert printed.startswith(str(held)) and float(printed.rsplit("calibrated ", 1)[1]) > 0.99
