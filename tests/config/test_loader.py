"""The loader names the file, line and key path of every problem."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from gauged.config import ConfigError, load_config, load_default_config, parse_config

REPO = Path(__file__).resolve().parents[2]

BASE = textwrap.dedent("""\
    site: t
    cameras:
      - id: cam1
        source: {type: zenoh, key: "a/b"}
      - id: cam2
        source: {type: mcap, path: x.mcap, topic: /cam2/image}
    gauges:
      - id: g1
        camera: cam1
      - id: g2
        camera: cam2
        alarms:
          low: 2
          high: 8
    """)


def _errors(text: str) -> list[str]:
    with pytest.raises(ConfigError) as info:
        parse_config(text, "cfg.yaml")
    return [str(issue) for issue in info.value.issues]


def test_parse_config_base_is_valid():
    config = parse_config(BASE)
    assert [g.id for g in config.gauges] == ["g1", "g2"]
    assert config.cameras[1].source.type == "mcap"
    assert config.gauges[1].alarms.high == 8


def test_parse_config_example_and_default_are_valid():
    config = load_config(REPO / "config" / "gauged.example.yaml")
    assert len(config.gauges) >= 2
    assert load_default_config().cameras


def test_parse_config_alarm_order_names_field_and_line():
    text = BASE.replace("high: 8", "high: 1")
    assert _errors(text) == ["cfg.yaml:14 gauges[1].alarms.high: must be greater than alarms.low (2)"]


def test_parse_config_high_high_below_high_is_blamed_on_high_high():
    text = BASE.replace("high: 8", "high: 8\n      high_high: 7")
    assert _errors(text) == ["cfg.yaml:15 gauges[1].alarms.high_high: must be greater than alarms.high (8)"]


def test_parse_config_unknown_key_names_its_line():
    text = BASE.replace("      low: 2", "      lo: 2")
    (error,) = _errors(text)
    assert error.startswith("cfg.yaml:13 gauges[1].alarms.lo: unknown key")


def test_parse_config_unknown_camera_reference():
    text = BASE.replace("camera: cam2", "camera: cam9")
    (error,) = _errors(text)
    assert error.startswith("cfg.yaml:11 gauges[1].camera: names camera 'cam9', which is not configured")


def test_parse_config_duplicate_ids():
    text = BASE.replace("id: cam2", "id: cam1").replace("camera: cam2", "camera: cam1").replace("id: g2", "id: g1")
    errors = _errors(text)
    assert "cfg.yaml:5 cameras[1].id: duplicate camera id 'cam1' (also cameras[0])" in errors
    assert "cfg.yaml:10 gauges[1].id: duplicate gauge id 'g1' (also gauges[0])" in errors


@pytest.mark.parametrize("roi", ["[0, 0, 10, 400]", "[-5, 0, 100, 100]", "[0, 0, 100, 99999]", "[100, 0, 50, 100]"])
def test_parse_config_roi_out_of_sane_bounds(roi):
    text = BASE.replace("camera: cam1", f"camera: cam1\n    roi: {roi}")
    (error,) = _errors(text)
    assert error.startswith("cfg.yaml:10 gauges[0].roi: ")


def test_parse_config_wrong_type_and_missing_key():
    text = BASE.replace('key: "a/b"', "").replace("low: 2", "low: two")
    errors = _errors(text)
    assert any(e.startswith("cfg.yaml:4 cameras[0].source.key: required key is missing") for e in errors)
    assert any(e.startswith("cfg.yaml:13 gauges[1].alarms.low: ") and "number" in e for e in errors)


def test_parse_config_unknown_source_type():
    (error,) = _errors(BASE.replace("type: zenoh", "type: rtsp"))
    assert error.startswith("cfg.yaml:4 cameras[0].source")
    assert "zenoh" in error and "mcap" in error


def test_parse_config_scale_max_must_exceed_min():
    text = BASE.replace("camera: cam1", "camera: cam1\n    scale: {min: 10, max: 0}")
    assert _errors(text) == ["cfg.yaml:10 gauges[0].scale.max: must be greater than scale.min (10)"]


def test_parse_config_scale_direction_is_cw_or_ccw():
    text = BASE.replace("camera: cam1", "camera: cam1\n    scale: {min: 0, max: 30, unit: inHg, direction: ccw}")
    assert parse_config(text).gauges[0].scale.direction == "ccw"
    assert parse_config(BASE.replace("camera: cam1", "camera: cam1\n    scale: {min: 0, max: 1}")).gauges[0].scale.direction == "cw"
    (error,) = _errors(BASE.replace("camera: cam1", "camera: cam1\n    scale: {min: 0, max: 1, direction: left}"))
    assert error.startswith("cfg.yaml:10 gauges[0].scale.direction") and "ccw" in error


def test_parse_config_bad_yaml_reports_line():
    (error,) = _errors("site: a\ncameras: [\n  - id: x\n")
    assert error.startswith("cfg.yaml:") and "not valid YAML" in error


def test_parse_config_top_level_must_be_mapping():
    assert _errors("- a\n- b\n") == ["cfg.yaml:1 <root>: the top level must be a mapping of keys"]


def test_parse_config_empty_file_gives_defaults():
    config = parse_config("")
    assert config.cameras == [] and config.outputs.prometheus.listen == "127.0.0.1:9464"


def test_load_config_missing_file_is_a_config_error(tmp_path):
    with pytest.raises(ConfigError) as info:
        load_config(tmp_path / "nope.yaml")
    assert "cannot read the file" in str(info.value)


def test_parse_config_bad_prefix_and_listen():
    text = BASE + "outputs:\n  zenoh: {prefix: 'a/**'}\n  prometheus: {listen: 'nowhere'}\n"
    errors = _errors(text)
    assert any(e.startswith("cfg.yaml:16 outputs.zenoh.prefix: must be a plain key") for e in errors)
    assert any(e.startswith("cfg.yaml:17 outputs.prometheus.listen: must be host:port") for e in errors)


def test_parse_config_rate_alarm_must_be_reachable():
    text = BASE.replace("      high: 8", "      high: 8\n      max_rate_per_s: 3\n    smoothing: {plausible_rate_per_s: 2}")
    (error,) = _errors(text)
    assert error.startswith("cfg.yaml:15 gauges[1].alarms.max_rate_per_s: must be below smoothing.plausible_rate_per_s (2)")


def _field_names(model: type) -> set[str]:
    from pydantic import BaseModel

    names = set()
    for name, field in model.model_fields.items():
        names.add(name)
        for candidate in getattr(field.annotation, "__args__", ()) + (field.annotation,):
            if isinstance(candidate, type) and issubclass(candidate, BaseModel):
                names |= _field_names(candidate)
    return names


def test_example_config_shows_every_option():
    from gauged.config.model import GaugedConfig
    from gauged.sources.config import McapSourceConfig, ZenohSourceConfig

    text = (REPO / "config" / "gauged.example.yaml").read_text()
    names = _field_names(GaugedConfig) | _field_names(McapSourceConfig) | _field_names(ZenohSourceConfig)
    missing = sorted(name for name in names if f"{name}:" not in text)
    assert not missing, f"config/gauged.example.yaml does not show: {missing}"
