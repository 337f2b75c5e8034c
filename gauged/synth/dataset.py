"""Batches of renders on disk: image folders with ``labels.jsonl``, and contact sheets.

Sample ``i`` of a batch is drawn from ``numpy.random.default_rng([seed, i])``, so a batch is the
same whatever the number of worker processes, and any sample can be re-rendered alone.
"""

from __future__ import annotations

import json
import logging
import math
from collections.abc import Iterator
import multiprocessing
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import cv2
import numpy as np

from gauged.synth.crop import render_crop
from gauged.synth.scene import render_scene
from gauged.synth.truth import image_record

log = logging.getLogger(__name__)


def sample_rng(seed: int, index: int) -> np.random.Generator:
    return np.random.default_rng([seed, index])


def render_item(args: tuple) -> tuple[np.ndarray, dict, np.ndarray | None]:
    """Render sample ``index``: (image, record, needle mask or None). Top-level so workers can run it.

    ``args`` is ``(kind, seed, index, width, height, size, clean)`` or the same with a scale
    ``direction`` ("cw", "ccw", "mixed") appended; without it the scales rise clockwise.
    """
    kind, seed, index, width, height, size, clean = args[:7]
    direction = args[7] if len(args) > 7 else "cw"
    rng = sample_rng(seed, index)
    if kind == "crop":
        crop = render_crop(rng, size, clean=clean, direction=direction)
        record = image_record([], size, size, render_scale=1.0 / crop.output_scale)
        return crop.image, record | {"gauges": [crop.truth]}, crop.needle_mask
    scene = render_scene(rng, width, height, clean=clean, direction=direction)
    return scene.image, scene.record, None


# Workers are spawned, not forked: a fork copies whatever threads the parent runs (a Zenoh runtime,
# onnxruntime pools) in a locked state, which hung the workers inside the test suite.
_SPAWN = multiprocessing.get_context("spawn")


def _init_worker() -> None:
    cv2.setNumThreads(1)  # processes, not threads, share the cores


def render_batch(kind: str, seed: int, count: int, *, width: int = 1280, height: int = 720, size: int = 448,
                 clean: bool = False, workers: int = 1,
                 direction: str = "cw") -> Iterator[tuple[int, np.ndarray, dict, np.ndarray | None]]:
    """Yield ``(index, image, record, mask)`` for ``count`` samples, in index order."""
    jobs = [(kind, seed, i, width, height, size, clean, direction) for i in range(count)]
    if workers <= 1:
        for i, job in enumerate(jobs):
            yield (i, *render_item(job))
        return
    with ProcessPoolExecutor(max_workers=workers, mp_context=_SPAWN, initializer=_init_worker) as pool:
        for i, result in enumerate(pool.map(render_item, jobs, chunksize=4)):
            yield (i, *result)


def write_images(out: Path, kind: str, seed: int, count: int, *, width: int = 1280, height: int = 720, size: int = 448,
                 clean: bool = False, workers: int = 1, quality: int = 95, masks: bool = False,
                 direction: str = "cw") -> Path:
    """Write ``count`` renders as ``out/NNNNNN.jpg`` plus ``out/labels.jsonl`` (and ``out/masks/NNNNNN.png``
    needle label maps for crops when ``masks``); returns the labels path. ``direction`` ("cw",
    "ccw", "mixed") is which way the scales rise."""
    out.mkdir(parents=True, exist_ok=True)
    if masks:
        (out / "masks").mkdir(exist_ok=True)
    labels = out / "labels.jsonl"
    step = max(1, count // 20)
    with labels.open("w", encoding="utf-8") as f:
        for i, image, record, mask in render_batch(kind, seed, count, width=width, height=height, size=size,
                                                   clean=clean, workers=workers, direction=direction):
            name = f"{i:06d}.jpg"
            cv2.imwrite(str(out / name), image, [cv2.IMWRITE_JPEG_QUALITY, quality])
            if masks and mask is not None:
                cv2.imwrite(str(out / "masks" / f"{i:06d}.png"), mask)
            record["image"] = name
            f.write(json.dumps(record, separators=(",", ":")) + "\n")
            if (i + 1) % step == 0 or i + 1 == count:
                log.info("rendered %d/%d", i + 1, count)
    return labels


def contact_sheet(seed: int, count: int = 48, tile: int = 256, columns: int = 8, workers: int = 1,
                  direction: str = "cw") -> np.ndarray:
    """A grid of ``count`` renders: mostly crops, every sixth a full scene letterboxed into its tile."""
    tiles = []
    scene_every = 6
    jobs_crop = [i for i in range(count) if i % scene_every != scene_every - 1]
    crops = {i: img for i, img, _, _ in _subset("crop", seed, jobs_crop, tile, workers, direction)}
    scenes = {i: img for i, img, _, _ in _subset("scene", seed, [i for i in range(count) if i not in crops], tile,
                                                 workers, direction)}
    for i in range(count):
        img = crops.get(i)
        if img is None:
            img = scenes[i]
            h = int(round(tile * img.shape[0] / img.shape[1]))
            box = np.full((tile, tile, 3), 30, np.uint8)
            y0 = (tile - h) // 2
            box[y0:y0 + h] = cv2.resize(img, (tile, h), interpolation=cv2.INTER_AREA)
            img = box
        tiles.append(img)
    rows = math.ceil(count / columns)
    sheet = np.full((rows * tile, columns * tile, 3), 30, np.uint8)
    for k, img in enumerate(tiles):
        r, c = divmod(k, columns)
        sheet[r * tile:(r + 1) * tile, c * tile:(c + 1) * tile] = img
    return sheet


def _subset(kind: str, seed: int, indices: list[int], tile: int, workers: int,
            direction: str = "cw") -> Iterator[tuple[int, np.ndarray, dict, None]]:
    jobs = [(kind, seed, i, 1280, 720, tile, False, direction) for i in indices]
    if workers <= 1 or len(jobs) < 2:
        results = [render_item(job) for job in jobs]
    else:
        with ProcessPoolExecutor(max_workers=workers, mp_context=_SPAWN, initializer=_init_worker) as pool:
            results = list(pool.map(render_item, jobs, chunksize=2))
    for i, (image, record, _) in zip(indices, results):
        yield i, image, record, None
