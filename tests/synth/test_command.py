"""``gauged synth`` through argparse: images, sheet, recording, and usage errors."""

from __future__ import annotations

import argparse
import json

import cv2
import pytest

from gauged.commands import synth


def _parse(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="gauged")
    synth.register(parser.add_subparsers(dest="command"))
    return parser.parse_args(argv)


def test_images_writes_labels_and_same_seed_same_files(tmp_path, capsys):
    for name in ("a", "b"):
        args = _parse(["synth", "images", "--count", "2", "--seed", "3", "--out", str(tmp_path / name),
                       "--width", "320", "--height", "240"])
        assert args.func(args) == 0
    lines = (tmp_path / "a" / "labels.jsonl").read_text().splitlines()
    assert [json.loads(line)["image"] for line in lines] == ["000000.jpg", "000001.jpg"]
    assert (tmp_path / "a" / "labels.jsonl").read_bytes() == (tmp_path / "b" / "labels.jsonl").read_bytes()
    assert (tmp_path / "a" / "000001.jpg").read_bytes() == (tmp_path / "b" / "000001.jpg").read_bytes()
    assert "wrote 2 scene images" in capsys.readouterr().out


def test_images_crops_with_masks(tmp_path):
    args = _parse(["synth", "images", "--count", "1", "--kind", "crop", "--size", "160", "--masks", "--out", str(tmp_path)])
    assert args.func(args) == 0
    mask = cv2.imread(str(tmp_path / "masks" / "000000.png"), cv2.IMREAD_UNCHANGED)
    assert mask.shape == (160, 160) and set(mask.ravel().tolist()) <= {0, 1, 2} and (mask == 1).any()


def test_sheet_writes_the_grid(tmp_path):
    args = _parse(["synth", "sheet", "--out", str(tmp_path / "s.png"), "--count", "8", "--tile", "64"])
    assert args.func(args) == 0
    assert cv2.imread(str(tmp_path / "s.png")).shape == (64, 512, 3)


def test_recording_writes_mcap(tmp_path):
    out = tmp_path / "r.mcap"
    args = _parse(["synth", "recording", "--seconds", "1", "--fps", "2", "--gauges", "1", "--out", str(out),
                   "--width", "320", "--height", "240", "--ros2"])
    assert args.func(args) == 0 and out.stat().st_size > 1000


def test_usage_errors(tmp_path):
    with pytest.raises(SystemExit):
        _parse(["synth", "images", "--count", "0", "--out", str(tmp_path)])
    args = _parse(["synth", "recording", "--out", str(tmp_path / "missing" / "r.mcap")])
    assert args.func(args) == 2
    (tmp_path / "file").write_text("x")
    args = _parse(["synth", "images", "--count", "1", "--out", str(tmp_path / "file")])
    assert args.func(args) == 2


def test_images_same_files_with_two_workers(tmp_path):
    for name, workers in (("one", "1"), ("two", "2")):
        args = _parse(["synth", "images", "--count", "3", "--seed", "9", "--kind", "crop", "--size", "96",
                       "--workers", workers, "--out", str(tmp_path / name)])
        assert args.func(args) == 0
    assert (tmp_path / "one" / "labels.jsonl").read_bytes() == (tmp_path / "two" / "labels.jsonl").read_bytes()
    assert (tmp_path / "one" / "000002.jpg").read_bytes() == (tmp_path / "two" / "000002.jpg").read_bytes()


def test_images_direction_sets_which_way_the_scales_rise(tmp_path):
    directions = {}
    for name in ("cw", "ccw", "mixed"):
        argv = ["synth", "images", "--count", "6", "--seed", "2", "--kind", "crop", "--size", "96", "--out",
                str(tmp_path / name)] + ([] if name == "cw" else ["--direction", name])
        args = _parse(argv)
        assert args.direction == name and args.func(args) == 0
        records = [json.loads(line) for line in (tmp_path / name / "labels.jsonl").read_text().splitlines()]
        directions[name] = {s["direction"] for r in records for g in r["gauges"] for s in g["scales"]}
    assert directions["cw"] == {"cw"} and directions["ccw"] == {"ccw"}
    with pytest.raises(SystemExit):
        _parse(["synth", "images", "--count", "1", "--out", str(tmp_path), "--direction", "left"])
    for sub in (["sheet", "--out", "s.png"], ["recording", "--out", "r.mcap"]):
        assert _parse(["synth", *sub, "--direction", "ccw"]).direction == "ccw"
