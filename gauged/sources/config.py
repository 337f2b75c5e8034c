"""Configuration models of the frame sources, selected by ``type:`` in the YAML."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field


class ZenohSourceConfig(BaseModel):
    """Frames from a Zenoh key expression (JPEG/PNG bytes or ROS 2 CDR images)."""

    model_config = ConfigDict(extra="forbid")

    type: Literal["zenoh"]
    key: str = Field(..., min_length=1, description="Key expression to subscribe to; wildcards allowed "
                     "(rmw_zenoh adds a type hash to its keys).")


class McapSourceConfig(BaseModel):
    """Frames replayed from an MCAP recording."""

    model_config = ConfigDict(extra="forbid")

    type: Literal["mcap"]
    path: Path = Field(..., description="MCAP file to replay (relative paths are taken from the working directory).")
    topic: str = Field(..., min_length=1, description="Image topic of this camera in the recording.")
    pace: Literal["realtime", "fast"] = Field(
        "realtime", description="realtime: respect the recorded log times; fast: as fast as frames are read.")
    loop: bool = Field(False, description="Start over at the end of the recording.")


SourceConfig = Annotated[ZenohSourceConfig | McapSourceConfig, Field(discriminator="type")]
