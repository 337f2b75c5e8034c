"""Losses of the crop model and the detector."""

from __future__ import annotations

import torch
from torch.nn import functional as F


def focal_heatmap_loss(logits: torch.Tensor, target: torch.Tensor, valid: torch.Tensor,
                       alpha: float = 2.0, beta: float = 4.0) -> torch.Tensor:
    """Penalty-reduced pixel-wise focal loss (CenterNet, Zhou et al. 2019, Eq. 1).

    ``logits``/``target``: (N, C, H, W); ``valid``: (N, C) in {0, 1} masks channels that are not
    labelled for a sample. Targets are Gaussians centred at sub-cell positions, so a peak rarely
    reaches 1: the positives are the targets' local maxima above 0.5. Normalised by their number.
    """
    prob = torch.sigmoid(logits).clamp(1e-4, 1 - 1e-4)
    pos = ((target >= F.max_pool2d(target, 3, stride=1, padding=1)) & (target > 0.5)).float()
    neg = 1.0 - pos
    pos_loss = -torch.log(prob) * (1 - prob) ** alpha * pos
    neg_loss = -torch.log(1 - prob) * prob**alpha * (1 - target) ** beta * neg
    per_map = (pos_loss + neg_loss).sum(dim=(2, 3))
    num_pos = pos.sum(dim=(2, 3)).clamp(min=1.0)
    return (per_map / num_pos * valid).sum() / valid.sum().clamp(min=1.0)


def mask_loss(logits: torch.Tensor, target: torch.Tensor, valid: torch.Tensor, overlap: str = "dice") -> torch.Tensor:
    """BCE + an overlap loss on a coverage mask. ``logits``/``target`` (N, H, W), ``valid`` (N,).

    ``overlap`` is ``dice`` (soft Dice) or ``lovasz`` (:func:`lovasz_hinge` against the target cut at
    0.5): the evaluation scores each photo's mask by its IoU, which the Lovasz hinge bounds directly."""
    bce = F.binary_cross_entropy_with_logits(logits, target, reduction="none").mean(dim=(1, 2))
    if overlap == "lovasz":
        return ((bce + lovasz_hinge(logits, target > 0.5)) * valid).sum() / valid.sum().clamp(min=1.0)
    if overlap != "dice":
        raise ValueError(f"unknown overlap loss {overlap!r}: use 'dice' or 'lovasz'")
    prob = torch.sigmoid(logits)
    inter = (prob * target).sum(dim=(1, 2))
    dice = 1 - (2 * inter + 1) / (prob.sum(dim=(1, 2)) + target.sum(dim=(1, 2)) + 1)
    return ((bce + dice) * valid).sum() / valid.sum().clamp(min=1.0)


def lovasz_hinge(logits: torch.Tensor, labels: torch.Tensor) -> torch.Tensor:
    """Per-image Lovasz hinge (Berman et al., CVPR 2018, Eq. 10-11): a convex surrogate of 1 - IoU of
    the mask ``logits`` > 0 with the boolean ``labels``, both (N, H, W); returns (N,). The hinge
    errors are sorted, and each is weighted by how much it adds to the Jaccard loss of the errors
    before it, so a pixel costs what it costs the image's IoU. An image with no labelled pixel
    costs its false positives' hinge errors weighted the same way (its IoU is 0 with any)."""
    flat_logits, flat_labels = logits.flatten(1), labels.flatten(1).to(logits.dtype)
    errors = 1.0 - flat_logits * (2.0 * flat_labels - 1.0)
    errors_sorted, order = torch.sort(errors, dim=1, descending=True)
    truth_sorted = torch.gather(flat_labels, 1, order)
    positives = truth_sorted.sum(dim=1, keepdim=True)
    intersection = positives - truth_sorted.cumsum(1)
    union = positives + (1.0 - truth_sorted).cumsum(1)
    jaccard = 1.0 - intersection / union
    grad = torch.cat([jaccard[:, :1], jaccard[:, 1:] - jaccard[:, :-1]], dim=1)
    return (F.relu(errors_sorted) * grad).sum(dim=1)


def upsampled_mask_loss(logits: torch.Tensor, target: torch.Tensor, valid: torch.Tensor, factor: int,
                        overlap: str = "dice") -> torch.Tensor:
    """:func:`mask_loss` where the mask is judged: ``logits`` (N, H, W) resized bilinearly ``factor``
    times (cell centres aligned, as ``needle_mask_at`` resizes them at evaluation) against the
    coverage ``target`` resized the same way and cut at 0.5, a binary mask. On a coverage target a
    cell half covered by a thin needle or its tapering tip is taught "0.5", which the evaluation's
    cut at 0.5 then drops; here each pixel of the needle is taught "needle"."""
    up = F.interpolate(logits[:, None], scale_factor=factor, mode="bilinear", align_corners=False)[:, 0]
    binary = (F.interpolate(target[:, None], scale_factor=factor, mode="bilinear", align_corners=False)[:, 0] > 0.5)
    return mask_loss(up, binary.to(up.dtype), valid, overlap)


def crop_loss(logits: torch.Tensor, target: torch.Tensor, valid: torch.Tensor,
              needle_upsample: int = 1, needle_overlap: str = "dice") -> dict[str, torch.Tensor]:
    """Total crop-model loss: heatmap focal loss on channels 0..C-2, mask loss on the last channel
    (on the coverage grid, or with ``needle_upsample`` > 1 by :func:`upsampled_mask_loss`), with
    ``needle_overlap`` as its overlap term (:func:`mask_loss`)."""
    heat = focal_heatmap_loss(logits[:, :-1], target[:, :-1], valid[:, :-1])
    if needle_upsample > 1:
        needle = upsampled_mask_loss(logits[:, -1], target[:, -1], valid[:, -1], needle_upsample, needle_overlap)
    else:
        needle = mask_loss(logits[:, -1], target[:, -1], valid[:, -1], needle_overlap)
    return {"loss": heat + needle, "heat": heat.detach(), "needle": needle.detach()}


def detector_loss(out: torch.Tensor, maps: torch.Tensor, weight: torch.Tensor) -> dict[str, torch.Tensor]:
    """CenterNet loss: focal loss on the centre map + L1 on size/offset at centre cells (Eq. 2-3)."""
    ones = torch.ones(out.shape[0], 1, device=out.device)
    center = focal_heatmap_loss(out[:, :1], maps[:, :1], ones)
    w = weight.unsqueeze(1)
    count = weight.sum().clamp(min=1.0)
    size = (torch.abs(out[:, 1:3] - maps[:, 1:3]) * w).sum() / count
    offset = (torch.abs(torch.sigmoid(out[:, 3:5]) - maps[:, 3:5]) * w).sum() / count
    return {"loss": center + 1.0 * size + 1.0 * offset, "center": center.detach(), "size": size.detach()}
