"""Find the gauges of one camera over several frames and decide each one's box and scale by vote.

Each frame is located and read as the daemon reads a camera with unconfigured gauges
(:func:`gauged.reader.locate.locate_gauges`, then every located box read with OCR). The sightings of one
gauge on different frames are grouped by the overlap of their *located* boxes (a box read again wider,
:func:`gauged.reader.locate.wider_boxes`, would otherwise look like another gauge); a gauge found on fewer
than half of the frames (a passing glare the detector took for a dial) is left out. A gauge's scale is
the (min, max, direction) most of its frames read, its unit the unit most of those read, its ROI the
median of their boxes. The result is then checked the way the daemon will read it: the ROI with that
scale configured (:meth:`~gauged.reader.pipeline.GaugeReader.read_box`, not located) on every frame.
"""

from __future__ import annotations

import logging
import math
from collections import Counter
from dataclasses import dataclass, field

import numpy as np

from gauged.geometry.boxes import box_iou
from gauged.reader.gauge_read import GaugeRead, KnownScale
from gauged.reader.locate import locate_gauges
from gauged.reader.pipeline import GaugeReader
from gauged.types import Box, Frame, ScaleModel, StageFailure

log = logging.getLogger(__name__)

MIN_IOU = 0.3  # boxes of one gauge on two frames overlap at least this much (as in daemon/association)
SEEN_SHARE = 0.5  # a box found on fewer of the frames is not a gauge worth writing
CHECK_SHARE = 0.5  # a config whose ROI and scale read fewer of the frames gets a TODO

Roi = tuple[int, int, int, int]


@dataclass(frozen=True, order=True)
class ScaleRead:
    """A scale as the config writes it, and which way it rises (+1 clockwise, -1 counter-clockwise)."""

    min: float
    max: float
    direction: int = 1
    unit: str | None = None

    @classmethod
    def of(cls, scale: ScaleModel) -> ScaleRead:
        return cls(_round(scale.min_value), _round(scale.max_value), 1 if scale.slope >= 0 else -1, scale.unit)

    @property
    def key(self) -> tuple[float, float, int]:
        return (self.min, self.max, self.direction)

    @property
    def span(self) -> float:
        return self.max - self.min

    def describe(self) -> str:
        way = "clockwise" if self.direction > 0 else "counter-clockwise"
        return f"{self.min:g}..{self.max:g} {self.unit or '(no unit)'} {way}"


@dataclass(frozen=True)
class Sighting:
    """One gauge located on one frame: the located box and the read of it (whose ``box`` may be wider)."""

    frame: int
    box: Box
    read: GaugeRead


@dataclass
class GaugeFinding:
    """One gauge found on a camera: its sightings, and what commissioning decided of them."""

    camera: str
    frames: int  # frames surveyed
    sightings: list[Sighting] = field(default_factory=list)
    id: str = ""
    roi: Roi | None = None
    scale: ScaleRead | None = None
    votes: Counter = field(default_factory=Counter)  # ScaleRead.key -> frames
    other_scale: ScaleRead | None = None  # a dual-scale dial's inner scale
    checked: int = 0  # frames read with the written ROI and scale
    check_failure: str | None = None  # the commonest refusal of that check
    todo: str | None = None
    shown: Sighting | None = None  # the sighting the contact sheet shows

    @property
    def seen(self) -> int:
        return len({s.frame for s in self.sightings})

    @property
    def box(self) -> Box:
        return _median_box([s.box for s in self.sightings])

    @property
    def value(self) -> float | None:
        read = None if self.shown is None else self.shown.read
        return None if read is None or read.value is None else read.value.value


def _round(value: float) -> float:
    return float(f"{value:.6g}")


def _median_box(boxes: list[Box]) -> Box:
    return tuple(float(v) for v in np.median(np.asarray(boxes, float), axis=0))  # type: ignore[return-value]


def _failure_text(failure: StageFailure | None) -> str:
    return "no reason given" if failure is None else f"{failure.stage}/{failure.reason}: {failure.detail}"


def _commonest_failure(reads: list[GaugeRead]) -> str:
    failures = Counter((r.failure.stage, r.failure.reason) for r in reads if r.failure is not None)
    if not failures:
        return "no reason given"
    (stage, reason), n = failures.most_common(1)[0]
    detail = next(r.failure.detail for r in reads
                  if r.failure is not None and (r.failure.stage, r.failure.reason) == (stage, reason))
    return f"{stage}/{reason} on {n} of {len(reads)} frame(s): {detail}"


def locate_and_read(reader: GaugeReader, image: np.ndarray) -> list[tuple[Box, GaugeRead]] | StageFailure:
    """Every gauge of (H, W, 3) uint8 BGR ``image``, located and read as
    :meth:`~gauged.reader.pipeline.GaugeReader.read_image` does, with the located box of each read
    (which ``read_image`` does not return: a read's own box is wider when the located one held no ring)."""
    located, failure = locate_gauges(reader.detector, image)
    reads = [(d.box, reader.read_box(image, d.box, d.score, located=True)) for d in located]
    if failure is not None and reads[0][1].failure is not None and reads[0][1].arc is None:
        return failure  # the detector found nothing and the image read whole is no dial either
    return reads


def group_sightings(frames_sightings: list[list[Sighting]]) -> list[list[Sighting]]:
    """The sightings of each frame grouped into gauges by located-box overlap (IoU >= :data:`MIN_IOU`,
    greedy from the best pair), at most one sighting per frame in a group."""
    groups: list[list[Sighting]] = []
    for sightings in frames_sightings:
        boxes = [_median_box([s.box for s in g]) for g in groups]
        pairs = sorted(((box_iou(boxes[g], s.box), g, k) for g in range(len(groups)) for k, s in enumerate(sightings)),
                       reverse=True)
        taken_groups, taken = set(), set()
        for iou, g, k in pairs:
            if iou < MIN_IOU:
                break
            if g in taken_groups or k in taken:
                continue
            groups[g].append(sightings[k])
            taken_groups.add(g)
            taken.add(k)
        groups.extend([s] for k, s in enumerate(sightings) if k not in taken)
    return groups


def roi_of(box: Box, width: int, height: int) -> Roi:
    """A box as an integer ROI (rounded outwards, inside the image)."""
    return (max(0, math.floor(box[0])), max(0, math.floor(box[1])), min(width, math.ceil(box[2])),
            min(height, math.ceil(box[3])))


def decide(finding: GaugeFinding) -> list[Sighting]:
    """The scale most frames read (a vote; a tie or a scale read once of several frames is a TODO), its
    unit, the dial's other scale and the sighting the contact sheet shows. Returns the sightings that
    read the chosen scale (all of them when none was chosen)."""
    reads = [s.read for s in finding.sightings]
    scaled = [s for s in finding.sightings if s.read.scale is not None]
    finding.votes = Counter(ScaleRead.of(s.read.scale).key for s in scaled)
    chosen = finding.sightings
    if not finding.votes:
        finding.todo = f"no scale read: {_commonest_failure(reads)}"
    else:
        ranked = finding.votes.most_common()
        (key, n), runner_up = ranked[0], ranked[1][1] if len(ranked) > 1 else 0
        if n == runner_up:
            tied = " and ".join(f"{k[0]:.4g}..{k[1]:.4g}" for k, c in ranked if c == n)
            finding.todo = f"the frames disagree on the scale ({tied}, {n} frame(s) each): read it off the dial"
        elif n < 2 <= finding.frames:
            failed = [r for r in reads if r.scale is None]
            why = f"; the others: {_commonest_failure(failed)}" if failed else ""
            finding.todo = (f"a scale ({ranked[0][0][0]:.4g}..{ranked[0][0][1]:.4g}) was read on only one of "
                            f"{finding.frames} frames{why}")
        else:
            chosen = [s for s in scaled if ScaleRead.of(s.read.scale).key == key]
            units = Counter(s.read.scale.unit for s in chosen if s.read.scale.unit)
            finding.scale = ScaleRead(*key, units.most_common(1)[0][0] if units else None)
            others = Counter(ScaleRead.of(s.read.scales[1]) for s in chosen if len(s.read.scales) > 1)
            finding.other_scale = others.most_common(1)[0][0] if others else None
    finding.shown = max(chosen, key=lambda s: (s.read.value is not None, s.read.scale is not None,
                                               s.read.value.confidence if s.read.value is not None else 0.0))
    return chosen


def _check_roi(reader: GaugeReader, finding: GaugeFinding, roi: Roi, frames: list[Frame]) -> tuple[int, str | None]:
    """How many of ``frames`` the daemon reads in ``roi`` (with the voted scale configured, either
    direction; with none, by OCR), and the commonest refusal."""
    scale = finding.scale
    known = KnownScale(scale.min, scale.max, scale.unit, scale.direction) if scale is not None else None
    primary = scale.unit if scale is not None and finding.other_scale is not None else None
    reads = [reader.read_box(frame.image, tuple(float(v) for v in roi), 1.0, known, primary, located=False)
             for frame in frames]
    bad = [r for r in reads if r.value is None]
    return len(reads) - len(bad), (_commonest_failure(bad) if bad else None)


def place_and_check(reader: GaugeReader, finding: GaugeFinding, chosen: list[Sighting], frames: list[Frame]) -> None:
    """The ROI: the median located box of the ``chosen`` sightings, or the median of the boxes they were
    read in when those were wider (a detector that boxed only part of the dial) and read more frames.
    Either is read on every frame as the daemon will; fewer than :data:`CHECK_SHARE` read is a TODO."""
    height, width = frames[0].image.shape[:2]
    candidates = [roi_of(_median_box([s.box for s in chosen]), width, height)]
    wider = roi_of(_median_box([s.read.box for s in chosen]), width, height)
    if finding.scale is not None and wider != candidates[0]:
        candidates.append(wider)
    best = None
    for roi in candidates:
        checked, failure = _check_roi(reader, finding, roi, frames)
        if best is None or checked > best[1]:
            best = (roi, checked, failure)
    finding.roi, finding.checked, finding.check_failure = best
    if finding.todo is None and finding.checked < CHECK_SHARE * len(frames):
        finding.todo = (f"with this roi and scale only {finding.checked} of {len(frames)} frames read: "
                        f"{finding.check_failure}")


def _reading_order(box: Roi) -> tuple[int, float]:
    """Rows top to bottom (a row a gauge's height), left to right in a row (as daemon/association)."""
    height = max(1.0, box[3] - box[1])
    return (round(((box[1] + box[3]) / 2) / height), (box[0] + box[2]) / 2)


def survey_camera(reader: GaugeReader, camera: str, frames: list[Frame]
                  ) -> tuple[list[GaugeFinding], list[GaugeFinding]]:
    """The gauges found on ``frames`` of ``camera`` in reading order, with ids ``<camera>-gauge-<n>``,
    and the boxes left out (found on fewer than :data:`SEEN_SHARE` of the frames)."""
    frames_sightings: list[list[Sighting]] = []
    for index, frame in enumerate(frames):
        reads = locate_and_read(reader, frame.image)
        if isinstance(reads, StageFailure):
            log.info("camera %s: frame %d/%d: no gauge (%s)", camera, index + 1, len(frames), _failure_text(reads))
            reads = []
        else:
            log.info("camera %s: frame %d/%d: %d gauge(s), %d with a scale", camera, index + 1, len(frames),
                     len(reads), sum(r.scale is not None for _, r in reads))
        frames_sightings.append([Sighting(index, box, read) for box, read in reads])
    kept, dropped = [], []
    for group in group_sightings(frames_sightings):
        finding = GaugeFinding(camera, len(frames), group)
        (kept if finding.seen >= SEEN_SHARE * len(frames) else dropped).append(finding)
    for finding in kept:
        place_and_check(reader, finding, decide(finding), frames)
    kept.sort(key=lambda f: _reading_order(f.roi))
    for n, finding in enumerate(kept, 1):
        finding.id = f"{camera}-gauge-{n}"
    return kept, dropped
