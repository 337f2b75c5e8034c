"""The needle loss judged where the evaluation judges it (losses.upsampled_mask_loss), and its overlap terms."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

torch = pytest.importorskip("torch", reason="the train extra (torch==2.13.0) is not installed")

from gauged.evaluation.model_metrics import needle_mask_at  # noqa: E402
from gauged.training.losses import (  # noqa: E402
    crop_loss,
    lovasz_hinge,
    mask_loss,
    upsampled_mask_loss,
)
from gauged.training.targets import downsample_mask  # noqa: E402


def thin_needle(size: int = 64) -> np.ndarray:
    """A needle 3 px wide ending in a one-pixel tip, at the input's resolution."""
    mask = np.zeros((size, size), np.uint8)
    cv2.line(mask, (12, 33), (52, 30), 1, thickness=3)
    cv2.line(mask, (52, 30), (58, 30), 1, thickness=1)
    return mask


def test_the_binary_target_is_the_coverage_grid_resized_as_the_evaluation_resizes_logits():
    coverage = downsample_mask(thin_needle(), 2).astype(np.float32)
    up = torch.nn.functional.interpolate(torch.from_numpy(coverage)[None, None], scale_factor=2,
                                         mode="bilinear", align_corners=False)[0, 0].numpy()
    # needle_mask_at cuts resized logits at 0: a map of coverage - 0.5 cut there is the same mask.
    assert np.array_equal(up > 0.5, needle_mask_at(coverage - 0.5, (64, 64)))


def test_the_judged_loss_asks_for_a_decided_mask_where_the_grid_loss_settles_for_the_coverage():
    target = torch.from_numpy(downsample_mask(thin_needle(), 2).astype(np.float32))[None]
    valid = torch.ones(1)
    soft = torch.logit(target.clamp(1e-3, 1 - 1e-3))  # the coverage itself as the probability
    sharp = 4 * soft  # the same map, decided: each cell nearer 0 or 1
    # On the grid the two cost about the same (0.146 vs 0.133); judged at the input's resolution
    # against the binary mask, the soft map costs three times as much (0.075 vs 0.023).
    assert mask_loss(sharp, target, valid) > 0.8 * mask_loss(soft, target, valid)
    assert upsampled_mask_loss(sharp, target, valid, 2) < 0.5 * upsampled_mask_loss(soft, target, valid, 2)


def test_crop_loss_uses_the_upsampled_needle_loss_only_when_asked():
    rng = np.random.default_rng(0)
    logits = torch.from_numpy(rng.normal(size=(2, 7, 32, 32)).astype(np.float32))
    target = torch.from_numpy(rng.uniform(size=(2, 7, 32, 32)).astype(np.float32))
    valid = torch.ones(2, 7)
    plain, judged = crop_loss(logits, target, valid), crop_loss(logits, target, valid, needle_upsample=2)
    assert torch.isclose(plain["heat"], judged["heat"])
    assert torch.isclose(plain["needle"], mask_loss(logits[:, -1], target[:, -1], valid[:, -1]))
    assert torch.isclose(judged["needle"], upsampled_mask_loss(logits[:, -1], target[:, -1], valid[:, -1], 2))


def test_the_lovasz_hinge_of_a_decided_mask_is_twice_its_jaccard_loss():
    # With logits of +-1 every right pixel has hinge error 0 and every wrong one 2, and the Lovasz
    # extension of that error vector is 2 * (1 - IoU) of the mask the logits cut (Berman et al.).
    truth = torch.from_numpy(thin_needle().astype(bool))[None]
    predicted = truth.clone()
    predicted[0, 28:36, 40:60] = True  # a blob beside the needle's far end
    predicted[0, 30:36, 10:20] = False  # the hub end missed
    logits = predicted.float() * 2 - 1
    iou = (predicted & truth).sum() / (predicted | truth).sum()
    assert torch.isclose(lovasz_hinge(logits, truth)[0], 2 * (1 - iou))


def test_the_lovasz_hinge_is_zero_for_a_mask_right_with_margin_and_grows_with_the_error():
    truth = torch.from_numpy(thin_needle().astype(bool))[None]
    right = (truth.float() * 2 - 1) * 3
    assert lovasz_hinge(right, truth)[0] == 0
    thicker = torch.from_numpy(cv2.dilate(thin_needle(), np.ones((3, 3), np.uint8)).astype(bool))[None]
    thickest = torch.from_numpy(cv2.dilate(thin_needle(), np.ones((5, 5), np.uint8)).astype(bool))[None]
    assert 0 < lovasz_hinge(thicker.float() * 2 - 1, truth)[0] < lovasz_hinge(thickest.float() * 2 - 1, truth)[0]


def test_the_mask_loss_takes_the_overlap_term_asked_for_and_refuses_an_unknown_one():
    target = torch.from_numpy(thin_needle().astype(np.float32))[None]
    logits = torch.zeros_like(target)
    valid = torch.ones(1)
    bce = torch.nn.functional.binary_cross_entropy_with_logits(logits, target)
    assert torch.isclose(mask_loss(logits, target, valid, "lovasz"), bce + lovasz_hinge(logits, target > 0.5)[0])
    assert not torch.isclose(mask_loss(logits, target, valid, "lovasz"), mask_loss(logits, target, valid))
    with pytest.raises(ValueError, match="unknown overlap loss 'iou'"):
        mask_loss(logits, target, valid, "iou")
