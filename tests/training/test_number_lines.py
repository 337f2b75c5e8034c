"""The number-line recogniser's data and training (session 10 groundwork, not used by the reader)."""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch", reason="the train extra (torch==2.13.0) is not installed")

from gauged.synth.crop import render_crop  # noqa: E402
from gauged.training.number_lines import (  # noqa: E402
    CHARS,
    LINE_HEIGHT,
    LINE_WIDTH,
    NumberNet,
    encode,
    exact_by_height,
    greedy_decode,
    number_lines,
    to_line_input,
    train_number_net,
)


def test_lines_of_a_render_carry_its_printed_numbers():
    sample = render_crop(7000003, 448, masks=False)
    lines = number_lines(sample.image, sample.truth, 1.0)
    printed = [n["text"] for s in sample.truth["scales"] for n in s["numbers"]]
    assert [text for _, text, _ in lines] == printed and len(printed) >= 3
    x = to_line_input(lines[0][0])
    assert x.shape == (LINE_HEIGHT, LINE_WIDTH) and x.dtype == np.uint8
    assert all(h > 3 for _, _, h in lines)


def test_ctc_labels_and_best_path():
    assert encode("-0,5") == [CHARS.index(c) + 1 for c in "-0,5"]
    assert encode("\u22122") == encode("-2")  # the typographic minus is a minus
    logits = torch.full((1, 6, len(CHARS) + 1), -5.0)
    for t, k in enumerate([2, 2, 0, 2, 0, 11]):  # "1", "1" (repeat merged), blank, "1", blank, "."
        logits[0, t, k] = 5.0
    assert greedy_decode(logits) == ["11."]


def test_training_writes_the_best_checkpoint(tmp_path):
    rng = np.random.default_rng(0)
    texts = np.array(["10", "20", "5", "0,5"] * 16)
    lines = rng.integers(0, 255, (len(texts), LINE_HEIGHT, LINE_WIDTH), dtype=np.uint8)
    heights = np.full(len(texts), 12.0, np.float32)
    np.savez(tmp_path / "d.npz", x=lines, t=texts, h=heights)
    best = train_number_net([tmp_path / "d.npz"], tmp_path / "d.npz", 1, tmp_path / "best.pt", batch=16, threads=1)
    assert 0.0 <= best["legible"] <= 1.0 and set(best) >= {"10-14", "legible"}
    net = NumberNet()
    net.load_state_dict(torch.load(tmp_path / "best.pt"))
    assert exact_by_height(net, lines, texts, heights)["legible"] == best["legible"]


def test_a_narrower_net_trains_and_exports_at_its_own_width(tmp_path):
    from gauged.reader.ocr.number_net import NumberNet as RuntimeNumberNet
    from gauged.training.number_lines import export_onnx, width_of

    rng = np.random.default_rng(1)
    texts = np.array(["10", "-5", "0.5", "200"] * 8)
    lines = rng.integers(0, 255, (len(texts), LINE_HEIGHT, LINE_WIDTH), dtype=np.uint8)
    np.savez(tmp_path / "d.npz", x=lines, t=texts, h=np.full(len(texts), 12.0, np.float32))
    train_number_net([tmp_path / "d.npz"], tmp_path / "d.npz", 1, tmp_path / "narrow.pt", batch=16, threads=1, width=16)
    state = torch.load(tmp_path / "narrow.pt")
    assert width_of(state) == 16 and state["features.0.0.weight"].numel() < NumberNet().features[0][0].weight.numel()
    export_onnx(tmp_path / "narrow.pt", tmp_path / "narrow.onnx")
    net = NumberNet(16)
    net.load_state_dict(state)
    net.eval()
    line = np.ascontiguousarray(np.repeat(lines[0][:, :, None], 3, axis=2))  # the runtime takes BGR lines
    with torch.no_grad():
        expected = greedy_decode(net(torch.from_numpy(lines[:1, None].astype(np.float32) / 255.0)))
    assert RuntimeNumberNet(tmp_path / "narrow.onnx", threads=1).read([line]) == expected


def test_compare_counts_every_main_scale_number_for_both_recognisers(tmp_path):
    import subprocess
    import sys

    from gauged.training.number_lines import compare_with_ppocr

    made = subprocess.run([sys.executable, "-m", "gauged", "synth", "images", "--kind", "crop", "--size", "448",
                           "--count", "2", "--seed", "5000100", "--out", str(tmp_path / "renders")],
                          capture_output=True, text=True, timeout=300)
    assert made.returncode == 0, made.stderr
    torch.manual_seed(0)
    torch.save(NumberNet().state_dict(), tmp_path / "untrained.pt")
    table = compare_with_ppocr(tmp_path / "renders", tmp_path / "untrained.pt")
    import json

    records = [json.loads(line) for line in (tmp_path / "renders" / "labels.jsonl").read_text().splitlines()]
    printed = sum(len(r["gauges"][0]["scales"][0]["numbers"]) for r in records)
    assert sum(row["numbers"] for row in table.values()) == printed
    assert all(0.0 <= row["number_net"] <= 1.0 for row in table.values())
    assert any(row["ppocr"] > 0.5 for row in table.values())  # PP-OCR reads clean renders' numbers
