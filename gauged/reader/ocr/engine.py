"""Text detection and recognition with the PP-OCR ONNX models that ship inside an OCR wheel.

The models are the PaddleOCR networks packaged by RapidOCR: a DB text detector (a per-pixel text
probability map) and an SVTR/CRNN recogniser (per-column character probabilities decoded by CTC).
Only the ``.onnx`` files are used, read from the installed package's folder *without importing the
package* (its ``__init__`` pulls in its own logging, YAML and polygon libraries, and the RapidOCR 3
package can download models). So nothing here reads the network, and the wrapper's dependencies are
onnxruntime, OpenCV and numpy.

The recogniser's alphabet is PaddleOCR's Chinese+English dictionary (6,623 symbols for PP-OCRv4);
gauges print digits, Latin letters and a few symbols, so CTC decoding is restricted to those
(:data:`TEXT_CHARS`), and a second decoding restricted to :data:`NUMBER_CHARS` gives the best
numeric reading of the same columns. Restricting the alphabet removes confusions with look-alike
CJK glyphs at no cost.

References: Liao et al., "Real-time Scene Text Detection with Differentiable Binarization", AAAI
2020 (post-processing: threshold, minimum-area rectangle, unclip by ``area * ratio / perimeter``);
Graves et al., "Connectionist Temporal Classification", ICML 2006 (greedy decoding, and the
forward algorithm that scores a given string: :func:`ctc_log_likelihood`).
"""

from __future__ import annotations

import hashlib
import importlib.util
import json
import logging
import math
import threading
from collections import OrderedDict
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

import cv2
import numpy as np

from gauged.reader.ocr.number_net import NumberNet
from gauged.reader.ocr.text import (
    Recognition,
    TextQuad,
    ctc_greedy,
    ctc_log_likelihood,
    db_boxes,
)
from gauged.types import StageFailure

log = logging.getLogger(__name__)

# Model files inside each supported wheel, best first (docs/ocr.md has the measurements). Both are
# installed with ``pip install --no-deps``: only the .onnx files are used.
MODEL_SETS: dict[str, tuple[str, str]] = {
    "rapidocr": ("models/PP-OCRv6_det_small.onnx", "models/PP-OCRv6_rec_small.onnx"),  # rapidocr==3.10.0
    "rapidocr_onnxruntime": ("models/ch_PP-OCRv4_det_infer.onnx", "models/ch_PP-OCRv4_rec_infer.onnx"),  # 1.4.4
}
DEFAULT_MODEL_PACKAGE = "auto"  # the first of MODEL_SETS that is installed

TEXT_CHARS = frozenset(
    "0123456789abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
    ".,-+/%()°℃℉²−—~:x×* "
)
NUMBER_CHARS = frozenset("0123456789.,-−")

REC_HEIGHT = 48
REC_MIN_WIDTH = 128  # PaddleOCR pads to 48 x 320; 128 reads as well on gauge text and is 2-3x faster
REC_BATCH = 8
REC_MEMO = 1024  # line images remembered per dial: a dial's passes read some tens (30 renders: 524 in all)
DET_MEMO = 16  # images whose text detection is remembered per dial (the second look detects the first pass's ring again)


class OcrUnavailable(RuntimeError):
    """The OCR models are not installed (an installation error, not an algorithmic failure)."""


def find_model_files(package: str = DEFAULT_MODEL_PACKAGE) -> tuple[Path, Path]:
    """Paths of the (detector, recogniser) ONNX files shipped in ``package``'s wheel (``"auto"``:
    the first installed of :data:`MODEL_SETS`).

    The package is located with :func:`importlib.util.find_spec` and never imported. Raises
    :class:`OcrUnavailable` when the package or its model files are missing.
    """
    if package == "auto":
        for name in MODEL_SETS:
            try:
                return find_model_files(name)
            except OcrUnavailable:
                continue
        raise OcrUnavailable(f"no OCR model package installed (one of {', '.join(MODEL_SETS)})")
    if package not in MODEL_SETS:
        raise ValueError(f"unknown OCR model package {package!r}; known: {sorted(MODEL_SETS)} or 'auto'")
    spec = importlib.util.find_spec(package)
    if spec is None or not spec.submodule_search_locations:
        raise OcrUnavailable(f"OCR package {package!r} is not installed")
    root = Path(next(iter(spec.submodule_search_locations)))
    det, rec = (root / p for p in MODEL_SETS[package])
    for path in (det, rec):
        if not path.is_file():
            raise OcrUnavailable(f"OCR model file missing: {path}")
    return det, rec


def _session(path: Path, threads: int):
    import onnxruntime as ort

    from gauged.reader.onnx_model import session_options

    return ort.InferenceSession(str(path), sess_options=session_options(threads), providers=["CPUExecutionProvider"])


def file_sha256(path: Path) -> str:
    """Hex SHA-256 of a file: how an int8 detector names the float file it was made from."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def _int8_session(int8_path: Path, float_path: Path, threads: int):
    """A session of the int8 detector when ``int8_path`` was made from ``float_path``; else None,
    with a warning naming the reason (the caller runs the float detector)."""
    if not int8_path.is_file():
        log.warning("int8 OCR detector %s is missing; running the float detector", int8_path)
        return None
    session = _session(int8_path, threads)
    made_from = json.loads(session.get_modelmeta().custom_metadata_map.get("gauged", "{}")).get("source_sha256")
    if made_from != file_sha256(float_path):
        log.warning("int8 OCR detector %s was made from another file than %s; running the float detector",
                    int8_path, float_path)
        return None
    return session


def _normalise(image_bgr: np.ndarray) -> np.ndarray:
    """uint8 (H, W, 3) BGR -> float32 (3, H, W) in [-1, 1], the PP-OCR input convention."""
    return (image_bgr.astype(np.float32) * (2.0 / 255.0) - 1.0).transpose(2, 0, 1)


class OcrEngine:
    """The detector and recogniser sessions, created once and reused. The daemon's camera threads
    share one engine: onnxruntime sessions may be run from several threads, and the memo below is
    kept per thread.

    ``threads`` is onnxruntime's intra-op thread count. ``package`` picks the model set
    (:data:`MODEL_SETS`). ``int8_detector`` is an int8 copy of the wheel's text detector
    (``gauged.training.quantize_ocr``); it replaces the float detector when it was made from that
    very file (the SHA-256 in its metadata), else the float one runs and a warning says why.

    ``memo`` is how many line images :meth:`recognize` remembers with their readings until
    :meth:`forget` (least recently used dropped first; 0 turns it off). The reader's passes over one
    dial read some lines twice: the quick pass's ink at a hint, then the full pass's same ink, or a
    box again in its first orientation. On 30 renders 85 of 524 recognitions were such exact
    repeats. A line read before is answered from the memo, so its reading does not depend on which
    batch it would have been padded with. The reader forgets at every dial, so a frame never
    reuses another frame's reading. Each thread has its own memo: one camera's dial does not empty
    another's in the middle of its passes. :meth:`detect` remembers the text regions of up to
    :data:`DET_MEMO` images the same way: the reader's second look at a refused dial detects the
    first pass's ring again.
    """

    def __init__(self, threads: int = 2, package: str = DEFAULT_MODEL_PACKAGE,
                 int8_detector: Path | None = None, memo: int = REC_MEMO, number_net: NumberNet | None = None) -> None:
        if threads < 1:
            raise ValueError("threads must be >= 1")
        det_path, rec_path = find_model_files(package)
        self.package = package
        self.threads = threads
        self._det = _int8_session(Path(int8_detector), det_path, threads) if int8_detector is not None else None
        if self._det is None:
            self._det = _session(det_path, threads)
        else:
            det_path = Path(int8_detector)
        self.model_files = (det_path, rec_path)
        self._rec = _session(rec_path, threads)
        meta = self._rec.get_modelmeta().custom_metadata_map
        if "character" not in meta:
            raise OcrUnavailable(f"recogniser {rec_path} has no embedded character list")
        # CTC classes: 0 = blank, 1..n = dictionary, n + 1 = space (PaddleOCR's layout).
        self._chars = ["", *meta["character"].splitlines(), " "]
        self._text_idx = self._class_subset(TEXT_CHARS)
        self._digit_idx = self._class_subset(NUMBER_CHARS)
        self.digit_chars = tuple(self._chars[i] for i in self._digit_idx[1:])
        self._digit_label = {c: k for k, c in enumerate(self.digit_chars, start=1)}
        self._minus_fold = ((self._digit_label["-"], self._digit_label["−"])
                            if "-" in self._digit_label and "−" in self._digit_label else None)
        self.memo_size = memo
        self.number_net = number_net
        self._local = threading.local()

    def _class_subset(self, chars: frozenset[str]) -> np.ndarray:
        return np.array([0] + [i for i, c in enumerate(self._chars) if i and c in chars], dtype=np.int64)

    # -- detection ---------------------------------------------------------------------------
    def detect(
        self,
        image_bgr: np.ndarray,
        max_side: int = 640,
        thresh: float = 0.3,
        box_thresh: float = 0.5,
        unclip_ratio: float = 1.6,
    ) -> list[TextQuad]:
        """Text regions in a (H, W, 3) uint8 BGR image, scaled so its longer side is ``max_side``
        (rounded to a multiple of 32) for the network; quads are in the input image's pixels."""
        key = (_line_key(image_bgr), max_side, thresh, box_thresh, unclip_ratio)
        found = self._detections.get(key)
        if found is None:
            found = self._detections[key] = self._run_detector(image_bgr, max_side, thresh, box_thresh, unclip_ratio)
            while len(self._detections) > DET_MEMO:
                self._detections.pop(next(iter(self._detections)))
        return list(found)

    def _run_detector(self, image_bgr: np.ndarray, max_side: int, thresh: float, box_thresh: float,
                      unclip_ratio: float) -> list[TextQuad]:
        h, w = image_bgr.shape[:2]
        scale = max_side / max(h, w)
        nh, nw = max(32, round(h * scale / 32) * 32), max(32, round(w * scale / 32) * 32)
        inp = cv2.resize(image_bgr, (nw, nh), interpolation=cv2.INTER_AREA if scale < 1 else cv2.INTER_LINEAR)
        prob = self._det.run(None, {self._det.get_inputs()[0].name: _normalise(inp)[None]})[0][0, 0]
        return db_boxes(prob, (w / nw, h / nh), thresh, box_thresh, unclip_ratio)

    # -- recognition -------------------------------------------------------------------------
    @property
    def _memo(self) -> OrderedDict[tuple, Recognition]:
        """This thread's memo of :meth:`recognize`."""
        memo = getattr(self._local, "memo", None)
        if memo is None:
            memo = self._local.memo = OrderedDict()
        return memo

    @property
    def _detections(self) -> dict[tuple, list[TextQuad]]:
        """This thread's memo of :meth:`detect`."""
        memo = getattr(self._local, "detections", None)
        if memo is None:
            memo = self._local.detections = {}
        return memo

    def forget(self) -> None:
        """Empty this thread's memos of :meth:`recognize` and :meth:`detect` (the reader does at every dial)."""
        self._memo.clear()
        self._detections.clear()

    def recognize(self, lines: Sequence[np.ndarray]) -> list[Recognition]:
        """Read each (h, w, 3) uint8 BGR line image (text left to right, upright), each distinct
        line once: a line in the memo or earlier in ``lines`` is not run through the network again.
        Inside :meth:`reading_numbers_again`, the number net reads the lines too (its readings are
        not remembered: the memo holds PP-OCR's, which the retry reuses)."""
        memo = self._memo
        keys = [_line_key(line) for line in lines]
        fresh: dict[tuple, int] = {}  # lines not in the memo: key -> index of the first such line
        for i, key in enumerate(keys):
            if key not in memo and key not in fresh:
                fresh[key] = i
        read = dict(zip(fresh, self.run_recogniser([lines[i] for i in fresh.values()]), strict=True))
        out = []
        for key in keys:
            if key in read:
                out.append(read[key])
            else:
                out.append(memo[key])
                memo.move_to_end(key)
        if self.memo_size > 0:
            memo.update(read)
            while len(memo) > self.memo_size:
                memo.popitem(last=False)
        return self._numbers_read_again(lines, out) if self.numbers_again else out

    def run_recogniser(self, lines: Sequence[np.ndarray]) -> list[Recognition]:
        """The recogniser network on every line, in batches of lines of similar aspect (no memo)."""
        out: list[Recognition | None] = [None] * len(lines)
        order = sorted(range(len(lines)), key=lambda i: lines[i].shape[1] / max(1, lines[i].shape[0]))
        for start in range(0, len(order), REC_BATCH):
            idx = order[start : start + REC_BATCH]
            widths = [max(1, math.ceil(REC_HEIGHT * lines[i].shape[1] / max(1, lines[i].shape[0]))) for i in idx]
            batch_w = max(REC_MIN_WIDTH, *widths)
            batch = np.zeros((len(idx), 3, REC_HEIGHT, batch_w), np.float32)
            for k, (i, rw) in enumerate(zip(idx, widths)):
                line = cv2.resize(lines[i], (rw, REC_HEIGHT), interpolation=cv2.INTER_LINEAR)
                batch[k, :, :, :rw] = _normalise(line)
            probs = self._rec.run(None, {self._rec.get_inputs()[0].name: batch})[0]
            for k, (i, rw) in enumerate(zip(idx, widths)):
                text, score = ctc_greedy(probs[k], self._text_idx, self._chars)
                digits, dscore = ctc_greedy(probs[k], self._digit_idx, self._chars)
                # The columns of the line itself (the rest of the batch's width is padding).
                columns = max(1, math.ceil(probs.shape[1] * rw / batch_w))
                sub = probs[k, :columns][:, self._digit_idx].astype(np.float64)
                if self._minus_fold is not None:  # "−" is a minus sign too: its probability counts for "-"
                    sub[:, self._minus_fold[0]] += sub[:, self._minus_fold[1]]
                    sub[:, self._minus_fold[1]] = 0.0
                logp = np.log(np.clip(sub / np.maximum(sub.sum(axis=1, keepdims=True), 1e-12), 1e-9, 1.0))
                out[i] = Recognition(text.strip(), score, digits, dscore, logp.astype(np.float32))
        return [r for r in out if r is not None]

    @property
    def numbers_again(self) -> bool:
        """Whether this thread's recognitions take the number net's numbers (:meth:`reading_numbers_again`)."""
        return getattr(self._local, "numbers_again", False)

    @contextmanager
    def reading_numbers_again(self) -> Iterator[None]:
        """Within the block, this thread's lines that PP-OCR reads digits in are read by the number net
        too (:meth:`_numbers_read_again`)."""
        if self.number_net is None:
            raise RuntimeError("this engine has no number net")
        before = self.numbers_again
        self._local.numbers_again = True
        try:
            yield
        finally:
            self._local.numbers_again = before

    def _numbers_read_again(self, lines: Sequence[np.ndarray], read: list[Recognition]) -> list[Recognition]:
        """Each line PP-OCR read digits in, read by the number net too; where the net reads a number,
        its string becomes the line's digits (and its text, when that held a digit). The scores and
        ``digit_logp`` stay PP-OCR's."""
        from gauged.reader.ocr.numbers import parse_number  # numbers imports the engine's text types

        out = []
        for rec, net_text in zip(read, self.number_net.read(lines), strict=True):
            if rec.digits and net_text and net_text != rec.digits and not isinstance(parse_number(net_text), StageFailure):
                text = net_text if any(c.isdigit() for c in rec.text) else rec.text
                rec = Recognition(text, rec.score, net_text, rec.digits_score, rec.digit_logp)
            out.append(rec)
        return out

    def log_likelihood(self, recognition: Recognition, text: str) -> float:
        """log P(``text`` | the line) under the recogniser restricted to :data:`NUMBER_CHARS`, summed
        over every CTC alignment; ``-inf`` for a character outside that set or no network output.
        The two minus signs are one character here: "−" is scored as "-"."""
        labels = [self._digit_label.get("-" if c == "−" else c) for c in text]
        if recognition.digit_logp is None or any(label is None for label in labels):
            return -math.inf
        return ctc_log_likelihood(recognition.digit_logp, labels)


def _line_key(line: np.ndarray) -> tuple:
    """A line image's identity for the memo: its shape and a digest of its pixels."""
    return (line.shape, hashlib.blake2b(np.ascontiguousarray(line).tobytes(), digest_size=16).digest())


