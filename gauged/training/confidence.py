"""Fit the reading confidence: a logistic model of "right" over each reading's evidence terms.

Input: the JSON of ``gauged eval readings --json`` on labelled sets the held-out sets do not share a
seed with (each attempted image carries its :func:`gauged.reader.evidence.evidence` terms). A reading
within :data:`gauged.evaluation.readings.RIGHT_WITHIN` of the span is right (1), anything else wrong
(0). The model is scikit-learn's L2 logistic regression on standardised terms; only its coefficients
ship (``gauged/models/confidence.json``), read by :class:`gauged.reader.evidence.Calibration` with numpy.

    gauged synth images --kind crop --size 448 --count 1000 --seed 8200000 --out data/conf-cw
    gauged synth images --kind crop --size 448 --count 1000 --seed 8300000 --direction ccw --out data/conf-ccw
    gauged eval readings --data data/conf-cw --json > conf-cw.json    # and conf-ccw.json
    python -m gauged.training.confidence fit --evals conf-cw.json conf-ccw.json --out gauged/models/confidence.json
    python -m gauged.training.confidence check --evals held-cw.json held-ccw.json   # AUC on other sets
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from gauged.evaluation.readings import RIGHT_WITHIN, WRONG_BEYOND
from gauged.reader.evidence import Calibration

C = 1.0  # inverse L2 strength of the logistic fit


def rows(evals: list[Path]) -> tuple[list[dict[str, float]], np.ndarray, np.ndarray]:
    """The evidence terms, relative errors and old confidences of every attempted image in ``evals``."""
    terms, errors, trust = [], [], []
    for path in evals:
        for image in json.loads(path.read_text())["images"]:
            if image["value"] is None or not image.get("evidence"):
                continue
            terms.append(image["evidence"])
            errors.append(image["relative_error"])
            trust.append(image["evidence"]["trust"])
    return terms, np.asarray(errors, float), np.asarray(trust, float)


def fit(terms: list[dict[str, float]], errors: np.ndarray, c: float = C) -> Calibration:
    from sklearn.linear_model import LogisticRegression

    names = tuple(sorted({name for t in terms for name in t}))
    x = np.array([[t.get(name, 0.0) for name in names] for t in terms], float)
    mean, scale = x.mean(axis=0), x.std(axis=0)
    scale[scale < 1e-9] = 1.0  # a term constant on the training sets carries no weight
    y = (errors <= RIGHT_WITHIN).astype(int)
    model = LogisticRegression(C=c, max_iter=2000).fit((x - mean) / scale, y)
    return Calibration(names, mean, scale, model.coef_[0], float(model.intercept_[0]))


def auc(scores: np.ndarray, errors: np.ndarray) -> tuple[float | None, int, int]:
    """ROC AUC of ``scores`` separating readings within RIGHT_WITHIN from those beyond WRONG_BEYOND."""
    right, wrong = scores[errors <= RIGHT_WITHIN], scores[errors > WRONG_BEYOND]
    if not len(right) or not len(wrong):
        return None, len(right), len(wrong)
    greater = (right[:, None] > wrong[None, :]).sum() + 0.5 * (right[:, None] == wrong[None, :]).sum()
    return float(greater / (len(right) * len(wrong))), len(right), len(wrong)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    fit_p = sub.add_parser("fit", help="fit the calibration on eval JSON files and write it")
    fit_p.add_argument("--evals", type=Path, nargs="+", required=True)
    fit_p.add_argument("--out", type=Path, required=True)
    fit_p.add_argument("--c", type=float, default=C, help=f"inverse L2 strength (default {C:g})")
    check_p = sub.add_parser("check", help="AUC of the trust and of a calibration on eval JSON files")
    check_p.add_argument("--evals", type=Path, nargs="+", required=True)
    check_p.add_argument("--calibration", type=Path, default=None, help="default: the shipped one")
    args = parser.parse_args(argv)

    if args.command == "fit":
        terms, errors, _ = rows(args.evals)
        if not len(errors):
            print("no attempted image with evidence terms in the eval files", file=sys.stderr)
            return 2
        calibration = fit(terms, errors, args.c)
        args.out.write_text(json.dumps(calibration.to_dict(), indent=1) + "\n")
        scores = np.array([calibration.probability(t) for t in terms])
        value, right, wrong = auc(scores, errors)
        print(f"fitted on {len(errors)} readings ({right} right, {wrong} wrong): training AUC {value:.3f}; "
              f"wrote {args.out}")
        return 0
    calibration = Calibration.load(args.calibration) if args.calibration else Calibration.load()
    if calibration is None:
        print("no calibration file", file=sys.stderr)
        return 2
    for label, paths in [(str(p), [p]) for p in args.evals] + ([("union", args.evals)] if len(args.evals) > 1 else []):
        terms, errors, trust = rows(paths)
        scores = np.array([calibration.probability(t) for t in terms])
        calibrated, right, wrong = auc(scores, errors)
        old, _, _ = auc(trust, errors)
        print(f"{label}: {right} right, {wrong} wrong; AUC trust {_fmt(old)}, calibrated {_fmt(calibrated)}")
    return 0


def _fmt(value: float | None) -> str:
    return "n/a" if value is None else f"{value:.3f}"


if __name__ == "__main__":
    sys.exit(main())
