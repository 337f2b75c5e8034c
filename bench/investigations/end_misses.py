"""How far the crop model's start and end notches lie from the labelled ones, in the pixels the camera captured.

    python bench/investigations/end_misses.py --shard data/synth-val-256 [--model gauged/models/crop.onnx]

``--shard`` is a crop shard of the synthetic engine (`python -m gauged.training.prerender crops
--seed 1000000 --count 500 --size 256 --out data/synth-val-256`, the held-out crops `gauged eval
models` scores). An end counts as found, as there, when the model's best peak of its kind lies within
issue 4's 4 px at 448 px (scaled to the crop size) of the label. A third of the engine's crops are
rendered at 12-60% of their size and upsampled (far gauges): there that tolerance is under one pixel
of the image the camera captured, so this script also reports each error in captured pixels, and
splits the misses into those within 1 and 2 captured px (placed as well as the image allows, but
outside the tolerance), those farther, and those with no peak at all.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # bench/, for common
import numpy as np  # noqa: E402
from common import header  # noqa: E402

from gauged.evaluation.models import render_scale  # noqa: E402
from gauged.reader.onnx_model import OnnxModel, to_model_input  # noqa: E402
from gauged.reader.stages.keypoints import decode_crop_maps  # noqa: E402
from gauged.training.shards import open_crop_shard  # noqa: E402

CAPTURED_STEPS = (0.5, 1.0, 1.5, 2.0, 3.0)


def end_errors(model: OnnxModel, shard_dir: Path, threshold: float) -> tuple[np.ndarray, np.ndarray, int]:
    """Per labelled end of every crop: the share of its resolution the crop was captured at, and the
    distance (crop px) from the label to the model's best peak of that kind above ``threshold`` (inf:
    no peak); and how many peaks were found for ends the crop does not show (false ends)."""
    shard = open_crop_shard(shard_dir)
    scales, errors, false_ends = [], [], 0
    for index in range(len(shard)):
        sample = shard.sample(index)
        if sample.image.shape[0] != model.input_size:
            raise SystemExit(f"{shard_dir} holds {sample.image.shape[0]} px crops; the model takes {model.input_size}")
        captured = render_scale(sample.source, sample.image.shape[0])
        keypoints = decode_crop_maps(model(to_model_input(sample.image)), model.input_size, threshold,
                                     require_notches=False)
        for name in ("start", "end"):
            truth = sample.points.get(name)
            peaks = getattr(keypoints, name)
            if not truth:
                false_ends += len(peaks) > 0
                continue
            scales.append(1.0 if captured is None else captured)
            errors.append(float(np.linalg.norm(peaks.points[0] - truth[0])) if len(peaks) else np.inf)
    return np.asarray(scales), np.asarray(errors), false_ends


def report(scales: np.ndarray, errors: np.ndarray, tol: float) -> None:
    found = errors <= tol
    captured = errors * scales  # the error in the captured image's pixels
    print(f"  labelled ends {len(errors)}: found {found.mean():.1%}; no peak {np.isinf(errors).mean():.1%}; "
          f"tolerance in captured px: median {np.median(tol * scales):.2f}")
    print("  best peak within d captured px: " + ", ".join(f"d {d:g}: {(captured <= d).mean():.1%}" for d in CAPTURED_STEPS))
    missed = ~found
    if missed.any():
        c = captured[missed]
        print(f"  misses {missed.sum()}: within 1 captured px {(c <= 1).sum()}, 1-2 px {((c > 1) & (c <= 2)).sum()}, "
              f"farther {(np.isfinite(c) & (c > 2)).sum()}, no peak {np.isinf(c).sum()}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--shard", type=Path, required=True, help="crop shard of the synthetic engine")
    parser.add_argument("--model", type=Path, default=Path("gauged/models/crop.onnx"))
    parser.add_argument("--threshold", type=float, default=0.3,
                        help="peak threshold of the start and end maps (default 0.3, the reader's)")
    args = parser.parse_args()
    if not (args.shard / "labels.jsonl").is_file():
        parser.error(f"{args.shard} is not a crop shard (no labels.jsonl); make one with gauged.training.prerender crops")
    header("how far the start and end notches are from their labels")
    model = OnnxModel(args.model, threads=2)
    tol = 4.0 * model.input_size / 448
    scales, errors, false_ends = end_errors(model, args.shard, args.threshold)
    print(f"# {args.shard}: crops at {model.input_size} px, tolerance {tol:.2f} px (4 px at 448), "
          f"peak threshold {args.threshold:g}; a start or end peak where the crop shows no end: {false_ends}")
    for group, chosen in (("all", np.ones(len(scales), bool)), ("full size", scales == 1.0), ("upsampled", scales < 1.0)):
        if chosen.any():
            print(group)
            report(scales[chosen], errors[chosen], tol)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
