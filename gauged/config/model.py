"""The one typed configuration tree of gauged (see ``config/gauged.example.yaml``)."""

from __future__ import annotations

from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from gauged.alarms.config import AlarmsConfig
from gauged.config.errors import FieldIssues
from gauged.sinks.config import OutputsConfig
from gauged.sources.config import SourceConfig
from gauged.tracking.config import SmoothingConfig

MAX_IMAGE_SIDE_PX = 16384  # no camera we support is larger; larger ROIs are typos
MIN_ROI_SIDE_PX = 16  # below this no stage can read a dial


class ZenohConfig(BaseModel):
    """The daemon's Zenoh session (passed to ``zenoh.Config``)."""

    model_config = ConfigDict(extra="forbid")

    mode: Literal["peer", "client", "router"] = Field("peer", description="Zenoh session mode.")
    connect: list[str] = Field(default_factory=list, description="Endpoints to connect to, e.g. tcp/10.0.0.1:7447.")
    listen: list[str] = Field(default_factory=list, description="Endpoints to listen on.")
    multicast_scouting: bool = Field(True, description="Find peers on the LAN by multicast scouting.")


class CameraConfig(BaseModel):
    model_config = ConfigDict(extra="forbid")

    id: str = Field(..., min_length=1, pattern=r"^[A-Za-z0-9_.-]+$", description="Camera id (used in keys and labels).")
    source: SourceConfig = Field(..., description="Where frames come from; `type:` selects zenoh or mcap.")
    max_rate_hz: float | None = Field(None, gt=0, description="Read at most this many frames per second (others are dropped and counted).")


class ScaleConfig(BaseModel):
    """A known scale: its values are used instead of the numbers read, and where the dial's end notches
    are not found, the numbers read place the configured ends (a strong prior, not a bypass)."""

    model_config = ConfigDict(extra="forbid")

    min: float = Field(..., description="Value at the start of the scale.")
    max: float = Field(..., description="Value at the end of the scale.")
    unit: str | None = Field(None, description="Unit printed on the dial, e.g. bar, psi, degC.")
    direction: Literal["cw", "ccw"] = Field(
        "cw", description="Which way the values rise: cw (min at the first notch clockwise) or ccw (min at the "
        "last: vacuum and some compound gauges, 0..30 inHg or -1..0 bar rising counter-clockwise).")

    @model_validator(mode="after")
    def _ordered(self) -> ScaleConfig:
        if not self.max > self.min:
            issues = FieldIssues()
            issues.add(("max",), f"must be greater than scale.min ({self.min:g})")
            issues.raise_if_any()
        return self


class GaugeConfig(BaseModel):
    model_config = ConfigDict(extra="forbid")

    id: str = Field(..., min_length=1, pattern=r"^[A-Za-z0-9_.-]+$", description="Gauge id (used in keys and labels).")
    camera: str = Field(..., description="Id of the camera that sees this gauge.")
    roi: tuple[int, int, int, int] | None = Field(
        None, description="Region [x0, y0, x1, y1] in pixels of the camera image; without it the gauge is detected.")
    scale: ScaleConfig | None = Field(None, description="Known scale; without it the scale is read by OCR and locked.")
    primary_unit: str | None = Field(None, description="On a dial with two scales, publish the one in this unit.")
    smoothing: SmoothingConfig = Field(default_factory=SmoothingConfig)
    alarms: AlarmsConfig = Field(default_factory=AlarmsConfig)

    @model_validator(mode="after")
    def _rate_alarm_reachable(self) -> GaugeConfig:
        plausible, alarm = self.smoothing.plausible_rate_per_s, self.alarms.max_rate_per_s
        if plausible is not None and alarm is not None and plausible <= alarm:
            issues = FieldIssues()
            issues.add(("alarms", "max_rate_per_s"), f"must be below smoothing.plausible_rate_per_s ({plausible:g}): "
                       "faster changes are rejected as implausible, so the rate alarm could never fire")
            issues.raise_if_any()
        return self

    @field_validator("roi")
    @classmethod
    def _sane_roi(cls, roi: tuple[int, int, int, int] | None) -> tuple[int, int, int, int] | None:
        if roi is None:
            return roi
        x0, y0, x1, y1 = roi
        if min(roi) < 0 or max(roi) > MAX_IMAGE_SIDE_PX:
            raise ValueError(f"coordinates must lie in [0, {MAX_IMAGE_SIDE_PX}] px, got {list(roi)}")
        if x1 - x0 < MIN_ROI_SIDE_PX or y1 - y0 < MIN_ROI_SIDE_PX:
            raise ValueError(f"must be [x0, y0, x1, y1] with x1 > x0 and y1 > y0, at least {MIN_ROI_SIDE_PX} px each way; got {list(roi)}")
        return roi


class ReaderConfig(BaseModel):
    """Settings of the reading pipeline."""

    model_config = ConfigDict(extra="forbid")

    threads: int = Field(2, ge=1, le=64, description="onnxruntime intra-op threads per model.")
    min_confidence: float = Field(0.5, ge=0, le=1, description="Readings below this confidence are refused.")
    models_dir: Path | None = Field(None, description="Folder whose crop.onnx/detector.onnx replace the shipped "
                                    "models (a candidate model under evaluation), and whose numbers.onnx/minus.onnx/"
                                    "ocr_det_int8.onnx/notch_check.onnx do where it holds them; unset: the shipped ones.")
    ocr_int8_detector: bool = Field(True, description="Run the OCR text detector as the shipped int8 copy of the "
                                    "OCR wheel's float model (2.7x faster, the same readings on the dev sets); "
                                    "false: the float model.")
    ocr_number_net: bool = Field(True, description="When a dial's numbers give no scale, read them again with the "
                                 "shipped number net (numbers.onnx) too and keep a scale it gives (docs/ocr.md); "
                                 "false: PP-OCR's recogniser alone.")
    ocr_minus_net: bool = Field(True, description="Tell a faint minus the text box left out from a tick beside a "
                                "number with the shipped minus net (minus.onnx) and the number net's evidence "
                                "together (docs/ocr.md); false: the number net's strings alone.")
    notch_check: bool = Field(True, description="A dial refused because its notch peaks fit no scale ring (after "
                              "every other look) is read once more on the major peaks the shipped notch check "
                              "(notch_check.onnx) keeps, without the minor ticks it drops; false: never.")


class ScaleLockConfig(BaseModel):
    """How the scale of a fixed camera is estimated over several frames and locked."""

    model_config = ConfigDict(extra="forbid")

    frames: int = Field(5, ge=1, description="Frames with a full scale read that are fused before locking.")
    recheck_every_s: float = Field(300.0, gt=0, description="Re-verify a locked scale this often (frame time).")
    move_tolerance_px: float = Field(8.0, gt=0, description="Release the lock when the gauge moves more than this.")


class StateConfig(BaseModel):
    model_config = ConfigDict(extra="forbid")

    dir: Path = Field(Path("gauged-state"), description="Where the last values and alarm states are saved.")
    max_age_s: float = Field(3600.0, ge=0, description="Saved state older than this is ignored on start.")


class GaugedConfig(BaseModel):
    """The whole configuration of one gauged daemon."""

    model_config = ConfigDict(extra="forbid")

    site: str = Field("gauged", min_length=1, pattern=r"^[A-Za-z0-9_.-]+$", description="Site name, used in logs and as the default node name.")
    node: str | None = Field(None, pattern=r"^[A-Za-z0-9_.-]+$", description="Node name of the liveliness token; default: the host name.")
    zenoh: ZenohConfig = Field(default_factory=ZenohConfig)
    cameras: list[CameraConfig] = Field(default_factory=list, description="Cameras and where their frames come from.")
    gauges: list[GaugeConfig] = Field(default_factory=list, description="Gauges to read, each on one camera.")
    reader: ReaderConfig = Field(default_factory=ReaderConfig)
    scale_lock: ScaleLockConfig = Field(default_factory=ScaleLockConfig)
    outputs: OutputsConfig = Field(default_factory=OutputsConfig)
    state: StateConfig = Field(default_factory=StateConfig)

    @model_validator(mode="after")
    def _references(self) -> GaugedConfig:
        issues = FieldIssues()
        seen: dict[str, int] = {}
        for i, camera in enumerate(self.cameras):
            if camera.id in seen:
                issues.add(("cameras", i, "id"), f"duplicate camera id {camera.id!r} (also cameras[{seen[camera.id]}])")
            seen.setdefault(camera.id, i)
        gauge_seen: dict[str, int] = {}
        for i, gauge in enumerate(self.gauges):
            if gauge.id in gauge_seen:
                issues.add(("gauges", i, "id"), f"duplicate gauge id {gauge.id!r} (also gauges[{gauge_seen[gauge.id]}])")
            gauge_seen.setdefault(gauge.id, i)
            if gauge.camera not in seen:
                known = ", ".join(sorted(seen)) or "none"
                issues.add(("gauges", i, "camera"), f"names camera {gauge.camera!r}, which is not configured (cameras: {known})")
        issues.raise_if_any()
        return self

    def gauges_of(self, camera_id: str) -> list[GaugeConfig]:
        return [g for g in self.gauges if g.camera == camera_id]
