"""Training smoke test: a few steps of each net on tiny inputs, exported to ONNX and run by the runtime."""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch", reason="the train extra (torch==2.13.0) is not installed")

from gauged.reader.onnx_model import OnnxModel  # noqa: E402
from gauged.reader.stages.keypoints import CROP_CHANNELS, decode_crop_maps  # noqa: E402
from gauged.training.loop import TrainSettings, train  # noqa: E402
from gauged.training.losses import crop_loss, detector_loss  # noqa: E402
from gauged.training.nets import CropNet, DetNet  # noqa: E402
from gauged.training.shards import CropSample  # noqa: E402
from gauged.training.targets import detector_targets  # noqa: E402
from gauged.training.train_crop import augmented, export_onnx  # noqa: E402

SIZE = 64


def tiny_sample(rng: np.random.Generator) -> CropSample:
    image = rng.integers(0, 255, (SIZE, SIZE, 3), dtype=np.uint8)
    needle = np.zeros((SIZE, SIZE), np.uint8)
    needle[30:34, 32:60] = 1
    points = {"start": [[10.0, 50.0]], "end": [[54.0, 50.0]], "major": [[10.0, 50.0], [32.0, 8.0], [54.0, 50.0]],
              "tip": [[58.0, 32.0]], "pivot": [[32.0, 32.0]], "numbers": []}
    return CropSample(image, points, needle, "smoke")


def test_crop_training_resumes_and_exports_onnx(tmp_path):
    rng = np.random.default_rng(0)
    samples = [tiny_sample(rng) for _ in range(4)]

    def batches(epoch):
        x, t, v = zip(*(augmented(s, SIZE, np.random.default_rng(epoch), 1.0) for s in samples))
        yield torch.from_numpy(np.stack(x)), torch.from_numpy(np.stack(t)), torch.from_numpy(np.stack(v))

    model = CropNet(SIZE, pretrained=False, width=16)
    settings = TrainSettings(epochs=1, warmup_steps=1)
    first = train(model, batches, 1, lambda m, b: crop_loss(m(b[0]), b[1], b[2]), lambda m: {"score": 0.5},
                  settings, tmp_path / "run")
    assert first == {"score": 0.5} and (tmp_path / "run" / "last.pt").exists()
    settings.epochs = 2  # resume: runs only the second epoch
    train(model, batches, 1, lambda m, b: crop_loss(m(b[0]), b[1], b[2]), lambda m: {"score": 0.6},
          settings, tmp_path / "run")
    history = (tmp_path / "run" / "history.jsonl").read_text().splitlines()
    assert len(history) == 2
    export_onnx(model, SIZE, tmp_path / "crop.onnx", {"kind": "crop", "size": SIZE, "stride": 2})
    runtime = OnnxModel(tmp_path / "crop.onnx", threads=1)
    assert runtime.metadata["kind"] == "crop" and runtime.input_size == SIZE
    logits = runtime(np.zeros((SIZE, SIZE, 3), np.float32))
    assert logits.shape == (len(CROP_CHANNELS), SIZE // 2, SIZE // 2)
    with torch.no_grad():
        expected = model.eval()(torch.zeros(1, 3, SIZE, SIZE))[0].numpy()
    assert np.allclose(logits, expected, atol=1e-4)
    decode_crop_maps(logits, SIZE, require_notches=False)  # decodes without error whatever it learnt


def test_detector_loss_decreases_on_one_batch():
    torch.manual_seed(0)
    model = DetNet(64, pretrained=False, width=16)
    maps, weight = detector_targets(np.array([[10.0, 12.0, 40.0, 44.0]]), 64)
    x = torch.rand(2, 3, 64, 64)
    maps_t, weight_t = torch.from_numpy(np.stack([maps, maps])), torch.from_numpy(np.stack([weight, weight]))
    optimizer = torch.optim.Adam(model.parameters(), 1e-2)
    losses = []
    for _ in range(15):
        loss = detector_loss(model(x), maps_t, weight_t)["loss"]
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()
        losses.append(float(loss))
    assert losses[-1] < 0.5 * losses[0]


def test_synthetic_needle_masks_are_widened_to_the_annotators_convention_and_real_ones_kept():
    from gauged.training.train_crop import widened_needle

    needle = np.zeros((SIZE, SIZE), np.uint8)
    needle[31:33, 32:60] = 1  # two pixels wide, as the engine paints a thin needle
    synth = widened_needle(CropSample(np.zeros((SIZE, SIZE, 3), np.uint8), {}, needle, "synth/7"), 1)
    rows = np.nonzero(synth.needle[:, 45])[0]
    assert rows.tolist() == [30, 31, 32, 33]  # one pixel more on each side
    real = CropSample(np.zeros((SIZE, SIZE, 3), np.uint8), {}, needle, "needle-polygons/train/a.jpg")
    assert widened_needle(real, 1) is real
    assert widened_needle(CropSample(real.image, {}, None, "synth/8"), 1).needle is None


def test_detector_batches_mix_scene_and_close_up_shards(tmp_path):
    """The detector trains on several synthetic shards at once: dial_renderer scenes and the engine's
    close-ups of one gauge, boxed whole (front and case) inside the frame."""
    from gauged.training.prerender import _render_closeup, _render_scene
    from gauged.training.shards import open_detector_shard, write_detector_shard
    from gauged.training.train_detector import make_batches

    closeups = [_render_closeup((seed, SIZE)) for seed in (1, 2)]
    for sample in closeups:
        (x0, y0, x1, y1), = sample.boxes
        assert 0 <= x0 < x1 <= SIZE and 0 <= y0 < y1 <= SIZE and (x1 - x0) * (y1 - y0) > 0.1 * SIZE**2
    write_detector_shard(tmp_path / "closeups", iter(closeups), 2, SIZE)
    write_detector_shard(tmp_path / "scenes", iter([_render_scene((seed, SIZE)) for seed in (1, 2)]), 2, SIZE)
    shards = [open_detector_shard(tmp_path / name) for name in ("scenes", "closeups")]
    (x, maps, weight), = list(make_batches(shards, [], SIZE, 4, 0, 0)(0))
    assert x.shape == (4, 3, SIZE, SIZE) and maps.shape == (4, 5, SIZE // 8, SIZE // 8)
    assert float(weight.sum()) >= 2  # at least the two close-ups' centres


def test_needle_branch_starts_as_the_shared_decoder_and_trains_only_the_needle():
    torch.manual_seed(0)
    model = CropNet(SIZE, pretrained=False, width=16).eval()
    x = torch.rand(2, 3, SIZE, SIZE)
    with torch.no_grad():
        before = model(x)
    model.add_needle_branch()
    with torch.no_grad():
        assert torch.allclose(model(x), before, atol=1e-6)  # a copy: the same function at first
    trainable = {name.split(".")[0] for name, p in model.named_parameters() if p.requires_grad}
    assert trainable == {"needle_branch"}
    optimizer = torch.optim.AdamW([p for p in model.parameters() if p.requires_grad], lr=1e-2)
    model.train()
    assert not model.encoder.training and model.needle_branch.training  # frozen BatchNorms keep their statistics
    for _ in range(3):
        optimizer.zero_grad()
        model(x)[:, -1].sigmoid().mean().backward()
        optimizer.step()
    model.eval()
    with torch.no_grad():
        after = model(x)
    assert torch.equal(after[:, :-1], before[:, :-1])  # keypoint maps untouched
    assert (after[:, -1] - before[:, -1]).abs().mean() > 1e-3  # the needle's branch learnt


def test_a_deepened_needle_branch_decodes_from_stride_16_and_still_trains_only_the_needle():
    torch.manual_seed(1)
    model = CropNet(SIZE, pretrained=False, width=16).eval()
    x = torch.rand(2, 3, SIZE, SIZE)
    with torch.no_grad():
        before = model(x)
    with pytest.raises(ValueError, match="add_needle_branch"):
        model.deepen_needle_branch()
    model.add_needle_branch()
    model.deepen_needle_branch()
    with torch.no_grad():
        assert torch.allclose(model(x), before, atol=1e-6)  # its up8 is a copy too
    assert {name.split(".")[0] for name, p in model.named_parameters() if p.requires_grad} == {"needle_branch"}
    assert any(name.startswith("needle_branch.up8.") and p.requires_grad for name, p in model.named_parameters())
    optimizer = torch.optim.AdamW([p for p in model.parameters() if p.requires_grad], lr=1e-2)
    model.train()
    for _ in range(3):
        optimizer.zero_grad()
        model(x)[:, -1].sigmoid().mean().backward()
        optimizer.step()
    model.eval()
    with torch.no_grad():
        after = model(x)
    assert torch.equal(after[:, :-1], before[:, :-1])  # keypoint maps untouched
    assert not torch.equal(model.needle_branch.up8.fuse[0].weight, model.up8.fuse[0].weight)  # its own block learnt


def test_an_unfrozen_needle_branch_trains_the_trunk_too():
    model = CropNet(SIZE, pretrained=False, width=16)
    model.add_needle_branch()
    model.unfreeze()
    assert all(p.requires_grad for p in model.parameters())
    model.train()
    assert model.encoder.training  # its BatchNorms learn statistics again
    model.eval()
    x = torch.rand(2, 3, SIZE, SIZE)
    with torch.no_grad():
        before = model(x)
    optimizer = torch.optim.AdamW(model.parameters(), lr=1e-2)
    model.train()
    for _ in range(2):
        optimizer.zero_grad()
        model(x)[:, -1].sigmoid().mean().backward()
        optimizer.step()
    model.eval()
    with torch.no_grad():
        assert (model(x)[:, :-1] - before[:, :-1]).abs().mean() > 1e-4  # the keypoint maps drift with the trunk


def test_colour_swap_shuffles_the_image_channels_and_leaves_the_targets_alone():
    sample = tiny_sample(np.random.default_rng(3))
    sample = CropSample(np.dstack([np.full((SIZE, SIZE), v, np.uint8) for v in (10, 120, 240)]), sample.points,
                        sample.needle, "smoke")
    x0, t0, v0 = augmented(sample, SIZE, np.random.default_rng(5), 0.0)
    orders = set()
    for seed in range(12):
        x, t, v = augmented(sample, SIZE, np.random.default_rng(seed), 0.0, colour_swap=1.0)
        assert np.array_equal(t, t0) and np.array_equal(v, v0)
        means = tuple(np.round(x.mean(axis=(1, 2)) * 255).astype(int))
        assert sorted(means) == sorted(np.round(x0.mean(axis=(1, 2)) * 255).astype(int))
        orders.add(means)
    assert len(orders) > 1  # the channels really move
    x, _, _ = augmented(sample, SIZE, np.random.default_rng(0), 0.0, colour_swap=0.0)
    assert np.array_equal(x, x0)


def test_the_keypoint_decoder_trains_alone_and_leaves_a_needle_branch_as_it_was():
    torch.manual_seed(2)
    model = CropNet(SIZE, pretrained=False, width=16).eval()
    model.add_needle_branch()
    x = torch.rand(2, 3, SIZE, SIZE)
    with torch.no_grad():
        before = model(x)
    model.freeze_all_but_keypoint_decoder()
    assert {name.split(".")[0] for name, p in model.named_parameters() if p.requires_grad} == {"up4", "up2", "head"}
    model.train()
    assert not model.encoder.training and not model.up8.training and not model.needle_branch.training
    assert model.up4.training and model.head.training
    optimizer = torch.optim.AdamW([p for p in model.parameters() if p.requires_grad], lr=1e-2)
    for _ in range(3):
        optimizer.zero_grad()
        model(x)[:, :-1].sigmoid().mean().backward()
        optimizer.step()
    model.eval()
    with torch.no_grad():
        after = model(x)
    assert torch.equal(after[:, -1], before[:, -1])  # the needle mask, from its own branch, is untouched
    assert (after[:, :-1] - before[:, :-1]).abs().mean() > 1e-3  # the keypoint maps learnt


def test_notch_peaks_can_be_drawn_narrower_than_the_other_heatmaps():
    sample = tiny_sample(np.random.default_rng(4))
    _, wide, _ = augmented(sample, SIZE, None, 0.0)
    _, narrow, _ = augmented(sample, SIZE, None, 0.0, sigma_by_channel={"major": 0.75})
    major, pivot = CROP_CHANNELS.index("major"), CROP_CHANNELS.index("pivot")
    assert np.array_equal(narrow[pivot], wide[pivot])  # other channels keep the default width
    assert narrow[major].sum() < 0.5 * wide[major].sum()  # three peaks, each (0.75 / 1.5)^2 the mass
    # the peaks stay where they were: the narrow map's maxima are the wide map's
    assert np.array_equal(np.argwhere(narrow[major] == narrow[major].max()), np.argwhere(wide[major] == wide[major].max()))
