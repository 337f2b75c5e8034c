"""Configuration models of the outputs (Zenoh, MCAP, Prometheus)."""

from __future__ import annotations

from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator


class ZenohSinkConfig(BaseModel):
    model_config = ConfigDict(extra="forbid")

    enabled: bool = Field(True, description="Publish readings and alarms on Zenoh.")
    prefix: str = Field("gauged", min_length=1, description="Key prefix: readings go to <prefix>/<gauge>/reading.")
    annotations: bool = Field(
        True, description="Put each gauge's overlay (foxglove.ImageAnnotations) on <prefix>/<gauge>/annotations.")

    @field_validator("prefix")
    @classmethod
    def _plain_prefix(cls, prefix: str) -> str:
        if any(c in prefix for c in "*$?#") or prefix.startswith("/") or prefix.endswith("/"):
            raise ValueError("must be a plain key without wildcards or leading/trailing '/'")
        return prefix


class McapSinkConfig(BaseModel):
    model_config = ConfigDict(extra="forbid")

    enabled: bool = Field(True, description="Log readings, failures and alarms to MCAP files.")
    dir: Path = Field(Path("gauged-out"), description="Directory of the MCAP files.")
    rotate_mb: float = Field(256.0, gt=0, description="Start a new file once the current one reaches this size (MiB).")
    rotate_s: float = Field(3600.0, gt=0, description="Start a new file after this many seconds of frame time.")
    images: Literal["none", "annotated"] = Field(
        "none", description="Also log annotated camera images on /gauged/<camera>/annotated.")
    annotations: bool = Field(
        True, description="Log the readings' overlays (foxglove.ImageAnnotations) on /<camera>/gauged/annotations.")
    chunk_kb: int = Field(
        64, ge=4, le=65536, description="Size of a zstd chunk (KiB); a crash loses at most the chunk being filled.")
    flush_s: float = Field(
        2.0, gt=0, description="Close the open chunk at least this often (seconds), bounding what a crash can lose.")


class PrometheusSinkConfig(BaseModel):
    model_config = ConfigDict(extra="forbid")

    enabled: bool = Field(True, description="Serve Prometheus metrics over HTTP.")
    listen: str = Field("127.0.0.1:9464", description="host:port of the metrics endpoint (loopback by default).")

    @field_validator("listen")
    @classmethod
    def _host_port(cls, listen: str) -> str:
        host, sep, port = listen.rpartition(":")
        if not sep or not host or not port.isdigit() or not 0 <= int(port) <= 65535:
            raise ValueError("must be host:port, e.g. 127.0.0.1:9464")
        return listen


class OutputsConfig(BaseModel):
    model_config = ConfigDict(extra="forbid")

    zenoh: ZenohSinkConfig = Field(default_factory=ZenohSinkConfig)
    mcap: McapSinkConfig = Field(default_factory=McapSinkConfig)
    prometheus: PrometheusSinkConfig = Field(default_factory=PrometheusSinkConfig)
