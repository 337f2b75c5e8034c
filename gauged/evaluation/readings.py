"""End-to-end reading accuracy on a labelled folder, reported the way Reitsma et al. (Tab. 3) do.

Labels: ``labels.json`` (a list) or ``labels.jsonl`` (one object per line) with ``image``, ``reading``,
``min`` and ``max`` per image — the format of ``../shared/datasets/gauge-readings-dev``. The relative
error of an image is ``|pred - reading| / (max - min)``. A refused image counts as a failure; errors
are averaged over attempted images, and over all images with a failure counted as 100%. Images whose
true reading sits at a scale end (needle at rest) are reported separately, so a reader that always
answers "minimum" cannot look good. Synthetic records (``gauged synth images``) also carry the printed
numbers' boxes: the table then breaks the images down by the height of the main scale's numbers as
the camera captured them (:data:`NUMBER_HEIGHTS`; the height in the image times the record's
``render_scale``, so a far gauge's crop upsampled 4x counts at its captured size), which is where
most OCR refusals come from.
"""

from __future__ import annotations

import json
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gauged.reader.ocr.text import quad_height
from gauged.types import StageFailure

# Bins (px) of the median printed-number height of an image's main scale as captured, for the
# breakdown table. Below about 5 px no reader resolves a digit (docs/accuracy.md).
NUMBER_HEIGHTS = ((0.0, 5.0), (5.0, 10.0), (10.0, 14.0), (14.0, 18.0), (18.0, float("inf")))


@dataclass(frozen=True)
class Label:
    image: str
    reading: float
    min: float
    max: float
    number_px: float | None = None  # median height (px) of the main scale's printed numbers, when labelled
    render_scale: float = 1.0  # the share of the image's resolution that was captured (synthetic records)
    unit: str | None = None  # the main scale's unit when the dial prints it (synthetic records)

    @property
    def captured_number_px(self) -> float | None:
        """The numbers' height as the camera captured them: in the image, times ``render_scale``."""
        return None if self.number_px is None else self.number_px * self.render_scale

    @property
    def at_rest(self) -> bool:
        span = self.max - self.min
        return min(abs(self.reading - self.min), abs(self.reading - self.max)) <= 0.005 * span


@dataclass(frozen=True)
class Outcome:
    label: Label
    value: float | None
    failure: StageFailure | None
    unit: str | None = None  # the unit the reader gave the reading
    confidence: float | None = None  # the reader's confidence in the reading
    evidence: dict[str, float] | None = None  # what the reading rests on (gauged.reader.evidence)

    @property
    def relative_error(self) -> float | None:
        if self.value is None:
            return None
        return abs(self.value - self.label.reading) / (self.label.max - self.label.min)


def load_labels(folder: Path) -> list[Label]:
    """Labels of ``folder`` from labels.json or labels.jsonl, in file order."""
    if (folder / "labels.json").is_file():
        items = json.loads((folder / "labels.json").read_text())
    elif (folder / "labels.jsonl").is_file():
        items = [json.loads(line) for line in (folder / "labels.jsonl").read_text().splitlines() if line.strip()]
    else:
        raise FileNotFoundError(f"{folder} has neither labels.json nor labels.jsonl")
    # A synthetic scene without any gauge has nothing to read; it is left out.
    return [_label(item) for item in items if "reading" in item or item.get("gauges")]


def _label(item: dict) -> Label:
    """A label of the dev-set format, or of a ``gauged synth images`` record (its largest gauge)."""
    if "reading" in item:
        return Label(str(item["image"]), float(item["reading"]), float(item["min"]), float(item["max"]))
    gauge = max(item["gauges"], key=lambda g: (g["box"][2] - g["box"][0]) * (g["box"][3] - g["box"][1]))
    return Label(str(item["image"]), float(gauge["value"]), float(gauge["min"]), float(gauge["max"]),
                 _number_height(gauge), float(item.get("render_scale", 1.0)), _printed_unit(gauge))


def _printed_unit(gauge: dict) -> str | None:
    """The unit of a synthetic gauge's primary scale when it is printed on the dial, else None."""
    primary = [s for s in gauge.get("scales", ()) if s.get("role") == "primary"]
    return primary[0]["unit"] if primary and primary[0].get("unit_label") else None


def _number_height(gauge: dict) -> float | None:
    """Median height (px, :func:`gauged.reader.ocr.engine.quad_height`) of the printed numbers of a
    synthetic gauge's primary scale, or None when not labelled."""
    scales = [s for s in gauge.get("scales", ()) if s.get("role") == "primary"]
    heights = [quad_height(n["quad"]) for s in scales for n in s.get("numbers", ()) if n.get("quad")]
    return float(np.median(heights)) if heights else None


def image_path(folder: Path, label: Label) -> Path:
    for candidate in (folder / label.image, folder / "images" / label.image):
        if candidate.is_file():
            return candidate
    return folder / "images" / label.image


@dataclass
class Summary:
    count: int
    failures: int
    mean_error: float  # over attempted
    median_error: float  # over attempted
    mean_error_all: float  # failures counted as 100%
    max_error: float
    by_reason: dict[str, int] = field(default_factory=dict)

    @property
    def failure_rate(self) -> float:
        return self.failures / self.count if self.count else 0.0

    def to_dict(self) -> dict:
        return {"count": self.count, "failures": self.failures, "failure_rate": self.failure_rate,
                "mean_relative_error": self.mean_error, "median_relative_error": self.median_error,
                "mean_relative_error_all": self.mean_error_all, "max_relative_error": self.max_error,
                "failures_by_reason": self.by_reason}


def summarize(outcomes: list[Outcome]) -> Summary:
    errors = np.array([o.relative_error for o in outcomes if o.relative_error is not None], float)
    failures = [o for o in outcomes if o.value is None]
    all_errors = np.concatenate([errors, np.ones(len(failures))]) if outcomes else np.zeros(0)
    reasons = Counter(f"{o.failure.stage}/{o.failure.reason}" for o in failures if o.failure is not None)
    nan = float("nan")
    return Summary(len(outcomes), len(failures),
                   float(errors.mean()) if len(errors) else nan, float(np.median(errors)) if len(errors) else nan,
                   float(all_errors.mean()) if len(all_errors) else nan, float(errors.max()) if len(errors) else nan,
                   dict(sorted(reasons.items())))


def evaluate(labels: list[Label], read: Callable[[Label], tuple]) -> list[Outcome]:
    """Outcomes of ``read(label)``: ``(value, failure)``, ``(value, failure, unit)`` or
    ``(value, failure, unit, confidence[, evidence])``."""
    return [Outcome(label, *read(label)) for label in labels]


def unit_counts(outcomes: list[Outcome]) -> dict[str, int]:
    """Of the readings of dials whose main unit is printed (and labelled): how many carry that unit,
    another one, or none."""
    read = [o for o in outcomes if o.value is not None and o.label.unit is not None]
    right = sum(o.unit == o.label.unit for o in read)
    none = sum(o.unit is None for o in read)
    return {"labelled": len(read), "right": right, "wrong": len(read) - right - none, "none": none}


RIGHT_WITHIN = 0.02  # of the span: a reading this close is right, for the confidence's ROC
WRONG_BEYOND = 0.05  # ... and one this far off is wrong (readings between are left out)


def confidence_auc(outcomes: list[Outcome]) -> dict:
    """How well the reader's confidence separates right readings (within :data:`RIGHT_WITHIN` of the
    span) from wrong ones (off by more than :data:`WRONG_BEYOND`): the area under the ROC curve, the
    chance that a right reading has the higher confidence (ties count half). None without both kinds."""
    scored = [o for o in outcomes if o.value is not None and o.confidence is not None]
    right = np.array([o.confidence for o in scored if o.relative_error <= RIGHT_WITHIN], float)
    wrong = np.array([o.confidence for o in scored if o.relative_error > WRONG_BEYOND], float)
    auc = None
    if len(right) and len(wrong):
        auc = float(((right[:, None] > wrong[None, :]).sum() + 0.5 * (right[:, None] == wrong[None, :]).sum())
                    / (len(right) * len(wrong)))
    return {"right": len(right), "wrong": len(wrong), "auc": auc}


def _height_bin(low: float, high: float) -> str:
    return f"numbers >= {low:g} px" if high == float("inf") else f"numbers {low:g}-{high:g} px"


def report(outcomes: list[Outcome]) -> dict:
    """The whole table: all images, the needle-at-rest subset and the rest, and (when the labels
    carry number boxes) the images by printed-number height as captured."""
    result = {
        "all": summarize(outcomes).to_dict(),
        "needle_at_rest": summarize([o for o in outcomes if o.label.at_rest]).to_dict(),
        "needle_off_rest": summarize([o for o in outcomes if not o.label.at_rest]).to_dict(),
        "images": [{"image": o.label.image, "truth": o.label.reading, "value": o.value,
                    "relative_error": o.relative_error, "number_px": o.label.number_px,
                    "captured_number_px": o.label.captured_number_px, "unit": o.unit, "true_unit": o.label.unit,
                    "confidence": o.confidence, "evidence": o.evidence,
                    "failure": None if o.failure is None else o.failure.to_dict()} for o in outcomes],
    }
    result["confidence"] = confidence_auc(outcomes)
    if any(o.label.unit is not None for o in outcomes):
        result["units"] = unit_counts(outcomes)
    if any(o.label.number_px is not None for o in outcomes):
        result["by_number_height"] = {
            _height_bin(low, high): summarize([o for o in outcomes if o.label.number_px is not None
                                               and low <= o.label.captured_number_px < high]).to_dict()
            for low, high in NUMBER_HEIGHTS}
    return result


def format_table(result: dict) -> str:
    lines = [f"{'subset':<19} {'images':>6} {'failed':>7} {'mean err':>9} {'median':>8} {'mean(all)':>9} {'max err':>8}"]
    rows = [(name, result[name]) for name in ("all", "needle_at_rest", "needle_off_rest")]
    rows += list(result.get("by_number_height", {}).items())
    for name, s in rows:
        lines.append(f"{name:<19} {s['count']:>6} {s['failure_rate']:>7.1%} {s['mean_relative_error']:>9.2%} "
                     f"{s['median_relative_error']:>8.2%} {s['mean_relative_error_all']:>9.2%} {s['max_relative_error']:>8.2%}")
    if "units" in result:
        u = result["units"]
        lines.append(f"units of the {u['labelled']} readings of dials printing theirs: {u['right']} right, "
                     f"{u['wrong']} wrong, {u['none']} none")
    c = result.get("confidence")
    if c and c["auc"] is not None:
        lines.append(f"confidence: ROC AUC {c['auc']:.3f} separating {c['right']} readings within "
                     f"{RIGHT_WITHIN:.0%} from {c['wrong']} off by more than {WRONG_BEYOND:.0%}")
    reasons = result["all"]["failures_by_reason"]
    if reasons:
        lines.append("failures: " + ", ".join(f"{k} {v}" for k, v in reasons.items()))
    worst = sorted((i for i in result["images"] if i["relative_error"] is not None), key=lambda i: -i["relative_error"])
    if worst:
        lines.append("largest errors: " + ", ".join(f"{i['image']} {i['relative_error']:.1%} (read {i['value']:.4g}, "
                                                    f"true {i['truth']:g})" for i in worst[:3]))
    return "\n".join(lines)
