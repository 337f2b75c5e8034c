"""Start training from a shipped ONNX file: rebuild the torch net whose export it is.

Checkpoints live in ``runs/`` and are not committed, so a later session that wants to fine-tune the
shipped ``crop.onnx`` has only the ONNX file. The export folded every BatchNorm into the convolution
before it (``y = W'x + b'``); this module loads ``W'`` and ``b'`` back and gives each BatchNorm the
statistics of its input on calibration images, so that

- in eval mode the torch net computes exactly the ONNX function (``gamma (x - m) / sqrt(v + eps) + beta``
  with ``gamma = sqrt(v + eps)``, ``beta = m + b'`` is ``x + b'``), and
- in train mode, where BatchNorm normalises by the batch's own statistics, it computes nearly the
  same function from the first step on (the batch statistics are close to the calibration ones),
  so fine-tuning continues from the shipped model instead of from a shock.

Convolutions are matched by execution order: the ONNX graph lists its Conv nodes in the order the
torch forward pass ran them, and each torch BatchNorm that directly follows a convolution belongs to it.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import torch
from torch import nn


def _execution_order(model: nn.Module, example: torch.Tensor) -> list[nn.Module]:
    """Conv2d and BatchNorm2d modules in the order a forward pass calls them."""
    order: list[nn.Module] = []
    hooks = [m.register_forward_hook(lambda mod, _i, _o: order.append(mod))
             for m in model.modules() if isinstance(m, (nn.Conv2d, nn.BatchNorm2d))]
    try:
        with torch.no_grad():
            model(example)
    finally:
        for hook in hooks:
            hook.remove()
    return order


def _onnx_convs(path: Path) -> list[tuple[np.ndarray, np.ndarray | None]]:
    """(weight, bias or None) of every Conv node of the ONNX graph, in graph order."""
    import onnx
    from onnx import numpy_helper

    graph = onnx.load(str(path)).graph
    tensors = {init.name: numpy_helper.to_array(init) for init in graph.initializer}
    convs = []
    for node in graph.node:
        if node.op_type != "Conv":
            continue
        weight = tensors[node.input[1]]
        bias = tensors[node.input[2]] if len(node.input) > 2 and node.input[2] else None
        convs.append((weight, bias))
    return convs


def initialise(model: nn.Module, init: Path, calibration: Callable[[], torch.Tensor]) -> str:
    """Load ``model``'s starting weights from ``init``: a shipped ONNX export (``.onnx``, its
    BatchNorms calibrated on the batch ``calibration()`` returns) or a training checkpoint. Returns
    what was done, for the log. Build the model without pretrained weights for an ONNX start."""
    if init.suffix == ".onnx":
        batch = calibration()
        load_from_onnx(model, init, batch)
        return f"initialised from the ONNX export {init} (BatchNorm calibrated on {len(batch)} inputs)"
    model.load_state_dict(torch.load(init, map_location="cpu", weights_only=False)["model"])
    return f"initialised from {init}"


def load_from_onnx(model: nn.Module, path: Path, calibration: torch.Tensor) -> None:
    """Set ``model``'s weights from the ONNX export at ``path`` (see the module docstring).

    ``calibration``: a batch (N, 3, S, S) of representative inputs for the BatchNorm statistics.
    Raises ValueError when the graph's convolutions do not match the model's one for one.
    """
    model.eval()
    order = _execution_order(model, calibration[:1])
    pairs: list[tuple[nn.Conv2d, nn.BatchNorm2d | None]] = []
    for index, module in enumerate(order):
        if isinstance(module, nn.Conv2d):
            follower = order[index + 1] if index + 1 < len(order) else None
            pairs.append((module, follower if isinstance(follower, nn.BatchNorm2d) else None))
    convs = _onnx_convs(path)
    if len(convs) != len(pairs):
        raise ValueError(f"{path}: {len(convs)} convolutions in the graph, {len(pairs)} in the model")
    with torch.no_grad():
        for number, ((conv, bn), (weight, bias)) in enumerate(zip(pairs, convs)):
            if tuple(conv.weight.shape) != weight.shape:
                raise ValueError(f"{path}: convolution {number} has shape {weight.shape}, the model's {tuple(conv.weight.shape)}")
            conv.weight.copy_(torch.from_numpy(weight.copy()))
            if bn is None:
                if (bias is None) != (conv.bias is None):
                    raise ValueError(f"{path}: convolution {number} bias does not match the model's")
                if bias is not None:
                    conv.bias.copy_(torch.from_numpy(bias))
                continue
            fused_bias = torch.zeros(weight.shape[0]) if bias is None else torch.from_numpy(bias.copy())
            # Identity plus the fused bias: (x - 0) / sqrt((1 - eps) + eps) * 1 + b'.
            bn.running_mean.zero_()
            bn.running_var.fill_(1.0 - bn.eps)
            bn.weight.fill_(1.0)
            bn.bias.copy_(fused_bias)
        _calibrate_batchnorms(model, calibration)


def _calibrate_batchnorms(model: nn.Module, calibration: torch.Tensor) -> None:
    """Give each identity-plus-bias BatchNorm its input's statistics without changing its eval output."""
    stats: dict[nn.BatchNorm2d, tuple[torch.Tensor, torch.Tensor]] = {}

    def record(module, inputs, _output):
        x = inputs[0]
        stats[module] = (x.mean(dim=(0, 2, 3)), x.var(dim=(0, 2, 3), unbiased=False))

    bns = [m for m in model.modules() if isinstance(m, nn.BatchNorm2d)]
    hooks = [bn.register_forward_hook(record) for bn in bns]
    try:
        model(calibration)  # eval mode: every BatchNorm is still identity plus bias
    finally:
        for hook in hooks:
            hook.remove()
    for bn in bns:
        mean, var = stats[bn]
        fused_bias = bn.bias.clone()
        bn.running_mean.copy_(mean)
        bn.running_var.copy_(var)
        bn.weight.copy_(torch.sqrt(var + bn.eps))
        bn.bias.copy_(mean + fused_bias)
