"""Render training shards once: real needle photos, real substation frames, and synthetic renders.

    python -m gauged.training.prerender needles --root ../shared/datasets/needle-polygons --split train \
        --size 256 --out data/needle-real
"""

from __future__ import annotations

import argparse
import logging
from collections.abc import Iterator
from pathlib import Path

import cv2
import numpy as np

from gauged.evaluation.gauge_crops import best_gauge_crop, crop_mask, shipped_detector
from gauged.training.real_data import load_needle_split
from gauged.training.shards import (
    CropSample,
    DetectorSample,
    write_crop_shard,
    write_detector_shard,
)
from gauged.training.targets import arc_end_points

log = logging.getLogger(__name__)


def real_needle_samples(root: Path, split: str, size: int, detector=None) -> Iterator[CropSample]:
    """Needle-polygons photos resized to ``size``² with their needle masks; no keypoint labels.

    With a ``detector`` (:class:`gauged.reader.stages.detect.GaugeDetector`) each photo is cut the reader's
    way instead, to the square crop of its best gauge (:mod:`gauged.evaluation.gauge_crops`); a photo
    where it finds no gauge is kept whole, as the reader would then have nothing to read.
    """
    for sample in load_needle_split(root, split):
        image, mask = sample.load()
        crop = best_gauge_crop(detector, image, size) if detector is not None else None
        name = f"needle-polygons/{split}/{sample.image_path.name}"
        points: dict = {}  # keypoints are not labelled on these photos: masked out of the loss
        if crop is None:
            yield CropSample(cv2.resize(image, (size, size), interpolation=cv2.INTER_AREA), points,
                             cv2.resize(mask, (size, size), interpolation=cv2.INTER_NEAREST), name)
        else:
            yield CropSample(crop.image, points, crop_mask(mask, crop, size), name + "#gauge")


def _render_one(args: tuple[int, int]) -> CropSample:
    from gauged.training.dial_renderer import render_crop

    seed, size = args
    image, labels = render_crop(seed, size)
    points = {name: pts.tolist() for name, pts in labels.points.items()}
    return CropSample(image, points, labels.needle, f"dial_renderer/{seed}")


def synth_points(truth: dict) -> dict[str, list[list[float]] | None]:
    """Crop-model keypoint labels from a :mod:`gauged.synth.truth` gauge record: start and end of the
    primary scale, the major notches and number centres of every scale, needle tip and pivot, and the
    minor notches (``minor``: not a shipped output; ``train_crop --minor-channel`` learns them as an
    auxiliary map so the major map learns what a major notch is not).

    Only notches the image shows are labelled: one behind an occluder, another gauge or the frame
    edge is left out (a hidden start or end leaves its channel labelled empty), so the model is
    neither taught nor scored to find what cannot be seen. Records without visibility count as seen.
    """
    scales = truth.get("scales") or []
    primary = next((s for s in scales if s.get("role") == "primary"), scales[0] if scales else None)
    majors = [m["point"] for s in scales for m in s.get("majors", []) if m.get("visible", True)]
    minors = [m["point"] for s in scales for m in s.get("minors", []) if m.get("visible", True)]
    numbers = [[(n["box"][0] + n["box"][2]) / 2, (n["box"][1] + n["box"][3]) / 2]
               for s in scales for n in s.get("numbers", []) if n.get("kind") == "number"]
    needle = truth.get("needle") or {}
    ends = arc_end_points(primary) if primary else {"start": None, "end": None}  # geometric, either direction

    return {
        "start": ends["start"],
        "end": ends["end"],
        "major": majors if scales else None,
        "minor": minors if scales and all("minors" in s for s in scales) else None,
        "tip": [needle["tip"]] if needle.get("tip") else None,
        "pivot": [needle["pivot"]] if needle.get("pivot") else None,
        "numbers": numbers or None,
    }


def _render_synth_one(args: tuple[int, int]) -> CropSample:
    """One crop of the full synthetic engine (:mod:`gauged.synth`): the pointing part of the needle
    is the mask (the counterweight is not, as in the real needle labels)."""
    from gauged.synth.crop import render_crop

    seed, size, *rest = args
    sample = render_crop(seed, size, direction=rest[0] if rest else "cw")
    needle = (sample.needle_mask == 1).astype(np.uint8)
    return CropSample(sample.image, synth_points(sample.truth), needle, f"synth/{seed}")


def _in_pool(render, jobs: list[tuple[int, int]], what: str, chunksize: int, workers: int) -> Iterator:
    """Results of ``render`` over ``jobs`` in order, on ``workers`` spawned processes, with progress.

    Spawned, not forked: a fork would copy whatever locks the parent's threads hold.
    """
    from multiprocessing import get_context

    every = max(1, len(jobs) // 8)
    with get_context("spawn").Pool(workers) as pool:
        for index, sample in enumerate(pool.imap(render, jobs, chunksize=chunksize)):
            if index % every == 0:
                log.info("rendered %d/%d %s", index, len(jobs), what)
            yield sample


def synthetic_crop_samples(first_seed: int, count: int, size: int, workers: int = 2,
                           engine: str = "synth", direction: str = "cw") -> Iterator[CropSample]:
    """Rendered crops for seeds ``first_seed .. first_seed + count - 1``, in seed order: ``engine``
    "synth" is the full :mod:`gauged.synth` engine, "dial" the simple training renderer; ``direction``
    is which way the full engine's scales rise ("cw", "ccw", "mixed")."""
    if engine == "synth" and direction != "cw":
        jobs = [(seed, size, direction) for seed in range(first_seed, first_seed + count)]
    else:
        jobs = [(seed, size) for seed in range(first_seed, first_seed + count)]
    render = _render_synth_one if engine == "synth" else _render_one
    return _in_pool(render, jobs, f"{engine} crops", 16, workers)


def _render_scene(args: tuple[int, int]) -> DetectorSample:
    from gauged.reader.stages.detect import Letterbox
    from gauged.training.dial_renderer import render_scene

    seed, size = args
    # Rendered at 640x360: the detector sees frames letterboxed to ~320 px, so more pixels buy nothing.
    image, boxes = render_scene(seed, 640, 360)
    letterbox = Letterbox.fit(image.shape[1], image.shape[0], size)
    offset = [letterbox.dx, letterbox.dy, letterbox.dx, letterbox.dy]
    scaled = [list(np.asarray(b) * letterbox.scale + offset) for b in boxes]
    return DetectorSample(letterbox.apply(image), scaled, f"dial_renderer/scene/{seed}")


def _render_closeup(args: tuple[int, int]) -> DetectorSample:
    """A close-up of the full engine (:func:`gauged.synth.crop.render_crop`: one gauge filling most of
    a square, often cut by its edges) resized to ``size``, boxed as the real substation frames are: the
    whole visible gauge front and case, clipped to the image (the face box alone, tried first, pulled
    the substation fold-B IoU from 0.896 to 0.826 and made crops that cut off the bezel)."""
    from gauged.synth.crop import render_crop

    seed, size = args
    sample = render_crop(seed, 448, masks=False)
    box = np.asarray(sample.truth["box"], float) * (size / 448)
    return DetectorSample(cv2.resize(sample.image, (size, size), interpolation=cv2.INTER_AREA), [list(box)],
                          f"synth/closeup/{seed}")


def closeup_samples(first_seed: int, count: int, size: int, workers: int = 2) -> Iterator[DetectorSample]:
    """Engine close-ups (one gauge each) for seeds ``first_seed ..``, in seed order."""
    jobs = [(seed, size) for seed in range(first_seed, first_seed + count)]
    return _in_pool(_render_closeup, jobs, "close-ups", 8, workers)


def synthetic_scene_samples(first_seed: int, count: int, size: int, workers: int = 2) -> Iterator[DetectorSample]:
    """Rendered scenes (letterboxed to ``size``) for seeds ``first_seed ..``, in seed order."""
    jobs = [(seed, size) for seed in range(first_seed, first_seed + count)]
    return _in_pool(_render_scene, jobs, "scenes", 8, workers)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="what", required=True)
    needles = sub.add_parser("needles", help="real needle-polygons photos -> crop shard")
    needles.add_argument("--root", type=Path, required=True)
    needles.add_argument("--split", default="train")
    needles.add_argument("--size", type=int, default=256)
    needles.add_argument("--out", type=Path, required=True)
    needles.add_argument("--crop-with-detector", action="store_true",
                         help="cut each photo to its detected gauge, as the reader does (the shipped detector)")
    crops = sub.add_parser("crops", help="synthetic dial crops -> crop shard")
    crops.add_argument("--seed", type=int, default=0, help="first seed (held-out sets use a disjoint range)")
    crops.add_argument("--count", type=int, required=True)
    crops.add_argument("--size", type=int, default=224)
    crops.add_argument("--out", type=Path, required=True)
    crops.add_argument("--engine", choices=("synth", "dial"), default="synth",
                       help="synth: the full gauged.synth engine (default); dial: the simple training renderer")
    crops.add_argument("--direction", choices=("cw", "ccw", "mixed"), default="cw",
                       help="which way the full engine's scales rise (ccw: the models checked on counter-clockwise dials)")
    scenes = sub.add_parser("scenes", help="synthetic camera frames with several dials -> detector shard")
    scenes.add_argument("--seed", type=int, default=0)
    scenes.add_argument("--count", type=int, required=True)
    scenes.add_argument("--size", type=int, default=320)
    scenes.add_argument("--out", type=Path, required=True)
    closeups = sub.add_parser("closeups", help="synthetic close-ups of one gauge (the full engine) -> detector shard")
    closeups.add_argument("--seed", type=int, default=20000)
    closeups.add_argument("--count", type=int, required=True)
    closeups.add_argument("--size", type=int, default=320)
    closeups.add_argument("--out", type=Path, required=True)
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    if args.what == "needles":
        count = len(load_needle_split(args.root, args.split))
        detector = shipped_detector() if args.crop_with_detector else None
        written = write_crop_shard(args.out, real_needle_samples(args.root, args.split, args.size, detector), count,
                                   args.size)
        log.info("wrote %d needle photos to %s", written, args.out)
    elif args.what == "crops":
        samples = synthetic_crop_samples(args.seed, args.count, args.size, engine=args.engine,
                                         direction=args.direction)
        written = write_crop_shard(args.out, samples, args.count, args.size)
        log.info("wrote %d synthetic crops to %s", written, args.out)
    elif args.what == "scenes":
        written = write_detector_shard(args.out, synthetic_scene_samples(args.seed, args.count, args.size), args.count,
                                       args.size)
        log.info("wrote %d synthetic scenes to %s", written, args.out)
    elif args.what == "closeups":
        written = write_detector_shard(args.out, closeup_samples(args.seed, args.count, args.size), args.count, args.size)
        log.info("wrote %d synthetic close-ups to %s", written, args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
