"""Rebuilding a torch crop net from its ONNX export (BatchNorm folded away) to fine-tune it."""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch", reason="the train extra (torch==2.13.0) is not installed")

from gauged.training.from_onnx import load_from_onnx  # noqa: E402
from gauged.training.nets import CropNet  # noqa: E402
from gauged.training.train_crop import export_onnx  # noqa: E402

SIZE = 64


def _trained_looking(seed: int) -> CropNet:
    """A net with non-trivial BatchNorm statistics and affine parameters, as after training."""
    torch.manual_seed(seed)
    model = CropNet(SIZE, pretrained=False, width=16)
    with torch.no_grad():
        for bn in (m for m in model.modules() if isinstance(m, torch.nn.BatchNorm2d)):
            bn.running_mean.uniform_(-0.5, 0.5)
            bn.running_var.uniform_(0.5, 2.0)
            bn.weight.uniform_(0.5, 1.5)
            bn.bias.uniform_(-0.2, 0.2)
    return model.eval()


def test_a_net_loaded_from_its_onnx_export_computes_the_same_maps_in_eval_and_nearly_in_train_mode(tmp_path):
    original = _trained_looking(0)
    export_onnx(original, SIZE, tmp_path / "crop.onnx", {"kind": "crop", "size": SIZE, "stride": 2})
    rng = np.random.default_rng(1)
    calibration = torch.from_numpy(rng.random((16, 3, SIZE, SIZE), dtype=np.float32))
    probe = torch.from_numpy(rng.random((4, 3, SIZE, SIZE), dtype=np.float32))

    rebuilt = CropNet(SIZE, pretrained=False, width=16)
    load_from_onnx(rebuilt, tmp_path / "crop.onnx", calibration)
    with torch.no_grad():
        expected = original(probe)
        assert torch.allclose(rebuilt.eval()(probe), expected, atol=1e-4)
        # train mode normalises by the batch's statistics, which the calibration made the BatchNorms
        # expect: the maps stay close (a net whose BatchNorms were reset would be far off)
        train_mode = rebuilt.train()(calibration)
        reference = original(calibration)
    assert float((train_mode - reference).abs().mean()) < 0.05 * float(reference.abs().mean())


def test_an_onnx_file_of_another_architecture_is_refused_naming_the_mismatch(tmp_path):
    export_onnx(_trained_looking(0), SIZE, tmp_path / "crop.onnx", {"kind": "crop", "size": SIZE, "stride": 2})
    wider = CropNet(SIZE, pretrained=False, width=24)
    with pytest.raises(ValueError, match="shape"):
        load_from_onnx(wider, tmp_path / "crop.onnx", torch.zeros(2, 3, SIZE, SIZE))


def test_a_net_with_a_needle_branch_reloads_from_its_export_only_when_built_with_the_branch(tmp_path):
    original = _trained_looking(2)
    original.add_needle_branch()
    with torch.no_grad():  # as after training the branch: its weights differ from the copied ones
        for p in original.needle_branch.parameters():
            p.add_(0.05 * torch.randn_like(p))
    original.eval()
    export_onnx(original, SIZE, tmp_path / "crop.onnx", {"kind": "crop", "size": SIZE, "stride": 2})
    rng = np.random.default_rng(3)
    calibration = torch.from_numpy(rng.random((16, 3, SIZE, SIZE), dtype=np.float32))
    probe = torch.from_numpy(rng.random((2, 3, SIZE, SIZE), dtype=np.float32))
    with pytest.raises(ValueError, match="convolutions"):
        load_from_onnx(CropNet(SIZE, pretrained=False, width=16), tmp_path / "crop.onnx", calibration)
    rebuilt = CropNet(SIZE, pretrained=False, width=16)
    rebuilt.add_needle_branch()
    load_from_onnx(rebuilt, tmp_path / "crop.onnx", calibration)
    rebuilt.eval()
    with torch.no_grad():
        assert torch.allclose(rebuilt(probe), original(probe), atol=1e-4)


def test_train_crop_knows_an_init_with_a_needle_branch(tmp_path):
    from gauged.training.train_crop import has_needle_branch

    plain, branched = _trained_looking(2), _trained_looking(2)
    branched.add_needle_branch()
    for net, name, branch in ((plain, "plain", False), (branched, "branched", True)):
        net.eval()
        export_onnx(net, SIZE, tmp_path / f"{name}.onnx", {"kind": "crop", "size": SIZE, "stride": 2, "needle_branch": branch})
        torch.save({"model": net.state_dict()}, tmp_path / f"{name}.pt")
        assert has_needle_branch(tmp_path / f"{name}.onnx") is branch
        assert has_needle_branch(tmp_path / f"{name}.pt") is branch


def test_train_crop_tells_a_deepened_needle_branch_from_a_plain_one(tmp_path):
    from gauged.training.train_crop import has_deep_needle_branch, has_needle_branch

    plain, deep = _trained_looking(4), _trained_looking(4)
    plain.add_needle_branch()
    deep.add_needle_branch()
    deep.deepen_needle_branch()
    for net, name, is_deep in ((plain, "plain", False), (deep, "deep", True)):
        net.eval()
        export_onnx(net, SIZE, tmp_path / f"{name}.onnx",
                    {"kind": "crop", "size": SIZE, "stride": 2, "needle_branch": True, "needle_branch_up8": is_deep})
        torch.save({"model": net.state_dict()}, tmp_path / f"{name}.pt")
        for path in (tmp_path / f"{name}.onnx", tmp_path / f"{name}.pt"):
            assert has_needle_branch(path) and has_deep_needle_branch(path) is is_deep


def test_a_deepened_needle_branch_reloads_from_its_export_when_built_deep(tmp_path):
    original = _trained_looking(5)
    original.add_needle_branch()
    original.deepen_needle_branch()
    with torch.no_grad():  # trained: the branch's own up8 no longer equals the shared one
        for p in original.needle_branch.parameters():
            p.add_(0.05 * torch.randn_like(p))
    original.eval()
    export_onnx(original, SIZE, tmp_path / "crop.onnx", {"kind": "crop", "size": SIZE, "stride": 2})
    rng = np.random.default_rng(6)
    calibration = torch.from_numpy(rng.random((16, 3, SIZE, SIZE), dtype=np.float32))
    probe = torch.from_numpy(rng.random((2, 3, SIZE, SIZE), dtype=np.float32))
    shallow = CropNet(SIZE, pretrained=False, width=16)
    shallow.add_needle_branch()
    with pytest.raises(ValueError, match="convolutions"):
        load_from_onnx(shallow, tmp_path / "crop.onnx", calibration)
    rebuilt = CropNet(SIZE, pretrained=False, width=16)
    rebuilt.add_needle_branch()
    rebuilt.deepen_needle_branch()
    load_from_onnx(rebuilt, tmp_path / "crop.onnx", calibration)
    rebuilt.eval()
    with torch.no_grad():
        assert torch.allclose(rebuilt(probe), original(probe), atol=1e-4)
