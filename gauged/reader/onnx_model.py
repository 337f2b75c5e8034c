"""onnxruntime sessions for the models that ship inside the package (no torch at run time)."""

from __future__ import annotations

import json
from importlib import resources
from pathlib import Path

import numpy as np
import onnxruntime as ort


class ModelNotAvailable(RuntimeError):
    """A model file the reader needs is not in the package (not trained/shipped yet) or is unreadable."""


def packaged_model_path(name: str) -> Path:
    """Path of ``gauged/models/<name>`` inside the installed package."""
    return Path(str(resources.files("gauged.models").joinpath(name)))


def session_options(threads: int) -> ort.SessionOptions:
    """CPU session options shared by every model the reader runs (its own and the OCR's).

    Idle intra-op threads sleep instead of spinning: the pipeline runs four sessions in turn
    (detector, crop model, OCR detector and recogniser), and the threads one session left spinning
    took the cores from the next. The cold read took 256 ms median with spinning, 191 ms without
    (``bench/bench_read.py``, 2 cores).

    Neither the memory arena nor memory patterns are kept: the OCR models take a new input shape
    at nearly every line and dial, and each shape grew the arena and cached a pattern for good. With
    them, four camera threads of cold reads held 935 MB; without, 554 MB, at the same cold-read
    speed (276-280 against 273-285 ms median, run alternately; ``bench/bench_load.py`` for the daemon).
    """
    options = ort.SessionOptions()
    options.intra_op_num_threads = threads
    options.inter_op_num_threads = 1
    options.execution_mode = ort.ExecutionMode.ORT_SEQUENTIAL
    options.graph_optimization_level = ort.GraphOptimizationLevel.ORT_ENABLE_ALL
    options.add_session_config_entry("session.intra_op.allow_spinning", "0")
    options.log_severity_level = 3
    options.enable_cpu_mem_arena = False
    options.enable_mem_pattern = False
    return options


def load_session(path: Path, threads: int, how_to_make: str = "see gauged/models/README.md"
                 ) -> tuple[ort.InferenceSession, dict]:
    """A CPU session of the ONNX file ``path`` and the JSON of its ``gauged`` metadata key ({} when
    it has none); :class:`ModelNotAvailable` names the file when it is missing or unreadable."""
    if not path.is_file():
        raise ModelNotAvailable(f"model file {path} is missing: train and export it ({how_to_make})")
    try:
        session = ort.InferenceSession(str(path), session_options(threads), providers=["CPUExecutionProvider"])
    except Exception as exc:  # onnxruntime raises its own hierarchy for corrupt files
        raise ModelNotAvailable(f"cannot load model {path}: {exc}") from exc
    return session, json.loads(session.get_modelmeta().custom_metadata_map.get("gauged", "{}"))


class OnnxModel:
    """One onnxruntime session, created once, with a fixed NCHW float input and validated calls.

    ``metadata`` holds the JSON written at export (input size, channel names, training figures).
    """

    def __init__(self, path: Path, threads: int = 2):
        self.session, self.metadata = load_session(path, threads)
        (inp,) = self.session.get_inputs()
        self.input_name = inp.name
        self.input_shape = tuple(inp.shape)  # (1, 3, S, S)
        self.path = path

    @property
    def input_size(self) -> int:
        return int(self.input_shape[-1])

    def __call__(self, image_rgb01: np.ndarray) -> np.ndarray:
        """Run on one (S, S, 3) float32 RGB image in [0, 1]; returns the first output without batch axis."""
        expected = (self.input_size, self.input_size, 3)
        if image_rgb01.shape != expected or image_rgb01.dtype != np.float32:
            raise ValueError(f"{self.path.name} expects a float32 array of shape {expected}, got "
                             f"{image_rgb01.dtype} {image_rgb01.shape}")
        batch = np.ascontiguousarray(image_rgb01.transpose(2, 0, 1)[None])
        return self.session.run(None, {self.input_name: batch})[0][0]


def to_model_input(image_bgr: np.ndarray) -> np.ndarray:
    """(H, W, 3) uint8 BGR -> (H, W, 3) float32 RGB in [0, 1], the models' input convention."""
    return image_bgr[:, :, ::-1].astype(np.float32) * np.float32(1 / 255)
