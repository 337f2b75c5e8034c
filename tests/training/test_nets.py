"""The crop net's optional parts start where the net was: a needle refiner adds zero, auxiliary
heatmaps leave the shipped maps alone and are not exported."""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch", reason="the train extra (torch==2.13.0) is not installed")

from gauged.reader.stages.keypoints import CROP_CHANNELS  # noqa: E402
from gauged.training.nets import CropNet  # noqa: E402
from gauged.training.train_crop import export_onnx, shipped_maps, train_channels  # noqa: E402

SIZE = 64


def _net(seed: int) -> CropNet:
    torch.manual_seed(seed)
    model = CropNet(SIZE, pretrained=False, width=16)
    model.add_needle_branch()
    model.deepen_needle_branch()
    return model.eval()


def _probe() -> torch.Tensor:
    return torch.from_numpy(np.random.default_rng(2).random((2, 3, SIZE, SIZE), dtype=np.float32))


def test_a_new_needle_refiner_leaves_the_maps_as_they_were_and_then_trains() -> None:
    model = _net(0)
    with torch.no_grad():
        before = model(_probe())
    model.refine_needle_branch(width=8)
    with torch.no_grad():
        after = model(_probe())
    assert torch.equal(before, after)
    trainable = {name.split(".")[1] for name, p in model.named_parameters() if p.requires_grad and name.startswith("needle_branch")}
    assert "refiner" in trainable
    assert not any(p.requires_grad for name, p in model.named_parameters() if name.startswith("encoder."))


def test_auxiliary_heatmaps_sit_before_the_needle_row_and_are_dropped_at_export(tmp_path) -> None:
    model = _net(1)
    with torch.no_grad():
        shipped = model(_probe())
    model.add_aux_heatmaps(("minor",))
    with torch.no_grad():
        trained = model(_probe())
    assert trained.shape[1] == len(CROP_CHANNELS) + 1
    assert train_channels(model.aux_heatmaps) == CROP_CHANNELS[:-1] + ("minor",) + CROP_CHANNELS[-1:]
    assert torch.equal(torch.from_numpy(shipped_maps(trained[0].numpy())), shipped[0])
    assert torch.all(trained[:, len(CROP_CHANNELS) - 1] == -4.0)  # the new row starts low: "no minor notch"

    export_onnx(model, SIZE, tmp_path / "crop.onnx", {"kind": "crop", "size": SIZE, "stride": 2})
    import onnxruntime as ort

    session = ort.InferenceSession(str(tmp_path / "crop.onnx"), providers=["CPUExecutionProvider"])
    maps = session.run(None, {"image": _probe()[:1].numpy()})[0]
    assert maps.shape == (1, len(CROP_CHANNELS), SIZE // 2, SIZE // 2)
    np.testing.assert_allclose(maps, shipped[:1].numpy(), atol=1e-4)


@pytest.mark.parametrize("variant", ["lite0", "lite1", "lite2"])
def test_each_encoder_taps_its_declared_channels_at_strides_2_to_16_and_the_crop_net_runs_on_it(variant: str) -> None:
    from gauged.training.nets import ENCODERS, Encoder

    encoder = Encoder(SIZE, pretrained=False, variant=variant).eval()
    with torch.no_grad():
        features = encoder(_probe())
    _, channels = ENCODERS[variant]
    assert {stride: tuple(f.shape[1:]) for stride, f in features.items()} == {
        stride: (channels[stride], SIZE // stride, SIZE // stride) for stride in (2, 4, 8, 16)}
    model = CropNet(SIZE, pretrained=False, width=16, encoder=variant).eval()
    with torch.no_grad():
        assert model(_probe()).shape == (2, len(CROP_CHANNELS), SIZE // 2, SIZE // 2)


def test_an_unknown_encoder_is_refused_by_name() -> None:
    with pytest.raises(ValueError, match="unknown encoder 'lite9'"):
        CropNet(SIZE, pretrained=False, encoder="lite9")
