from __future__ import annotations

import json
import math

from gauged.evaluation.readings import Label, evaluate, format_table, load_labels, report
from gauged.types import StageFailure


def test_report_counts_failures_and_separates_needle_at_rest(tmp_path):
    labels = [Label("a.jpg", 5.0, 0, 10), Label("b.jpg", 0.0, 0, 10), Label("c.jpg", 2.0, 0, 10), Label("d.jpg", 10.0, 0, 10)]
    answers = {"a.jpg": (5.5, None), "b.jpg": (0.0, None), "c.jpg": (None, StageFailure("ocr", "no_numbers")),
               "d.jpg": (9.0, None)}
    result = report(evaluate(labels, lambda label: answers[label.image]))
    everything = result["all"]
    assert everything["count"] == 4 and everything["failures"] == 1
    assert math.isclose(everything["mean_relative_error"], (0.05 + 0 + 0.1) / 3)
    assert math.isclose(everything["mean_relative_error_all"], (0.05 + 0 + 0.1 + 1.0) / 4)
    assert math.isclose(everything["max_relative_error"], 0.1)
    assert everything["failures_by_reason"] == {"ocr/no_numbers": 1}
    assert result["needle_at_rest"]["count"] == 2 and result["needle_off_rest"]["count"] == 2
    assert "needle_at_rest" in format_table(result)


def test_load_labels_reads_json_and_jsonl(tmp_path):
    (tmp_path / "labels.json").write_text(json.dumps([{"image": "x.jpg", "reading": 1, "min": 0, "max": 4}]))
    assert load_labels(tmp_path) == [Label("x.jpg", 1.0, 0.0, 4.0)]
    (tmp_path / "labels.json").unlink()
    (tmp_path / "labels.jsonl").write_text('{"image": "y.png", "reading": -1, "min": -1, "max": 3}\n')
    assert load_labels(tmp_path)[0].at_rest


def test_load_labels_on_the_real_dev_set(shared_datasets):
    labels = load_labels(shared_datasets / "gauge-readings-dev")
    assert len(labels) == 21 and all(l.max > l.min for l in labels)


def _synth_record(image: str, number_height: float, render_scale: float | None = None) -> dict:
    quads = [[[x, 50.0], [x + 20.0, 50.0], [x + 20.0, 50.0 + number_height], [x, 50.0 + number_height]] for x in (10.0, 40.0, 70.0)]
    scale = {"role": "primary", "numbers": [{"text": t, "quad": q} for t, q in zip("012", quads)]}
    record = {"image": image, "gauges": [{"box": [0, 0, 100, 100], "value": 1.0, "min": 0.0, "max": 2.0, "scales": [scale]}]}
    return record if render_scale is None else record | {"render_scale": render_scale}


def test_synthetic_labels_break_the_table_down_by_printed_number_height(tmp_path):
    # "far" is 16 px tall in the image but was rendered at a quarter and upsampled: captured 4 px tall
    records = [_synth_record("small.jpg", 8.0), _synth_record("mid.jpg", 12.0), _synth_record("large.jpg", 30.0, 1.0),
               _synth_record("far.jpg", 16.0, 0.25)]
    (tmp_path / "labels.jsonl").write_text("".join(json.dumps(r) + "\n" for r in records))
    labels = load_labels(tmp_path)
    assert [l.number_px for l in labels] == [8.0, 12.0, 30.0, 16.0]
    assert [l.captured_number_px for l in labels] == [8.0, 12.0, 30.0, 4.0]
    answers = {"small.jpg": (None, StageFailure("ocr", "no_text")), "mid.jpg": (1.1, None), "large.jpg": (1.0, None),
               "far.jpg": (None, StageFailure("ocr", "no_text"))}
    result = report(evaluate(labels, lambda label: answers[label.image]))
    bins = result["by_number_height"]
    assert bins["numbers 0-5 px"]["count"] == 1 and bins["numbers 0-5 px"]["failures"] == 1
    assert bins["numbers 5-10 px"]["count"] == 1 and bins["numbers 5-10 px"]["failures"] == 1
    assert bins["numbers 10-14 px"]["count"] == 1 and math.isclose(bins["numbers 10-14 px"]["mean_relative_error"], 0.05)
    assert bins["numbers 14-18 px"]["count"] == 0 and bins["numbers >= 18 px"]["failures"] == 0
    assert [i["captured_number_px"] for i in result["images"]] == [8.0, 12.0, 30.0, 4.0]
    assert "numbers >= 18 px" in format_table(result)
    # the real dev format has no number boxes: no breakdown
    assert "by_number_height" not in report(evaluate([Label("x.jpg", 1.0, 0.0, 2.0)], lambda label: (1.0, None)))


def test_units_of_readings_are_counted_where_the_dial_prints_its_unit(tmp_path):
    record = {"image": "a.jpg", "gauges": [{"box": [0, 0, 10, 10], "value": 1.0, "min": 0.0, "max": 2.0, "scales": [
        {"role": "primary", "unit": "psi", "unit_label": {"text": "PSI"}},
        {"role": "secondary", "unit": "bar", "unit_label": {"text": "bar"}}]}]}
    unprinted = dict(record, image="b.jpg")
    unprinted["gauges"] = [dict(record["gauges"][0], scales=[{"role": "primary", "unit": "bar", "unit_label": None}])]
    (tmp_path / "labels.jsonl").write_text("\n".join(json.dumps(r) for r in (record, unprinted)) + "\n")
    labels = load_labels(tmp_path)
    assert [l.unit for l in labels] == ["psi", None]
    answers = {"a.jpg": (1.0, None, "bar"), "b.jpg": (1.0, None, "bar")}
    result = report(evaluate(labels, lambda label: answers[label.image]))
    assert result["units"] == {"labelled": 1, "right": 0, "wrong": 1, "none": 0}
    assert "1 wrong" in format_table(result)
    result = report(evaluate(labels[:1], lambda label: (None, StageFailure("ocr", "no_text"))))
    assert result["units"] == {"labelled": 0, "right": 0, "wrong": 0, "none": 0}


def test_confidence_auc_ranks_right_readings_above_wrong_ones():
    import pytest

    from gauged.evaluation.readings import Label, Outcome, confidence_auc

    label = Label("x.jpg", reading=50.0, min=0.0, max=100.0)
    right = [Outcome(label, 50.5, None, None, c) for c in (0.9, 0.8, 0.7)]  # 0.5% off
    wrong = [Outcome(label, 80.0, None, None, c) for c in (0.6, 0.75)]  # 30% off
    middle = [Outcome(label, 53.0, None, None, 0.1)]  # 3% off: neither, left out
    result = confidence_auc(right + wrong + middle)
    assert (result["right"], result["wrong"]) == (3, 2)
    assert result["auc"] == pytest.approx(5 / 6)  # 0.7 loses to 0.75 only
    assert confidence_auc(right)["auc"] is None
