"""Training and export of the minus net (:mod:`gauged.training.minus_lines` makes its data)."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import torch
from torch import nn
from torch.nn import functional as F

from gauged.reader.ocr.minus_net import INPUT_WIDTH
from gauged.reader.ocr.number_net import LINE_HEIGHT

log = logging.getLogger(__name__)

FALSE_RATE = 0.005  # of the numbers printed without a minus (not facing the ticks): the operating point
# the validation figure is read at (recall of the printed minus signs there)


class MinusNet(nn.Module):
    """(N, 1, 32, INPUT_WIDTH) grey in [0, 1] -> (N,) log-odds that a minus stands first."""

    def __init__(self, width: int = 16):
        super().__init__()

        def block(cin: int, cout: int) -> nn.Sequential:
            return nn.Sequential(nn.Conv2d(cin, cout, 3, padding=1, bias=False), nn.BatchNorm2d(cout), nn.ReLU(inplace=True))

        w = width
        self.features = nn.Sequential(block(1, w), nn.MaxPool2d(2), block(w, 2 * w), nn.MaxPool2d(2),
                                      block(2 * w, 4 * w), nn.MaxPool2d(2), block(4 * w, 4 * w))  # -> (4w, 4, 8)
        self.out = nn.Linear(4 * w * 4 * (INPUT_WIDTH // 8), 1)  # position matters: the minus stands at the left

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.out(F.dropout(self.features(x).flatten(1), 0.2, self.training)).squeeze(1)


def _load(paths: list[Path]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    parts = [np.load(p) for p in paths]
    return (np.concatenate([p["x"] for p in parts]), np.concatenate([p["minus"] for p in parts]),
            np.concatenate([p["faces"] for p in parts]))


def _augmented(x: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """A batch (N, 32, W) uint8 with each line's brightness, contrast, polarity, noise and position varied."""
    out = x.astype(np.float32)
    n = len(out)
    flip = rng.random(n) < 0.15
    out[flip] = 255.0 - out[flip]  # light numbers on a dark face
    out = out * rng.uniform(0.7, 1.3, (n, 1, 1)) + rng.uniform(-30, 30, (n, 1, 1))
    noisy = rng.random(n) < 0.3
    out[noisy] += rng.normal(0, 1, out[noisy].shape) * rng.uniform(2, 10, (int(noisy.sum()), 1, 1))
    for i in np.flatnonzero(rng.random(n) < 0.5):  # shifted up to 2 px either way, edge repeated
        dy, dx = rng.integers(-2, 3, 2)
        out[i] = np.roll(out[i], (dy, dx), axis=(0, 1))
    return np.clip(out, 0, 255) / 255.0


def scores(net: MinusNet, x: np.ndarray) -> np.ndarray:
    net.eval()
    with torch.no_grad():
        return np.concatenate([net(torch.from_numpy(x[i:i + 512, None].astype(np.float32) / 255.0)).numpy()
                               for i in range(0, len(x), 512)])


def operating_point(odds: np.ndarray, minus: np.ndarray, faces: np.ndarray) -> dict[str, float]:
    """Recall of the printed minus signs at the threshold that passes :data:`FALSE_RATE` of the numbers
    without (both over the lines not facing the ticks), and the threshold."""
    keep = ~faces
    neg, pos = odds[keep & ~minus], odds[keep & minus]
    threshold = float(np.quantile(neg, 1 - FALSE_RATE)) if len(neg) else 0.0
    return {"recall": float((pos > threshold).mean()) if len(pos) else float("nan"), "threshold": threshold,
            "false_at_0": float((neg > 0).mean()) if len(neg) else float("nan"),
            "recall_at_0": float((pos > 0).mean()) if len(pos) else float("nan"),
            "minus": int(len(pos)), "without": int(len(neg))}


def train(data: list[Path], val: Path, out: Path, epochs: int = 12, threads: int = 2, batch: int = 128,
          lr: float = 2e-3, seed: int = 0) -> dict[str, float]:
    """Train on every margin's cut of every line of ``data``; keep the checkpoint whose recall at the
    operating point (:func:`operating_point`, on ``val``'s reader margin) is best at ``out``."""
    torch.set_num_threads(threads)
    torch.manual_seed(seed)
    rng = np.random.default_rng(seed)
    x, minus, _ = _load(data)
    vx, vminus, vfaces = _load([val])
    cuts = x.shape[1]
    vx = vx[:, cuts // 2]  # the reader's own margin
    net = MinusNet()
    opt = torch.optim.AdamW(net.parameters(), lr=lr, weight_decay=1e-4)
    steps = epochs * (len(x) // batch)
    sched = torch.optim.lr_scheduler.OneCycleLR(opt, max_lr=lr, total_steps=steps)
    pos_weight = torch.tensor(float(max(1.0, (~minus).sum() / max(1, minus.sum())) ** 0.5))
    best: dict[str, float] = {"recall": -1.0}
    out.parent.mkdir(parents=True, exist_ok=True)
    for epoch in range(epochs):
        net.train()
        order = rng.permutation(len(x))
        total = 0.0
        for start in range(0, len(order) - batch + 1, batch):
            idx = order[start:start + batch]
            xb = _augmented(x[idx, rng.integers(0, cuts, len(idx))], rng)
            logits = net(torch.from_numpy(xb[:, None].astype(np.float32)))
            loss = F.binary_cross_entropy_with_logits(logits, torch.from_numpy(minus[idx].astype(np.float32)),
                                                      pos_weight=pos_weight)
            opt.zero_grad()
            loss.backward()
            opt.step()
            sched.step()
            total += loss.item() * len(idx)
        point = operating_point(scores(net, vx), vminus, vfaces)
        log.info("epoch %d: loss %.4f, val %s", epoch + 1, total / len(order), point)
        if point["recall"] > best["recall"]:
            best = {**point, "epoch": epoch + 1}
            torch.save(net.state_dict(), out)
    return best


def export_onnx(weights: Path, out: Path) -> None:
    net = MinusNet()
    net.load_state_dict(torch.load(weights, map_location="cpu"))
    net.eval()
    dummy = torch.zeros(1, 1, LINE_HEIGHT, INPUT_WIDTH)
    out.parent.mkdir(parents=True, exist_ok=True)
    torch.onnx.export(net, dummy, str(out), input_names=["line"], output_names=["log_odds"],
                      dynamic_axes={"line": {0: "n"}, "log_odds": {0: "n"}}, opset_version=17, dynamo=False)
