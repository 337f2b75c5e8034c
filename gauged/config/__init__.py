"""Typed configuration: the model tree, its YAML loader, and errors naming key path and line."""

from gauged.config.errors import ConfigError, ConfigIssue
from gauged.config.loader import default_config_text, load_config, load_default_config, parse_config
from gauged.config.model import CameraConfig, GaugeConfig, GaugedConfig, ScaleConfig

__all__ = [
    "CameraConfig",
    "ConfigError",
    "ConfigIssue",
    "GaugeConfig",
    "GaugedConfig",
    "ScaleConfig",
    "default_config_text",
    "load_config",
    "load_default_config",
    "parse_config",
]
