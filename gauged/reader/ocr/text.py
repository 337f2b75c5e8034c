"""Text on a dial as the engine gives it (quads, recognitions, boxes), and the decoding of the PP-OCR outputs:
CTC for the recogniser, DB boxes for the detector."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np


@dataclass(frozen=True, slots=True)
class TextQuad:
    """A detected text region: ``quad`` (4, 2) float32 corners in pixel (x, y), clockwise from the
    top-left as the detector orders them, and the detector's mean text probability inside it."""

    quad: np.ndarray
    score: float


@dataclass(frozen=True, slots=True)
class Recognition:
    """The recogniser's reading of one line image.

    ``text``/``score`` decode with :data:`TEXT_CHARS`; ``digits``/``digits_score`` decode the same
    network output restricted to :data:`NUMBER_CHARS`. Scores are the mean probability of the kept
    characters (0 for an empty string). ``digit_logp`` (T, K) is that restricted output as
    log-probabilities over the line's own columns (class 0 the CTC blank, then
    :attr:`OcrEngine.digit_chars`), for scoring strings other than the best one
    (:meth:`OcrEngine.log_likelihood`); None where a reading was not made by the network.
    """

    text: str
    score: float
    digits: str
    digits_score: float
    digit_logp: np.ndarray | None = None


@dataclass(frozen=True, slots=True)
class TextBox:
    """One recognised text: ``text`` and its recogniser ``score``, ``quad`` (4, 2) float corners in
    the pixel coordinates of the image given to the reader (``quad[0] -> quad[1]`` is the reading
    direction, ``quad[0]`` the text's top-left), and the digits-only decoding of the same line."""

    text: str
    score: float
    quad: np.ndarray
    digits: str = ""
    digits_score: float = 0.0
    net_minus: bool = False  # the nets' evidence leans to a minus before it in its line widened left (minus_sign)

    @property
    def center(self) -> tuple[float, float]:
        c = np.asarray(self.quad, float).mean(axis=0)
        return (float(c[0]), float(c[1]))

    @property
    def box(self) -> tuple[float, float, float, float]:
        """Axis-aligned ``(x0, y0, x1, y1)`` around the quad."""
        q = np.asarray(self.quad, float)
        return (float(q[:, 0].min()), float(q[:, 1].min()), float(q[:, 0].max()), float(q[:, 1].max()))

    @property
    def height(self) -> float:
        """Text height: :func:`quad_height` of the quad."""
        return quad_height(self.quad)

    @property
    def width(self) -> float:
        """Text length along the reading direction."""
        q = np.asarray(self.quad, float)
        return float(0.5 * (np.linalg.norm(q[1] - q[0]) + np.linalg.norm(q[2] - q[3])))


def quad_height(quad: np.ndarray) -> float:
    """Height of a text quad (4, 2) ordered as :class:`TextBox` quads are: the mean length of its two
    sides across the reading direction."""
    q = np.asarray(quad, float)
    return float(0.5 * (np.linalg.norm(q[3] - q[0]) + np.linalg.norm(q[2] - q[1])))


def ctc_greedy(probs: np.ndarray, classes: np.ndarray, chars: Sequence[str]) -> tuple[str, float]:
    """Greedy CTC decoding of ``probs`` (T, C) restricted to the class indices ``classes`` (index 0
    of ``classes`` must be the blank): best class per column, repeats merged, blanks dropped.
    Returns the text and the mean probability of its characters (0.0 when empty)."""
    sub = probs[:, classes]
    best = sub.argmax(axis=1)
    keep = best != 0
    keep[1:] &= best[1:] != best[:-1]
    if not keep.any():
        return "", 0.0
    cls = classes[best[keep]]
    return "".join(chars[c] for c in cls), float(sub[np.nonzero(keep)[0], best[keep]].mean())


def ctc_log_likelihood(logp: np.ndarray, labels: Sequence[int]) -> float:
    """log P(``labels`` | ``logp``) by the CTC forward algorithm (Graves et al. 2006, Sec. 4.1).

    ``logp`` (T, K) are per-column log-probabilities with class 0 the blank; ``labels`` the string's
    class indices (1..K-1). ``-inf`` when the string needs more columns than there are.

    >>> lp = np.log(np.array([[0.1, 0.9, 0.0], [0.9, 0.1, 0.0], [0.1, 0.0, 0.9]]) + 1e-12)
    >>> round(math.exp(ctc_log_likelihood(lp, [1, 2])), 3)  # "ab" as a-a-b, a-blank-b or blank-a-b
    0.819
    """
    if not labels:
        return float(logp[:, 0].sum())
    ext = [0] * (2 * len(labels) + 1)  # blank, l1, blank, l2, ..., blank
    ext[1::2] = labels
    # a label may be reached from two states back unless it repeats the label there
    skip = [i >= 3 and i % 2 == 1 and ext[i] != ext[i - 2] for i in range(len(ext))]
    # The recursion in probabilities, rescaled at every column (Graves et al.'s own trick): the scale
    # factors' logs add up to the log-likelihood, with no underflow. Plain Python: on these few
    # states it is 3-4x faster than numpy's per-call overhead.
    columns = np.exp(logp[:, ext].astype(np.float64)).tolist()
    alpha = [0.0] * len(ext)
    alpha[0], alpha[1] = columns[0][0], columns[0][1]
    total = 0.0
    for probs in columns[1:]:
        norm = sum(alpha)
        if norm <= 0.0:
            return -math.inf
        total += math.log(norm)
        before = after_one = 0.0  # alpha two states back, one state back
        step = []
        for state, (a, p) in enumerate(zip(alpha, probs)):
            step.append((a + after_one + (before if skip[state] else 0.0)) * p / norm)
            before, after_one = after_one, a
        alpha = step
    end = alpha[-1] + alpha[-2]
    return total + math.log(end) if end > 0.0 else -math.inf


def db_boxes(
    prob: np.ndarray,
    to_input: tuple[float, float],
    thresh: float = 0.3,
    box_thresh: float = 0.5,
    unclip_ratio: float = 1.6,
    min_side: float = 3.0,
) -> list[TextQuad]:
    """DB post-processing of a (h, w) float text-probability map into rotated quads.

    Each connected region of ``prob > thresh`` becomes its minimum-area rectangle; rectangles whose
    mean probability is below ``box_thresh`` are dropped, the rest grown on every side by
    ``area * unclip_ratio / perimeter`` (the DB paper's unclip; for a rectangle the exact offset
    polygon's bounding rectangle) and scaled by ``to_input = (sx, sy)`` to input pixels.
    """
    mask = cv2.dilate((prob > thresh).astype(np.uint8), np.ones((2, 2), np.uint8))
    contours, _ = cv2.findContours(mask, cv2.RETR_LIST, cv2.CHAIN_APPROX_SIMPLE)
    sx, sy = to_input
    out = []
    for contour in contours[:1000]:
        (cx, cy), (rw, rh), angle = cv2.minAreaRect(contour)
        if min(rw, rh) < min_side:
            continue
        pts = cv2.boxPoints(((cx, cy), (rw, rh), angle))
        score = _mean_in_polygon(prob, pts)
        if score < box_thresh:
            continue
        d = rw * rh * unclip_ratio / (2.0 * (rw + rh))
        if min(rw, rh) + 2 * d < min_side + 2:
            continue
        pts = cv2.boxPoints(((cx, cy), (rw + 2 * d, rh + 2 * d), angle))
        pts = order_quad(pts) * np.array([sx, sy], np.float32)
        out.append(TextQuad(pts.astype(np.float32), float(score)))
    return out


def _mean_in_polygon(prob: np.ndarray, pts: np.ndarray) -> float:
    h, w = prob.shape
    x0, y0 = np.clip(np.floor(pts.min(0)).astype(int), 0, [w - 1, h - 1])
    x1, y1 = np.clip(np.ceil(pts.max(0)).astype(int), 0, [w - 1, h - 1])
    m = np.zeros((y1 - y0 + 1, x1 - x0 + 1), np.uint8)
    cv2.fillPoly(m, [np.round(pts - [x0, y0]).astype(np.int32)], 1)
    return float(cv2.mean(prob[y0 : y1 + 1, x0 : x1 + 1], m)[0])


def order_quad(pts: np.ndarray) -> np.ndarray:
    """Order 4 corners as top-left, top-right, bottom-right, bottom-left (y down), reading the
    quad's longer-or-equal horizontal-ish side as its top: the ordering the recogniser crop uses."""
    pts = np.asarray(pts, np.float32)
    xs = pts[np.argsort(pts[:, 0], kind="stable")]
    left, right = xs[:2], xs[2:]
    tl, bl = left[np.argsort(left[:, 1], kind="stable")]
    tr, br = right[np.argsort(right[:, 1], kind="stable")]
    return np.stack([tl, tr, br, bl])


def crop_quad(image_bgr: np.ndarray, quad: np.ndarray) -> np.ndarray:
    """The quad's content warped to an axis-aligned (h, w, 3) image, ``quad[0]`` -> top-left."""
    quad = np.asarray(quad, np.float32)
    w = int(round(max(np.linalg.norm(quad[0] - quad[1]), np.linalg.norm(quad[3] - quad[2]))))
    h = int(round(max(np.linalg.norm(quad[0] - quad[3]), np.linalg.norm(quad[1] - quad[2]))))
    w, h = max(w, 2), max(h, 2)
    dst = np.array([[0, 0], [w, 0], [w, h], [0, h]], np.float32)
    m = cv2.getPerspectiveTransform(quad, dst)
    return cv2.warpPerspective(image_bgr, m, (w, h), flags=cv2.INTER_CUBIC, borderMode=cv2.BORDER_REPLICATE)
