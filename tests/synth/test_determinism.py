"""Same seed, same bytes: crops, scenes, labels; different seeds differ."""

from __future__ import annotations

import json

import numpy as np

from gauged.synth.crop import render_crop
from gauged.synth.dataset import render_item
from gauged.synth.scene import render_scene


def test_render_crop_same_seed_same_bytes():
    a, b = render_crop(123, size=256), render_crop(123, size=256)
    assert a.image.tobytes() == b.image.tobytes()
    assert a.needle_mask.tobytes() == b.needle_mask.tobytes()
    assert json.dumps(a.truth) == json.dumps(b.truth)
    assert render_crop(124, size=256).image.tobytes() != a.image.tobytes()


def test_render_crop_accepts_a_generator_like_a_seed():
    a = render_crop(np.random.default_rng(5), size=128)
    b = render_crop(5, size=128)
    assert a.image.tobytes() == b.image.tobytes()


def test_render_scene_same_seed_same_bytes():
    a, b = render_scene(7, 640, 360), render_scene(7, 640, 360)
    assert a.image.tobytes() == b.image.tobytes()
    assert json.dumps(a.record) == json.dumps(b.record)
    assert render_scene(8, 640, 360).image.tobytes() != a.image.tobytes()


def test_batch_items_do_not_depend_on_order():
    first = render_item(("crop", 3, 5, 0, 0, 128, False))
    render_item(("scene", 3, 4, 320, 240, 0, False))  # something else in between
    again = render_item(("crop", 3, 5, 0, 0, 128, False))
    assert first[0].tobytes() == again[0].tobytes()


def test_scene_truth_is_json_serialisable_with_documented_keys():
    record = render_scene(11, 640, 360, n_gauges=3).record
    text = json.dumps(record)
    assert json.loads(text) == record
    for gauge in record["gauges"]:
        assert {"gauge", "box", "box_unclipped", "face_box", "face", "bezel", "pivot", "visible_fraction", "diameter_px",
                "needle", "value", "unit", "min", "max", "scales", "texts"} <= set(gauge)
        for scale in gauge["scales"]:
            assert {"role", "min", "max", "unit", "ellipse", "start", "end", "majors", "numbers", "unit_label",
                    "reading"} <= set(scale)
