"""Which detection is which configured gauge, stable from frame to frame.

Gauges without an ROI are matched to the detector's boxes: first by overlap with the box each gauge
had last time (IoU, greedy from the best pair), then, for gauges seen for the first time, in reading
order (top-to-bottom rows, left to right) against the configuration order. The rule is simple so an
operator can predict it: on a camera with several unboxed gauges, list them in the config in
reading order, or give each an ROI.
"""

from __future__ import annotations

from gauged.geometry.boxes import box_iou
from gauged.types import Box, GaugeDetection

MIN_IOU = 0.3


def _reading_order(detection: GaugeDetection) -> tuple[float, float]:
    x0, y0, x1, y1 = detection.box
    row_height = max(1.0, y1 - y0)
    return (round(((y0 + y1) / 2) / row_height), (x0 + x1) / 2)


def associate(gauges: list[str], previous: dict[str, Box], detections: list[GaugeDetection]
              ) -> dict[str, GaugeDetection]:
    """Assign detections to gauge ids; a gauge with no fitting detection is left out of the result."""
    assigned: dict[str, GaugeDetection] = {}
    free = list(range(len(detections)))
    pairs = sorted(((box_iou(previous[g], detections[d].box), g, d) for g in gauges if g in previous for d in free),
                   reverse=True)
    for iou, gauge, index in pairs:
        if iou < MIN_IOU:
            break
        if gauge in assigned or index not in free:
            continue
        assigned[gauge] = detections[index]
        free.remove(index)
    newcomers = [g for g in gauges if g not in assigned and g not in previous]
    for gauge, index in zip(newcomers, sorted(free, key=lambda i: _reading_order(detections[i]))):
        assigned[gauge] = detections[index]
    return assigned
