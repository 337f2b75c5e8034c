from __future__ import annotations

from gauged.daemon.association import associate
from gauged.types import GaugeDetection


def det(x0: float, y0: float, size: float = 100.0) -> GaugeDetection:
    return GaugeDetection((x0, y0, x0 + size, y0 + size), 0.9)


def test_associate_first_frame_in_reading_order():
    detections = [det(500, 10), det(10, 12), det(10, 300)]
    result = associate(["a", "b", "c"], {}, detections)
    assert result["a"].box[0] == 10 and result["a"].box[1] == 12
    assert result["b"].box[0] == 500
    assert result["c"].box[1] == 300


def test_associate_keeps_identity_when_gauges_move_slightly():
    previous = {"a": (10.0, 10.0, 110.0, 110.0), "b": (500.0, 10.0, 600.0, 110.0)}
    result = associate(["a", "b"], previous, [det(505, 12), det(12, 8)])
    assert result["a"].box[0] == 12 and result["b"].box[0] == 505


def test_associate_leaves_a_lost_gauge_out_rather_than_swapping():
    previous = {"a": (10.0, 10.0, 110.0, 110.0), "b": (500.0, 10.0, 600.0, 110.0)}
    result = associate(["a", "b"], previous, [det(505, 12)])
    assert set(result) == {"b"}
