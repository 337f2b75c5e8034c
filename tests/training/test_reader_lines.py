"""The reader's own lines, labelled from the truth (gauged.training.reader_lines)."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np

from gauged.training.reader_lines import label_line, observing_lines, write_reader_lines

NUMBER = {"text": "40", "kind": "number", "quad": [[100, 100], [120, 100], [120, 110], [100, 110]]}
BRAND = {"text": "ACME", "kind": "brand", "quad": [[100, 200], [160, 200], [160, 212], [100, 212]]}


def _box(x0, y0, x1, y1):
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], float)


def test_a_line_holding_the_whole_number_reads_it():
    assert label_line(_box(96, 97, 124, 113), [NUMBER, BRAND]) == ("40", "number", 10.0)


def test_a_line_holding_part_of_the_number_is_left_out():
    label, why, _ = label_line(_box(96, 97, 111, 113), [NUMBER, BRAND])  # the "4" alone
    assert (label, why) == (None, "partial")


def test_a_line_read_upside_down_is_left_out():
    upside_down = _box(96, 97, 124, 113)[[2, 3, 0, 1]]  # reading direction right to left
    assert label_line(upside_down, [NUMBER])[:2] == (None, "turned")


def test_a_box_over_two_numbers_is_left_out():
    assert label_line(_box(60, 90, 160, 120), [NUMBER])[:2] == (None, "partial")  # 15x the number's area


def test_a_line_far_from_every_text_reads_nothing_and_one_over_other_text_is_left_out():
    assert label_line(_box(300, 300, 320, 310), [NUMBER, BRAND]) == ("", "nothing", 0.0)
    assert label_line(_box(98, 198, 162, 214), [NUMBER, BRAND])[:2] == (None, "other_text")


def test_lines_of_a_render_are_labelled_with_its_printed_numbers(tmp_path):
    made = subprocess.run([sys.executable, "-m", "gauged", "synth", "images", "--kind", "crop", "--size", "448",
                           "--count", "3", "--seed", "5000300", "--out", str(tmp_path / "renders")],
                          capture_output=True, text=True, timeout=300)
    assert made.returncode == 0, made.stderr
    import gauged.reader.ocr.dial_reader as dial_reader
    import gauged.reader.stages.ocr as ocr

    before = ocr.crop_quad
    seen = []
    why = write_reader_lines(tmp_path / "renders", tmp_path / "lines.npz", workers=1, progress=seen.append)
    assert ocr.crop_quad is before and dial_reader.crop_quad is before  # the reader is observed only inside observing_lines
    lines = np.load(tmp_path / "lines.npz")
    records = [json.loads(line) for line in (tmp_path / "renders" / "labels.jsonl").read_text().splitlines()]
    printed = {r["image"]: {n["text"] for g in r["gauges"] for s in g["scales"] for n in s["numbers"]} for r in records}
    numbers = [(image, text) for image, text in zip(lines["image"], lines["t"], strict=True) if text]
    assert len(numbers) >= 5 and why["number"] == len(numbers)
    assert all(text in printed[image] for image, text in numbers)
    assert lines["x"].shape[1:] == (32, 128) and (lines["h"][lines["t"] != ""] > 2).all()
    assert seen and seen[-1].startswith("read 3/3 images")


def test_observing_restores_the_reader_after_an_error():
    import gauged.reader.pipeline as pipeline

    before = pipeline.crop_gauge
    try:
        with observing_lines():
            assert pipeline.crop_gauge is not before
            raise RuntimeError("boom")
    except RuntimeError:
        pass
    assert pipeline.crop_gauge is before
