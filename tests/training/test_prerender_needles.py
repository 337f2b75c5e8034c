"""``prerender needles``: real-format needle photos, given whole or cut to the detected gauge."""

from __future__ import annotations

import cv2
import numpy as np

from gauged.evaluation.gauge_crops import shipped_detector
from gauged.synth.crop import render_crop
from gauged.training.prerender import real_needle_samples


def _needle_polygons_folder(root, frame, needle):
    """A one-photo needle-polygons split in the dataset's YOLO format (class, then x y normalised)."""
    (root / "train" / "images").mkdir(parents=True)
    (root / "train" / "labels").mkdir(parents=True)
    cv2.imwrite(str(root / "train" / "images" / "dial.png"), frame)
    contours, _ = cv2.findContours(needle, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    outline = max(contours, key=cv2.contourArea).reshape(-1, 2) + 0.5
    coords = " ".join(f"{x / frame.shape[1]:.6f} {y / frame.shape[0]:.6f}" for x, y in outline)
    (root / "train" / "labels" / "dial.txt").write_text(f"0 {coords}\n")


def test_a_photo_is_cut_to_its_gauge_with_its_needle_label(tmp_path):
    render = render_crop(7000003, 448)
    frame = np.full((700, 900, 3), 90, np.uint8)
    frame[150:598, 300:748] = render.image  # the gauge in a larger photo
    needle = np.zeros(frame.shape[:2], np.uint8)
    needle[150:598, 300:748] = render.needle_mask == 1
    _needle_polygons_folder(tmp_path, frame, needle)

    (whole,) = real_needle_samples(tmp_path, "train", 256)
    (cut,) = real_needle_samples(tmp_path, "train", 256, shipped_detector(threads=1))
    assert not whole.source.endswith("#gauge") and cut.source.endswith("#gauge")
    assert whole.image.shape == cut.image.shape == (256, 256, 3)
    # Cut to the gauge, the needle is seen larger: its label covers more of the crop than of the photo.
    assert cut.needle.sum() > 2 * whole.needle.sum() > 0
    # And the label still lies on the needle's paint: the same colour as under the photo's label.
    paint = frame[needle > 0].mean(axis=0)
    assert np.abs(cut.image[cut.needle > 0].mean(axis=0) - paint).max() < 20
    assert np.abs(cut.image.reshape(-1, 3).mean(axis=0) - paint).max() > 40
