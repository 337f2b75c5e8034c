"""deploy/prometheus/: promtool accepts the scrape config and the rules, the rules' unit tests
pass and cover every alert both ways, and the rules read only series gauged exports."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
import yaml

from tests.deploy.metric_names import exported_metric_names, gauged_names_in, recorded_names_in
from tests.deploy.system_tools import require_tool, run_tool
from tests.deploy.unit_file import DEPLOY

PROM = DEPLOY / "prometheus"
RULES = PROM / "gauged.rules.yml"
RULE_TESTS = sorted((PROM / "tests").glob("*.yml"))


def promtool(*args: str) -> str:
    result = run_tool(require_tool("promtool", "prometheus"), *args)
    assert result.returncode == 0, result.stdout + result.stderr
    return result.stdout


def rules() -> list[dict]:
    return [rule for group in yaml.safe_load(RULES.read_text())["groups"] for rule in group["rules"]]


def test_scrape_config_is_valid() -> None:
    assert "SUCCESS" in promtool("check", "config", str(PROM / "prometheus.yml"))


def test_rules_are_valid() -> None:
    out = promtool("check", "rules", str(RULES))
    assert f"SUCCESS: {len(rules())} rules found" in out


def test_rule_unit_tests_pass() -> None:
    assert RULE_TESTS
    assert "SUCCESS" in promtool("test", "rules", *map(str, RULE_TESTS))


def test_rule_unit_tests_notice_a_changed_threshold(tmp_path: Path) -> None:
    """The unit tests pin the thresholds: raising one makes them fail."""
    (tmp_path / "tests").mkdir()
    text = RULES.read_text()
    assert "gauge:gauged_stage_failure_ratio:rate10m > 0.5" in text
    (tmp_path / RULES.name).write_text(text.replace("gauge:gauged_stage_failure_ratio:rate10m > 0.5",
                                                    "gauge:gauged_stage_failure_ratio:rate10m > 0.7"))
    for test in RULE_TESTS:
        shutil.copy(test, tmp_path / "tests" / test.name)
    result = run_tool(require_tool("promtool", "prometheus"), "test", "rules",
                      *(str(tmp_path / "tests" / t.name) for t in RULE_TESTS))
    assert result.returncode != 0 and "StageFailureRatioHigh" in result.stdout + result.stderr


def test_every_alert_is_tested_firing_and_not_firing() -> None:
    cases: dict[str, set[bool]] = {}
    for path in RULE_TESTS:
        for test in yaml.safe_load(path.read_text())["tests"]:
            for case in test.get("alert_rule_test", []):
                cases.setdefault(case["alertname"], set()).add(bool(case.get("exp_alerts")))
    alerts = {rule["alert"] for rule in rules() if "alert" in rule}
    assert {name: cases.get(name, set()) for name in alerts} == {name: {True, False} for name in alerts}


def test_every_recording_rule_is_tested_or_used_by_a_tested_alert() -> None:
    tested = set()
    for path in RULE_TESTS:
        for test in yaml.safe_load(path.read_text())["tests"]:
            tested |= {case["expr"] for case in test.get("promql_expr_test", [])}
            tested |= {case["alertname"] for case in test.get("alert_rule_test", [])}
    used_by = {name for rule in rules() if rule.get("alert") in tested for name in recorded_names_in(rule["expr"])}
    recorded = {rule["record"] for rule in rules() if "record" in rule}
    untested = {name for name in recorded if name not in tested and name not in used_by}
    # The latency quantile is a plain histogram_quantile for the dashboard; nothing to pin.
    assert untested <= {"stage:gauged_stage_duration_seconds:p95_5m"}


@pytest.mark.parametrize("rule", rules(), ids=lambda r: r.get("alert") or r["record"])
def test_rule_reads_only_exported_or_recorded_series(rule: dict) -> None:
    recorded = {r["record"] for r in rules() if "record" in r}
    assert gauged_names_in(rule["expr"]) <= exported_metric_names(), rule["expr"]
    assert recorded_names_in(rule["expr"]) <= recorded, rule["expr"]
