"""The contact sheet of a commissioning: a PNG the operator checks the written config against.

One section per camera: a title, the camera's first frame with every written ROI boxed and labelled by
its gauge id (green: read; orange: written with a TODO; grey, thin: a box left out), then one tile per
gauge: the read shown (:func:`gauged.reader.annotate.annotate`: scale ring, notches, needle, the numbers
read) with a caption of what the config says (id, scale, unit, direction, frames agreeing, the daemon's
check of the ROI, the value when commissioned, the TODO and its reason).
"""

from __future__ import annotations

import cv2
import numpy as np

from gauged.commissioning.frames import CameraFrames
from gauged.commissioning.survey import GaugeFinding
from gauged.geometry.boxes import box_iou
from gauged.reader.annotate import annotate

WIDTH = 1280  # px of the whole sheet
COLUMNS = 4  # gauge tiles per row
GAP = 10  # px between tiles and around the sheet
TILE = (WIDTH - (COLUMNS + 1) * GAP) // COLUMNS
CAPTION_LINES = 8
LINE_PX = 18
TITLE_PX = 34
MAX_OVERVIEW_PX = 720  # the camera's frame is shown at most this high
MIN_SHOWN_IOU = 0.5  # a read whose box overlaps the ROI less is shown as the ROI, not as its crop

BACKGROUND, INK, GREEN, ORANGE, RED, GREY = (32, 32, 32), (235, 235, 235), (80, 210, 80), (0, 160, 255), (70, 70, 240), (140, 140, 140)
FONT = cv2.FONT_HERSHEY_SIMPLEX

Rect = tuple[int, int, int, int]  # (x0, y0, x1, y1) sheet pixels


def _text(image: np.ndarray, text: str, origin: tuple[int, int], color: tuple[int, int, int], size: float = 0.48,
          backed: bool = False) -> None:
    """Text at ``origin`` (its baseline's left end); ``backed``: on a dark box, for text over a picture.
    (An outline drawn thicker would not do: this OpenCV's font grows wider with the thickness.)"""
    if backed:
        (w, h), base = cv2.getTextSize(text, FONT, size, 1)
        x, y = origin
        cv2.rectangle(image, (x - 2, y - h - 3), (x + w + 2, y + base + 1), (0, 0, 0), -1)
    cv2.putText(image, text, origin, FONT, size, color, 1, cv2.LINE_AA)


def wrap(text: str, width_px: int, size: float = 0.48) -> list[str]:
    """``text`` broken into lines of at most ``width_px`` pixels in the sheet's font (a word longer
    than a line is cut)."""
    lines: list[str] = []
    line = ""
    for word in text.split():
        candidate = f"{line} {word}".strip()
        if cv2.getTextSize(candidate, FONT, size, 1)[0][0] <= width_px:
            line = candidate
            continue
        if line:
            lines.append(line)
        while cv2.getTextSize(word, FONT, size, 1)[0][0] > width_px and len(word) > 1:
            cut = max(1, len(word) * width_px // cv2.getTextSize(word, FONT, size, 1)[0][0])
            lines.append(word[:cut])
            word = word[cut:]
        line = word
    if line:
        lines.append(line)
    return lines


def caption(gauge: GaugeFinding) -> list[tuple[str, tuple[int, int, int]]]:
    """The caption lines of one gauge's tile with their colours."""
    lines = [(f"{gauge.id}  roi {list(gauge.roi)}", INK)]
    if gauge.scale is not None:
        scale = gauge.scale
        lines.append((f"scale {scale.describe()}", GREEN))
        lines.append((f"read on {gauge.votes[scale.key]} of {gauge.frames} frame(s)", INK))
        if gauge.other_scale is not None:
            lines.append((f"also {gauge.other_scale.describe()}", INK))
    else:
        lines.append(("scale: not read", RED))
    checked = GREEN if gauge.checked == gauge.frames else ORANGE if gauge.todo is None else RED
    lines.append((f"daemon's read of roi and scale: "
                  f"{gauge.checked} of {gauge.frames}", checked))
    if gauge.value is not None and gauge.scale is not None:
        unit = gauge.scale.unit if gauge.scale is not None and gauge.scale.unit else ""
        lines.append((f"value when commissioned: {gauge.value:.4g} {unit}".rstrip(), INK))
    notes = []
    if gauge.todo is not None:
        notes.append((f"TODO: {gauge.todo}", RED))
    elif gauge.scale is not None and gauge.scale.unit is None:
        notes.append(("TODO: no unit read: add unit: to the scale", ORANGE))
    for note, color in notes:
        lines.extend((line, color) for line in wrap(note, TILE - 8))
    if len(lines) > CAPTION_LINES:
        lines = lines[:CAPTION_LINES - 1] + [(lines[CAPTION_LINES - 1][0][:-3] + "...", lines[CAPTION_LINES - 1][1])]
    return lines


def gauge_picture(gauge: GaugeFinding, camera: CameraFrames) -> np.ndarray:
    """(TILE, TILE + footer, 3) uint8 BGR: the annotated read shown, or the ROI of its frame when the
    read has no crop or was read in a box much wider than the ROI (the crop would show the wall)."""
    read = gauge.shown.read
    if read.crop is not None and box_iou(read.box, gauge.roi) >= MIN_SHOWN_IOU:
        picture = annotate(read)
    else:
        frame = camera.frames[gauge.shown.frame].image
        x0, y0, x1, y1 = gauge.roi
        picture = frame[y0:y1, x0:x1]
    scale = TILE / picture.shape[1]
    return cv2.resize(picture, (TILE, max(1, round(picture.shape[0] * scale))), interpolation=cv2.INTER_AREA)


def _tile(gauge: GaugeFinding, camera: CameraFrames) -> np.ndarray:
    picture = gauge_picture(gauge, camera)
    tile = np.full((picture.shape[0] + CAPTION_LINES * LINE_PX + 8, TILE, 3), BACKGROUND, np.uint8)
    tile[:picture.shape[0]] = picture
    border = RED if gauge.todo is not None else GREEN
    cv2.rectangle(tile, (0, 0), (TILE - 1, picture.shape[0] - 1), border, 2)
    for i, (line, color) in enumerate(caption(gauge)):
        _text(tile, line, (4, picture.shape[0] + LINE_PX * (i + 1)), color)
    return tile


def _overview(camera: CameraFrames, gauges: list[GaugeFinding], dropped: list[GaugeFinding]) -> np.ndarray:
    frame = camera.frames[0].image
    height, width = frame.shape[:2]
    scale = min((WIDTH - 2 * GAP) / width, MAX_OVERVIEW_PX / height)
    view = cv2.resize(frame, (round(width * scale), round(height * scale)), interpolation=cv2.INTER_AREA)
    for left_out in dropped:
        x0, y0, x1, y1 = (round(v * scale) for v in left_out.box)
        cv2.rectangle(view, (x0, y0), (x1, y1), GREY, 1)
    for gauge in gauges:
        x0, y0, x1, y1 = (round(v * scale) for v in gauge.roi)
        color = ORANGE if gauge.todo is not None else GREEN
        cv2.rectangle(view, (x0, y0), (x1, y1), color, 2)
        _text(view, gauge.id, (x0 + 4, max(16, y0 + 18)), color, 0.55, backed=True)
    return view


def camera_section(camera: CameraFrames, gauges: list[GaugeFinding], dropped: list[GaugeFinding]
                   ) -> tuple[np.ndarray, dict[str, Rect]]:
    """The section of one camera (WIDTH px wide) and where each gauge's tile is in it."""
    parts: list[np.ndarray] = []
    title = np.full((TITLE_PX, WIDTH, 3), BACKGROUND, np.uint8)
    where = camera.source.get("topic") or camera.source.get("key") or ""
    todo = sum(g.todo is not None for g in gauges)
    _text(title, f"camera {camera.camera} ({where}): {len(gauges)} gauge(s) on {len(camera.frames)} frame(s)"
          + (f", {todo} with a TODO" if todo else ""), (GAP, 24), INK, 0.65)
    parts.append(title)
    overview = _overview(camera, gauges, dropped)
    band = np.full((overview.shape[0] + GAP, WIDTH, 3), BACKGROUND, np.uint8)
    left = (WIDTH - overview.shape[1]) // 2
    band[:overview.shape[0], left:left + overview.shape[1]] = overview
    parts.append(band)
    top = sum(p.shape[0] for p in parts)
    tiles: dict[str, Rect] = {}
    for row_start in range(0, len(gauges), COLUMNS):
        row = [_tile(g, camera) for g in gauges[row_start:row_start + COLUMNS]]
        row_px = max(t.shape[0] for t in row)
        band = np.full((row_px + GAP, WIDTH, 3), BACKGROUND, np.uint8)
        for column, (gauge, tile) in enumerate(zip(gauges[row_start:row_start + COLUMNS], row, strict=True)):
            x = GAP + column * (TILE + GAP)
            band[:tile.shape[0], x:x + TILE] = tile
            tiles[gauge.id] = (x, top, x + TILE, top + tile.shape[0])
        parts.append(band)
        top += band.shape[0]
    return np.vstack(parts), tiles


def contact_sheet(cameras: list[CameraFrames], gauges: dict[str, list[GaugeFinding]],
                  dropped: dict[str, list[GaugeFinding]]) -> tuple[np.ndarray, dict[str, Rect]]:
    """(H, :data:`WIDTH`, 3) uint8 BGR sheet of every camera and gauge, and each gauge's tile on it."""
    parts = [np.full((GAP, WIDTH, 3), BACKGROUND, np.uint8)]
    tiles: dict[str, Rect] = {}
    for camera in cameras:
        section, where = camera_section(camera, gauges.get(camera.camera, []), dropped.get(camera.camera, []))
        top = sum(p.shape[0] for p in parts)
        tiles.update({gid: (x0, y0 + top, x1, y1 + top) for gid, (x0, y0, x1, y1) in where.items()})
        parts.append(section)
    return np.vstack(parts), tiles
