"""The evidence behind one reading, as numbers, and the calibrated confidence they give.

The reading stage's trust (:func:`gauged.reader.stages.reading.read_value`) gates what is refused; it
is a product of part scores and ranks wrong readings poorly (docs/accuracy.md). :func:`evidence`
lists what a reading rests on (needle, notch ring, numbers agreeing, the look that found the scale)
and :class:`Calibration` turns it into the probability that the reading is right, a logistic model
fitted on synthetic renders (``gauged train confidence``) and shipped as
``gauged/models/confidence.json``. Without that file the confidence is the trust.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from gauged.geometry.dial_frame import normalized_radius
from gauged.reader.gauge_read import GaugeRead
from gauged.reader.ocr.numbers import MINUS_LIKE
from gauged.reader.stages.scale_direction import added_signs, direction_margin, overruled_signs

# How the reading's scale was found (GaugeRead.look), most direct first.
LOOKS = ("first", "number_net", "likely_scale", "hint", "pivot", "between_numbers", "known", "locked")
CALIBRATION_FILE = Path(__file__).resolve().parent.parent / "models" / "confidence.json"
# Scales the calibration was not fitted on (its renders are read by OCR): a configured or locked scale
# keeps the trust as its confidence, which the tracker weighs readings by (calibrated, the bundled
# recordings' smoothed errors grew, 0.78 -> 1.13% on one gauge, their raw readings unchanged).
UNCALIBRATED_LOOKS = ("known", "locked")


def evidence(read: GaugeRead) -> dict[str, float]:
    """What a read reading rests on, one number per term (empty when ``read`` has no value)."""
    if read.value is None or read.needle is None or read.arc is None or not read.scales:
        return {}
    needle, arc, scale, value = read.needle, read.arc, read.scales[0], read.value
    span = abs(scale.max_value - scale.min_value) or 1.0
    agreeing = [m for m in scale.markers if m.inlier]
    values = [m.value for m in agreeing]
    terms = {
        "trust": value.trust,
        "needle_mask": float(needle.mask_score),
        "needle_offset": float(needle.offset),
        # how far the needle's mask reaches towards the scale ring (1 on it): a short stroke is often
        # the counterweight or a shadow taken for the needle, read 180 degrees off
        "needle_reach": float(normalized_radius(arc.ellipse, np.asarray([needle.line.tip], float))[0]),
        "notch_fit_share": float(arc.fit_share),
        "notches": float(len(arc.notches)),
        "ends_inferred": float(arc.ends_inferred),
        "arc_span": float(arc.span / (2 * math.pi)),
        "numbers": float(len(scale.markers)),
        "agreeing": float(scale.inliers),
        "agreeing_share": scale.inliers / len(scale.markers) if scale.markers else 1.0,
        "rms_share": float(scale.rms_value / span),
        "coverage": (max(values) - min(values)) / span if len(values) >= 2 else 0.0,
        "number_score": float(np.mean([m.score for m in agreeing])) if agreeing else 1.0,
        "negative_numbers": float(any(v < 0 for v in values)),
        "signs_overruled": float(overruled_signs(scale)),
        "signs_added": float(added_signs(scale)),
        "minus_read": float(sum(m.text.strip()[:1] in MINUS_LIKE for m in read.markers if m.text.strip())),
        # agreeing numbers the reading puts above 0 before which the number net read a minus (its signs
        # not counted: too few of the dial's numbers showed one), the doubt of a mirror-image reading
        "net_minus_against": float(sum(m.net_minus and m.value > 0 for m in agreeing)),
        "decimal_numbers": float(any("." in m.text or "," in m.text for m in agreeing)),
        "falling": float(scale.slope < 0),
        "direction_margin": float(direction_margin(arc, scale)),
        "full_circle": float(scale.full_circle),
        "edge": float(min(abs(value.position), abs(1 - value.position))),
        "crop_px": float(math.log2(max(1.0, read.box[2] - read.box[0]))),
        "checked_notches": float(read.checked_notches),
    }
    for look in LOOKS:
        terms[f"look_{look}"] = float(read.look == look)
    return terms


@dataclass(frozen=True)
class Calibration:
    """A logistic model over :func:`evidence` terms: p(right) = sigmoid(w . (x - mean) / scale + b)."""

    terms: tuple[str, ...]
    mean: np.ndarray
    scale: np.ndarray
    weights: np.ndarray
    bias: float

    @classmethod
    def load(cls, path: Path = CALIBRATION_FILE) -> "Calibration | None":
        """The shipped calibration, or None when the file is not there (confidence stays the trust)."""
        if not path.is_file():
            return None
        data = json.loads(path.read_text())
        return cls(tuple(data["terms"]), np.asarray(data["mean"], float), np.asarray(data["scale"], float),
                   np.asarray(data["weights"], float), float(data["bias"]))

    def to_dict(self) -> dict:
        return {"terms": list(self.terms), "mean": self.mean.tolist(), "scale": self.scale.tolist(),
                "weights": self.weights.tolist(), "bias": self.bias}

    def probability(self, terms: dict[str, float]) -> float:
        x = np.array([terms.get(name, 0.0) for name in self.terms], float)
        z = float(self.weights @ ((x - self.mean) / self.scale) + self.bias)
        return 1.0 / (1.0 + math.exp(-max(-50.0, min(50.0, z))))

    def apply(self, read: GaugeRead) -> GaugeRead:
        """``read`` with its value's confidence the calibrated probability (its trust kept); a read on a
        configured or locked scale (:data:`UNCALIBRATED_LOOKS`) is returned as it is."""
        if read.look in UNCALIBRATED_LOOKS:
            return read
        terms = evidence(read)
        if terms:
            read.value = replace(read.value, confidence=self.probability(terms))
        return read
