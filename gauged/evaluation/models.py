"""Model metrics of the shipped ONNX files on the real sets (``gauged eval models``), numpy + onnxruntime.

- Detector on ``substation-dials``: per frame, the best IoU between the labelled dial box and any
  detection; mean IoU and recall at IoU 0.5.
- Crop model on ``needle-polygons/valid``: needle mask IoU at the photo's resolution (logits resized
  bilinearly, cut at 0.5) and the needle direction error (mask axis oriented away from the image
  centre, see :func:`gauged.evaluation.model_metrics.mask_direction`); once with each photo given
  whole, once cut to its detected gauge as the reader does (:mod:`gauged.evaluation.gauge_crops`).
- Crop model on a synthetic crop shard: major-notch recall and unassigned share within 4 px at
  448 px, start/end notch found; with the notch check (``notch_check.onnx``) where it ships, and
  of the crop model's peaks alone.
- Speed: median of 100 runs after 10 warm-up runs, at the configured thread count.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from gauged.evaluation.gauge_crops import best_gauge_crop, crop_logits_in_frame
from gauged.evaluation.model_metrics import (
    angle_error_deg,
    best_iou,
    mask_direction,
    mask_iou,
    match_points,
    needle_mask_at,
)
from gauged.evaluation.timing import median_s
from gauged.reader.factory import (
    CROP_MODEL,
    DETECTOR_MODEL,
    MINUS_NET_MODEL,
    NOTCH_CHECK_MODEL,
    NUMBER_NET_MODEL,
    OCR_DET_INT8_MODEL,
    helper_model_path,
    model_path,
)
from gauged.reader.onnx_model import ModelNotAvailable, OnnxModel, to_model_input
from gauged.reader.stages.detect import GaugeDetector
from gauged.reader.stages.keypoints import CropKeypoints, decode_crop_maps
from gauged.reader.stages.notch_check import NotchCheck
from gauged.types import StageFailure


def median_ms(fn, runs: int = 100, warmup: int = 10) -> float:
    return 1000 * median_s(fn, runs, warmup)


def detector_metrics(detector: GaugeDetector, root: Path) -> dict:
    from gauged.training.real_data import load_substation_dials

    samples = load_substation_dials(root)
    return {"frames": len(samples), **_box_ious(detector, [(s.image_path, s.box) for s in samples])}


def _box_ious(detector: GaugeDetector, labelled) -> dict:
    """Mean IoU of the best detection with each labelled box, and the share found at IoU 0.5, over
    ``labelled`` (image path, box) pairs."""
    ious = []
    for path, box in labelled:
        found = detector.detect(cv2.imread(str(path), cv2.IMREAD_COLOR))
        ious.append(best_iou(box, [] if isinstance(found, StageFailure) else [d.box for d in found]))
    ious_arr = np.asarray(ious)
    return {"mean_box_iou": float(ious_arr.mean()), "recall_iou50": float((ious_arr >= 0.5).mean())}


def closeup_metrics(detector: GaugeDetector, folder: Path) -> dict:
    """Detection on rendered close-ups (``gauged synth images --kind crop``: one gauge filling most of
    each image, ``labels.jsonl``): IoU of the best box with the gauge's box (front and case, clipped),
    the convention of the real substation labels."""
    import json

    records = [json.loads(line) for line in (folder / "labels.jsonl").read_text().splitlines()]
    return {"images": len(records), **_box_ious(detector, [(folder / r["image"], r["gauges"][0]["box"]) for r in records])}


def needle_metrics(crop: OnnxModel, root: Path, detector: GaugeDetector | None = None) -> dict:
    """Needle mask IoU and direction on the ``valid`` photos, each given whole to the crop model and,
    with a ``detector``, also cut to its detected gauge first as the reader does (``reader_crop``)."""
    from gauged.training.real_data import load_needle_split

    size = crop.input_size
    samples = load_needle_split(root, "valid")
    result = _needle_scores(crop, samples, lambda image: None)
    if detector is not None:
        result["reader_crop"] = _needle_scores(crop, samples, lambda image: best_gauge_crop(detector, image, size))
    return result


def whole_photo_needle_logits(crop: OnnxModel, image: np.ndarray) -> np.ndarray:
    """The needle logits (h, w) of a photo given whole to the crop model, resized to its input."""
    size = crop.input_size
    return crop(to_model_input(cv2.resize(image, (size, size), interpolation=cv2.INTER_AREA)))[-1]


def _needle_scores(crop: OnnxModel, samples, crop_of) -> dict:
    """IoU and direction over ``samples``; ``crop_of(image)`` gives the reader's crop of a photo, or
    None to give the crop model the whole photo."""
    size = crop.input_size
    ious, errors, whole = [], [], 0
    for sample in samples:
        image, mask = sample.load()
        gauge = crop_of(image)
        if gauge is None:
            whole += 1
            pred = needle_mask_at(whole_photo_needle_logits(crop, image), mask.shape)
        else:
            pred = crop_logits_in_frame(crop(to_model_input(gauge.image))[-1], gauge, size, mask.shape) > 0
        truth = mask > 0
        ious.append(mask_iou(pred, truth))
        centre = (pred.shape[1] / 2, pred.shape[0] / 2)
        a, b = mask_direction(pred, centre), mask_direction(truth, centre)
        errors.append(180.0 if a is None or b is None else angle_error_deg(a, b))
    errors_arr = np.asarray(errors)
    return {"photos": len(ious), "whole_photos": whole, "mean_mask_iou": float(np.mean(ious)),
            "direction_within_3deg": float((errors_arr <= 3).mean()),
            "median_direction_error_deg": float(np.median(errors_arr))}


def render_scale(source: str, size: int) -> float | None:
    """The share of its resolution a shard crop was captured at (:mod:`gauged.synth.truth`,
    ``render_scale``), recomputed from its seed for engine crops (``synth/<seed>``), else None."""
    if not source.startswith("synth/"):
        return None
    from gauged.synth.crop import sample_crop_spec

    _, upsampling = sample_crop_spec(np.random.default_rng(int(source.split("/")[1])), size)
    return 1.0 / upsampling


class _NotchCounts:
    def __init__(self) -> None:
        self.crops = self.matched = self.labelled = self.predicted = self.ends = self.ends_found = 0

    def add(self, match, ends: list[bool]) -> None:
        """One crop: its major-notch match and, per labelled end, whether it was found."""
        self.crops += 1
        self.matched += match.matched
        self.labelled += match.labelled
        self.predicted += match.predicted
        self.ends += len(ends)
        self.ends_found += sum(ends)

    def to_dict(self) -> dict:
        return {"crops": self.crops, "notch_recall_4px_at_448": self.matched / max(1, self.labelled),
                "unassigned_share": (self.predicted - self.matched) / max(1, self.predicted),
                "start_end_found": self.ends_found / max(1, self.ends)}


def notch_metrics(crop: OnnxModel, shard_dir: Path, limit: int = 1000, notch_check: NotchCheck | None = None) -> dict:
    """Notch recall, unassigned share and ends found on a shard's crops; ``by_capture`` splits the
    engine's crops into those captured at full size and those rendered small and upsampled (a third
    of the engine's crops, at 12-60% of their size: far gauges, whose notches may not be resolved).
    With ``notch_check`` the major peaks are those it keeps, and ``peaks_alone`` holds the same
    figures of the crop model's peaks, from the same run of the crop model."""
    from gauged.training.shards import open_crop_shard

    shard = open_crop_shard(shard_dir)
    size = crop.input_size
    tol = 4.0 * size / 448
    variants = ["checked", "alone"] if notch_check is not None else ["alone"]
    groups = {v: {"all": _NotchCounts(), "full size": _NotchCounts(), "upsampled": _NotchCounts()} for v in variants}
    for index in range(min(limit, len(shard))):
        sample = shard.sample(index)
        captured = render_scale(sample.source, sample.image.shape[0])
        names = ["all"] + ([] if captured is None else ["full size" if captured == 1.0 else "upsampled"])
        image = sample.image if sample.image.shape[0] == size else cv2.resize(sample.image, (size, size))
        model_input = to_model_input(image)
        logits = crop(model_input)
        alone = decode_crop_maps(logits, size, require_notches=False)
        keypoints = {"alone": alone}
        if notch_check is not None:
            keypoints["checked"] = notch_check(model_input, logits, alone)
        for variant in variants:
            match, found = _notch_match(keypoints[variant], sample, tol)
            for name in names:
                groups[variant][name].add(match, found)
    results = {variant: _notch_figures(counts) for variant, counts in groups.items()}
    if notch_check is None:
        return results["alone"]
    return {**results["checked"], "peaks_alone": results["alone"]}


def _notch_match(keypoints: CropKeypoints, sample, tol: float):
    """The major-notch match of one crop's keypoints and, per labelled end, whether it was found."""
    match = match_points(keypoints.major.points, np.asarray(sample.points.get("major") or []).reshape(-1, 2), tol)
    found = []
    for name in ("start", "end"):
        truth = sample.points.get(name)
        if truth:
            peaks = getattr(keypoints, name)
            found.append(len(peaks) > 0 and np.linalg.norm(peaks.points[0] - truth[0]) <= tol)
    return match, found


def _notch_figures(groups: dict[str, _NotchCounts]) -> dict:
    result = groups["all"].to_dict()
    if groups["full size"].crops or groups["upsampled"].crops:
        result["by_capture"] = {name: groups[name].to_dict() for name in ("full size", "upsampled")}
    return result


def evaluate_models(data: Path, synth: Path | None, threads: int, models_dir: Path | None = None,
                    closeups: Path | None = None) -> dict:
    crop = OnnxModel(model_path(CROP_MODEL, models_dir), threads)
    try:
        detector_model: OnnxModel | None = OnnxModel(model_path(DETECTOR_MODEL, models_dir), threads)
    except ModelNotAvailable:
        detector_model = None  # reported as missing rather than failing the crop-model figures
    # Every ONNX file the reader ships: the two models, the notch check, the OCR's int8 text detector and the number net.
    try:
        notch_check: NotchCheck | None = NotchCheck(helper_model_path(NOTCH_CHECK_MODEL, models_dir), threads)
    except ModelNotAvailable:
        notch_check = None  # the notch figures are then the crop model's peaks alone
    files = [m.path for m in (crop, detector_model, notch_check) if m is not None]
    files += [p for p in (helper_model_path(n, models_dir) for n in (OCR_DET_INT8_MODEL, NUMBER_NET_MODEL, MINUS_NET_MODEL)) if p.is_file()]
    result: dict = {"files_mb": round(sum(p.stat().st_size for p in files) / 2**20, 2),
                    "files": [p.name for p in files]}
    crop_input = np.zeros((crop.input_size, crop.input_size, 3), np.float32)
    result["speed_ms"] = {"crop_model": median_ms(lambda: crop(crop_input))}
    if notch_check is not None and synth is not None:
        result["speed_ms"]["crop_model_and_notch_check"] = _checked_crop_ms(crop, notch_check, synth)
    if detector_model is not None:
        detector = GaugeDetector(detector_model)
        frame = np.full((720, 1280, 3), 128, np.uint8)
        result["speed_ms"]["detector_1280x720"] = median_ms(lambda: detector.detect(frame))
        if (data / "substation-dials").is_dir():
            result["detector"] = detector_metrics(detector, data / "substation-dials")
        if closeups is not None:
            result["closeups"] = closeup_metrics(detector, closeups)
    else:
        result["detector"] = "missing: gauged/models/detector.onnx is not trained yet"
    if (data / "needle-polygons").is_dir():
        result["needle"] = needle_metrics(crop, data / "needle-polygons",
                                          GaugeDetector(detector_model) if detector_model is not None else None)
    if synth is not None:
        result["notches"] = notch_metrics(crop, synth, notch_check=notch_check)
    return result


def _checked_crop_ms(crop: OnnxModel, notch_check: NotchCheck, shard_dir: Path) -> float:
    """Crop model, peak decoding and notch check on the shard's first crop, as the reader runs them."""
    from gauged.training.shards import open_crop_shard

    image = open_crop_shard(shard_dir).sample(0).image
    model_input = to_model_input(cv2.resize(image, (crop.input_size, crop.input_size)))

    def run() -> None:
        logits = crop(model_input)
        notch_check(model_input, logits, decode_crop_maps(logits, crop.input_size, require_notches=False))

    return median_ms(run)


def format_models(result: dict) -> str:
    speed = result["speed_ms"]
    lines = [f"model files: {result['files_mb']} MB ({', '.join(result.get('files', []))})",
             f"speed (median of 100): crop {speed['crop_model']:.1f} ms"
             + (f" (with peaks and notch check {speed['crop_model_and_notch_check']:.1f} ms)"
                if "crop_model_and_notch_check" in speed else "")
             + (f", detector {speed['detector_1280x720']:.1f} ms per 1280x720 frame" if "detector_1280x720" in speed else "")]
    if isinstance(result.get("detector"), str):
        lines.append(f"detector: {result['detector']}")
    elif "detector" in result:
        d = result["detector"]
        lines.append(f"detector on {d['frames']} substation frames: mean box IoU {d['mean_box_iou']:.3f}, "
                     f"recall@0.5 {d['recall_iou50']:.1%}")
    if "closeups" in result:
        c = result["closeups"]
        lines.append(f"detector on {c['images']} rendered close-ups: mean box IoU {c['mean_box_iou']:.3f}, "
                     f"recall@0.5 {c['recall_iou50']:.1%}")
    if "needle" in result:
        n = result["needle"]
        lines.append(f"needle on {n['photos']} real photos, whole: mean mask IoU {n['mean_mask_iou']:.3f}, direction within "
                     f"3 deg {n['direction_within_3deg']:.1%} (median error {n['median_direction_error_deg']:.1f} deg)")
        if "reader_crop" in n:
            r = n["reader_crop"]
            lines.append(f"needle on {r['photos']} real photos, cut to the detected gauge as the reader does "
                         f"({r['whole_photos']} with no detection given whole): mean mask IoU {r['mean_mask_iou']:.3f}, "
                         f"direction within 3 deg {r['direction_within_3deg']:.1%} "
                         f"(median error {r['median_direction_error_deg']:.1f} deg)")
    if "notches" in result:
        for title, t in (("", result["notches"]), (" (the crop model's peaks alone)", result["notches"].get("peaks_alone"))):
            if t is None:
                continue
            checked = " after the notch check" if title == "" and "peaks_alone" in result["notches"] else ""
            lines.append(f"notches on {t['crops']} synthetic crops{checked}{title}: recall {t['notch_recall_4px_at_448']:.1%}, "
                         f"unassigned {t['unassigned_share']:.1%}, start/end found {t['start_end_found']:.1%}")
            for name, g in t.get("by_capture", {}).items():
                lines.append(f"  {g['crops']} crops captured {name}: recall {g['notch_recall_4px_at_448']:.1%}, "
                             f"unassigned {g['unassigned_share']:.1%}, start/end found {g['start_end_found']:.1%}")
    return "\n".join(lines)
