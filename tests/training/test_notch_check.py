"""The notch check's training: the threshold it chooses, and a smoke run exported and run by the reader's wrapper."""

from __future__ import annotations

import json

import numpy as np
import pytest

torch = pytest.importorskip("torch", reason="the train extra (torch==2.13.0) is not installed")

from gauged.reader.stages.keypoints import CROP_CHANNELS, Peaks, decode_crop_maps  # noqa: E402
from gauged.reader.stages.notch_check import PATCH, NotchCheck  # noqa: E402
from gauged.training.notch_check import (  # noqa: E402
    CHANNELS,
    MAJOR,
    NEAR,
    OTHER,
    choose_threshold,
    export_onnx,
    kept_figures,
    load_net,
    train,
)


def test_kept_figures_count_the_majors_kept_and_the_others_let_through():
    p = np.array([0.9, 0.8, 0.6, 0.4, 0.7, 0.2, 0.95])
    labels = np.array([MAJOR, MAJOR, MAJOR, MAJOR, OTHER, OTHER, NEAR])
    figures = kept_figures(p, labels, 0.5)
    assert figures["major_kept"] == pytest.approx(3 / 4)
    assert figures["unassigned"] == pytest.approx(2 / 5)  # the other at 0.7 and the near miss


def test_the_threshold_is_the_lowest_that_meets_the_unassigned_target():
    p = np.concatenate([np.linspace(0.5, 1.0, 95), np.linspace(0.0, 0.6, 20)])
    labels = np.array([MAJOR] * 95 + [OTHER] * 20)
    threshold = choose_threshold(p, labels, target=0.05)
    assert kept_figures(p, labels, threshold)["unassigned"] <= 0.05
    assert kept_figures(p, labels, threshold - 0.01)["unassigned"] > 0.05


def _peaks_file(path, rng, count):
    """Peaks whose label is written into the windows: majors bright in the middle, the others dark."""
    labels = rng.choice([MAJOR, OTHER, NEAR], count, p=[0.6, 0.3, 0.1]).astype(np.int8)
    windows = rng.integers(0, 60, (count, CHANNELS, PATCH, PATCH), dtype=np.uint8)
    windows[labels == MAJOR, :, PATCH // 2 - 4:PATCH // 2 + 4, PATCH // 2 - 4:PATCH // 2 + 4] = 250
    features = rng.random((count, 3)).astype(np.float32)
    np.savez(path, windows=windows, features=features, labels=labels, crops=np.arange(count), full=np.ones(count, bool))


def test_a_short_run_learns_exports_and_runs_in_the_readers_wrapper(tmp_path):
    rng = np.random.default_rng(0)
    _peaks_file(tmp_path / "train.npz", rng, 1500)
    _peaks_file(tmp_path / "tune.npz", rng, 200)
    best = train([tmp_path / "train.npz"], tmp_path / "tune.npz", tmp_path / "run", epochs=3, width=8, batch=64, threads=1)
    assert best["tune_major_kept"] > 0.9 and best["tune_unassigned"] <= 0.05
    assert len((tmp_path / "run" / "history.jsonl").read_text().splitlines()) == 3
    meta = export_onnx(tmp_path / "run" / "best.pt", tmp_path / "notch_check.onnx")
    check = NotchCheck(tmp_path / "notch_check.onnx", threads=1)
    assert check.threshold == meta["threshold"] == best["threshold"]
    assert check.metadata == json.loads(json.dumps(meta))
    # The wrapper builds the windows from a crop; the exported net gives what the checkpoint gives on them.
    image = rng.random((64, 64, 3)).astype(np.float32)
    logits = rng.normal(size=(len(CROP_CHANNELS), 32, 32)).astype(np.float32)
    keypoints = decode_crop_maps(logits, 64, threshold=0.0, require_notches=False)
    assert len(keypoints.major) > 0
    p = check.probabilities(image, logits, keypoints)
    net, _ = load_net(tmp_path / "run" / "best.pt")
    from gauged.reader.stages.notch_check import notch_windows, peak_features

    with torch.no_grad():
        expected = torch.sigmoid(net(torch.from_numpy(notch_windows(image, logits, keypoints.major.points)),
                                     torch.from_numpy(peak_features(keypoints.major, keypoints.pivot, 64)))).numpy()
    assert np.allclose(p, expected, atol=1e-5)
    checked = check(image, logits, keypoints)
    assert isinstance(checked.major, Peaks) and np.all(checked.major.scores >= check.threshold)
