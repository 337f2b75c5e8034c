"""A small, resumable training loop shared by the crop model and the detector.

Checkpoints (model, optimiser, scheduler, epoch, best metric) are written after every epoch to
``<run_dir>/last.pt`` and the best-by-validation model to ``<run_dir>/best.pt``; starting again with
the same ``run_dir`` resumes where the last completed epoch ended, so a session limit loses at most
one epoch. Progress goes to the log and to ``<run_dir>/history.jsonl``.
"""

from __future__ import annotations

import json
import logging
import math
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

import torch
from torch import nn

log = logging.getLogger(__name__)

Batch = tuple[torch.Tensor, ...]
LossFn = Callable[[nn.Module, Batch], dict[str, torch.Tensor]]
ValidateFn = Callable[[nn.Module], dict[str, float]]


@dataclass
class TrainSettings:
    epochs: int
    lr: float = 2e-3
    weight_decay: float = 1e-4
    warmup_steps: int = 200
    higher_is_better: bool = True
    metric: str = "score"
    log_every: int = 50


def _lr_lambda(total_steps: int, warmup: int) -> Callable[[int], float]:
    def factor(step: int) -> float:
        if step < warmup:
            return (step + 1) / warmup
        progress = (step - warmup) / max(1, total_steps - warmup)
        return 0.02 + 0.98 * 0.5 * (1 + math.cos(math.pi * min(1.0, progress)))

    return factor


def train(model: nn.Module, batches: Callable[[int], Iterable[Batch]], steps_per_epoch: int,
          loss_fn: LossFn, validate: ValidateFn, settings: TrainSettings, run_dir: Path) -> dict[str, float]:
    """Train ``model`` for ``settings.epochs``; ``batches(epoch)`` yields the epoch's batches.

    Returns the best validation metrics. Resumes from ``run_dir/last.pt`` when it exists.
    """
    run_dir.mkdir(parents=True, exist_ok=True)
    optimizer = torch.optim.AdamW(model.parameters(), lr=settings.lr, weight_decay=settings.weight_decay)
    scheduler = torch.optim.lr_scheduler.LambdaLR(
        optimizer, _lr_lambda(settings.epochs * steps_per_epoch, settings.warmup_steps))
    start_epoch, best = 0, None
    last = run_dir / "last.pt"
    if last.exists():
        state = torch.load(last, map_location="cpu", weights_only=False)
        model.load_state_dict(state["model"])
        optimizer.load_state_dict(state["optimizer"])
        scheduler.load_state_dict(state["scheduler"])
        start_epoch, best = state["epoch"] + 1, state.get("best")
        log.info("resuming %s at epoch %d (best %s so far: %s)", run_dir, start_epoch + 1, settings.metric, best)
    best_metrics: dict[str, float] = {}
    for epoch in range(start_epoch, settings.epochs):
        model.train()
        started, sums, count = time.monotonic(), {}, 0
        for step, batch in enumerate(batches(epoch)):
            losses = loss_fn(model, batch)
            optimizer.zero_grad(set_to_none=True)
            losses["loss"].backward()
            nn.utils.clip_grad_norm_(model.parameters(), 5.0)
            optimizer.step()
            scheduler.step()
            count += 1
            for key, value in losses.items():
                sums[key] = sums.get(key, 0.0) + float(value.detach())
            if step % settings.log_every == 0:
                log.info("epoch %d/%d step %d/%d loss %.4f (%.0f s)", epoch + 1, settings.epochs, step,
                         steps_per_epoch, float(losses["loss"].detach()), time.monotonic() - started)
        model.eval()
        with torch.no_grad():
            metrics = validate(model)
        metric = metrics[settings.metric]
        improved = best is None or (metric > best if settings.higher_is_better else metric < best)
        if improved:
            best, best_metrics = metric, dict(metrics)
            torch.save({"model": model.state_dict(), "epoch": epoch, "metrics": metrics}, run_dir / "best.pt")
        torch.save({"model": model.state_dict(), "optimizer": optimizer.state_dict(),
                    "scheduler": scheduler.state_dict(), "epoch": epoch, "best": best}, last)
        record = {"epoch": epoch + 1, "seconds": round(time.monotonic() - started, 1),
                  **{f"train_{k}": round(v / max(1, count), 5) for k, v in sums.items()}, **metrics}
        with (run_dir / "history.jsonl").open("a") as history:
            history.write(json.dumps(record) + "\n")
        log.info("epoch %d done: %s%s", epoch + 1, json.dumps(metrics), " (best)" if improved else "")
    if not best_metrics and (run_dir / "best.pt").exists():
        best_metrics = torch.load(run_dir / "best.pt", map_location="cpu", weights_only=False)["metrics"]
    return best_metrics
