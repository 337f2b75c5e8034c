"""Which major notches the crop model misses, and what its unassigned peaks sit on.

    python bench/investigations/notch_kinds.py --shard data/synth-val-256 [--model gauged/models/crop.onnx] [--group "full size"] [--check]

``--shard`` is the held-out crop shard `gauged eval models` scores (`python -m
gauged.training.prerender crops --seed 1000000 --count 500 --size 256 --out data/synth-val-256`).
Each crop is rendered again from its seed, so every notch's kind is known: its scale's role, its
drawing style, whether a number is printed at it, how far apart the scale's majors are, and where
the minor notches are. Peaks are the reader's (`decode_crop_maps`, threshold 0.3), and with
``--check`` only those the notch check keeps (`gauged/models/notch_check.onnx`); the tolerance is
issue 4's 4 px at 448 px. Prints:

- recall by kind of labelled major notch (a peak within the tolerance of it);
- every peak sorted by what it lies on: a labelled major, a hidden major, a labelled major 1-2
  tolerances off, a minor notch (within one tolerance, or two), a number, the needle, or none of those;
- how close each labelled major's nearest other notch (major or minor) lies in the image the camera
  captured (crop pixels times the capture scale): two notches under about 2 px apart there are one
  blur, whatever the model.

About 15 s for the 353 full-size crops.
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter, defaultdict
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # bench/, for common
import numpy as np  # noqa: E402
from common import header  # noqa: E402

from gauged.evaluation.models import render_scale  # noqa: E402
from gauged.reader.onnx_model import OnnxModel, packaged_model_path, to_model_input  # noqa: E402
from gauged.reader.stages.keypoints import decode_crop_maps  # noqa: E402
from gauged.reader.stages.notch_check import NotchCheck  # noqa: E402
from gauged.synth.crop import render_crop  # noqa: E402
from gauged.training.shards import open_crop_shard  # noqa: E402

GROUPS = ("all", "full size", "upsampled")


def nearest(points: np.ndarray, p: np.ndarray) -> float:
    return float(np.min(np.linalg.norm(points - p, axis=1))) if len(points) else np.inf


def spacing_kind(points: np.ndarray) -> str:
    """The scale's major notches by their median spacing at 256 px."""
    gap = float(np.median(np.linalg.norm(np.diff(points, axis=0), axis=1))) if len(points) > 1 else np.inf
    return "majors < 8 px apart" if gap < 8 else "majors 8-14 px apart" if gap < 14 else "majors >= 14 px apart"


def peak_kind(p: np.ndarray, labelled: np.ndarray, every_major: np.ndarray, minors: np.ndarray,
              numbers: np.ndarray, needle: np.ndarray | None, tol: float) -> str:
    if nearest(labelled, p) <= tol:
        return "a labelled major (assigned)"
    if nearest(every_major, p) <= tol:
        return "a hidden major"
    if nearest(labelled, p) <= 2 * tol:
        return "a labelled major, 1-2 tolerances off"
    if nearest(minors, p) <= tol:
        return "a minor notch"
    if nearest(minors, p) <= 2 * tol:
        return "a minor notch, 1-2 tolerances off"
    if nearest(numbers, p) <= 6:
        return "a number"
    if needle is not None:
        x, y = (int(np.clip(v, 0, side - 1)) for v, side in zip(p, needle.shape[::-1]))
        if needle[y, x]:
            return "the needle"
    return "none of those"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--shard", type=Path, required=True, help="crop shard of the synthetic engine")
    parser.add_argument("--model", type=Path, default=Path("gauged/models/crop.onnx"))
    parser.add_argument("--group", choices=GROUPS, default="full size", help="crops captured at full size, upsampled, or all")
    parser.add_argument("--check", action="store_true", help="only the peaks the shipped notch check keeps")
    args = parser.parse_args()
    if not (args.shard / "labels.jsonl").is_file():
        parser.error(f"{args.shard} is not a crop shard (no labels.jsonl); make one with gauged.training.prerender crops")
    header("which major notches are missed, and what the unassigned peaks lie on")
    model = OnnxModel(args.model, threads=2)
    check = NotchCheck(packaged_model_path("notch_check.onnx"), threads=2) if args.check else None
    shard = open_crop_shard(args.shard)
    size = model.input_size
    tol = 4.0 * size / 448
    recall: dict[str, list[int]] = defaultdict(lambda: [0, 0])
    peaks_on: Counter[str] = Counter()
    separation: list[float] = []
    crops = 0
    for index in range(len(shard)):
        sample = shard.sample(index)
        if sample.image.shape[0] != size:
            raise SystemExit(f"{args.shard} holds {sample.image.shape[0]} px crops; the model takes {size}")
        captured = render_scale(sample.source, size)
        group = "full size" if captured == 1.0 else "upsampled"
        if args.group != "all" and group != args.group:
            continue
        crops += 1
        crop = render_crop(int(sample.source.split("/")[1]), size, masks=False)
        model_input = to_model_input(sample.image)
        logits = model(model_input)
        keypoints = decode_crop_maps(logits, size, require_notches=False)
        if check is not None:
            keypoints = check(model_input, logits, keypoints)
        peaks = keypoints.major.points.reshape(-1, 2)
        labelled = np.asarray(sample.points.get("major") or [], float).reshape(-1, 2)
        every_major, minors = [], []
        for truth, scale in zip(crop.truth["scales"], crop.params.scales):
            seen = np.asarray([m["point"] for m in truth["majors"] if m["visible"]], float).reshape(-1, 2)
            every_major.append(np.asarray([m["point"] for m in truth["majors"]], float).reshape(-1, 2))
            minors.append(np.asarray([m["point"] for m in truth.get("minors", [])], float).reshape(-1, 2))
            for m in truth["majors"]:
                if not m["visible"]:
                    continue
                hit = nearest(peaks, np.asarray(m["point"])) <= tol
                for kind in (f"{scale.role} scale", f"drawn as {scale.major_style}",
                             "numbered" if m["labelled"] else "not numbered", spacing_kind(seen)):
                    recall[kind][0] += 1
                    recall[kind][1] += int(hit)
        every_major, minors = np.vstack(every_major), np.vstack(minors)
        every_notch = np.vstack([every_major, minors])
        for m in (m for truth in crop.truth["scales"] for m in truth["majors"] if m["visible"]):
            gaps = np.linalg.norm(every_notch - np.asarray(m["point"]), axis=1)
            gaps = gaps[gaps > 1e-6]
            separation.append(float(gaps.min()) * captured if len(gaps) else np.inf)
        numbers = np.asarray(sample.points.get("numbers") or [], float).reshape(-1, 2)
        for p in peaks:
            peaks_on[peak_kind(p, labelled, every_major, minors, numbers, sample.needle, tol)] += 1
    print(f"# {crops} crops ({args.group}) at {size} px, tolerance {tol:.2f} px (4 px at 448)"
          + (", peaks the notch check keeps" if check is not None else ""))
    print("recall by kind of labelled major notch:")
    for kind, (count, hit) in sorted(recall.items()):
        print(f"  {kind:24s} {count:5d}  {hit / count:6.1%}")
    gaps = np.asarray(separation)
    print("labelled majors whose nearest other notch is closer than d px in the captured image: "
          + ", ".join(f"d {d:g}: {(gaps < d).mean():.1%}" for d in (1.0, 1.5, 2.0, 3.0)))
    total = sum(peaks_on.values())
    print(f"what the {total} peaks lie on:")
    for kind, count in peaks_on.most_common():
        print(f"  {kind:38s} {count:5d}  {count / total:6.1%}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
