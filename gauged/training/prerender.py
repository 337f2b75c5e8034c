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

from gauged.training.real_data import load_needle_split
from gauged.training.shards import CropSample, write_crop_shard

log = logging.getLogger(__name__)


def real_needle_samples(root: Path, split: str, size: int) -> Iterator[CropSample]:
    """Needle-polygons photos resized to ``size``² with their needle masks; no keypoint labels."""
    for sample in load_needle_split(root, split):
        image, mask = sample.load()
        yield CropSample(cv2.resize(image, (size, size), interpolation=cv2.INTER_AREA),
                         {},  # keypoints are not labelled on these photos: masked out of the loss
                         cv2.resize(mask, (size, size), interpolation=cv2.INTER_NEAREST),
                         f"needle-polygons/{split}/{sample.image_path.name}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="what", required=True)
    needles = sub.add_parser("needles", help="real needle-polygons photos -> crop shard")
    needles.add_argument("--root", type=Path, required=True)
    needles.add_argument("--split", default="train")
    needles.add_argument("--size", type=int, default=256)
    needles.add_argument("--out", type=Path, required=True)
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    if args.what == "needles":
        count = len(load_needle_split(args.root, args.split))
        written = write_crop_shard(args.out, real_needle_samples(args.root, args.split, args.size), count, args.size)
        log.info("wrote %d needle photos to %s", written, args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
