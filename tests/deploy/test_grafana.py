"""deploy/grafana/gauged.json imports cleanly: a well-formed dashboard whose panels have unique ids,
sane non-overlapping positions, a Prometheus data source and queries that promtool parses and that
read only series gauged exports, using only variables the dashboard defines."""

from __future__ import annotations

import json
import re
from itertools import combinations
from pathlib import Path

import pytest
import yaml

from tests.deploy.metric_names import PROMETHEUS_SERIES, exported_metric_names, gauged_names_in
from tests.deploy.system_tools import require_tool, run_tool
from tests.deploy.unit_file import DEPLOY

DASHBOARD = json.loads((DEPLOY / "grafana" / "gauged.json").read_text())
PANELS = DASHBOARD["panels"]
QUERY_PANELS = [p for p in PANELS if p["type"] != "row"]
VARIABLES = {v["name"]: v for v in DASHBOARD["templating"]["list"]}
BUILTIN_VARIABLES = {"__rate_interval", "__interval", "__range", "__all"}
GRID_COLUMNS = 24


def variables_in(text: str) -> set[str]:
    return set(re.findall(r"\$\{?(\w+)", text))


def expressions() -> list[str]:
    return [t["expr"] for p in QUERY_PANELS for t in p["targets"]]


def test_dashboard_has_identity_and_schema() -> None:
    assert isinstance(DASHBOARD["schemaVersion"], int) and DASHBOARD["schemaVersion"] >= 36
    assert DASHBOARD["uid"] and DASHBOARD["title"] and "id" not in DASHBOARD  # no instance id: imports anywhere


def test_panel_ids_are_unique() -> None:
    ids = [p["id"] for p in PANELS]
    assert len(ids) == len(set(ids))


@pytest.mark.parametrize("panel", PANELS, ids=lambda p: f'{p["id"]}-{p["title"]}')
def test_panel_sits_inside_the_grid(panel: dict) -> None:
    g = panel["gridPos"]
    assert g["x"] >= 0 and g["y"] >= 0 and g["w"] >= 1 and g["h"] >= 1 and g["x"] + g["w"] <= GRID_COLUMNS


def test_panels_do_not_overlap() -> None:
    def cells(p: dict) -> set[tuple[int, int]]:
        g = p["gridPos"]
        return {(x, y) for x in range(g["x"], g["x"] + g["w"]) for y in range(g["y"], g["y"] + g["h"])}

    for a, b in combinations(PANELS, 2):
        assert not cells(a) & cells(b), f'{a["title"]} overlaps {b["title"]}'


@pytest.mark.parametrize("panel", QUERY_PANELS, ids=lambda p: f'{p["id"]}-{p["title"]}')
def test_panel_queries_prometheus_through_the_datasource_variable(panel: dict) -> None:
    source = {"type": "prometheus", "uid": "${datasource}"}
    assert panel["datasource"] == source and panel["targets"]
    assert all(t["datasource"] == source and t["expr"].strip() for t in panel["targets"])
    ref_ids = [t["refId"] for t in panel["targets"]]
    assert len(ref_ids) == len(set(ref_ids))


@pytest.mark.parametrize("panel", QUERY_PANELS, ids=lambda p: f'{p["id"]}-{p["title"]}')
def test_panel_reads_only_exported_series(panel: dict) -> None:
    for target in panel["targets"]:
        expr = target["expr"]
        names = gauged_names_in(expr)
        assert names <= exported_metric_names(), expr
        # A query without a gauged series may only ask whether Prometheus reaches gauged at all.
        other = "|".join(sorted(PROMETHEUS_SERIES))
        assert names or re.fullmatch(rf"({other})\{{[^}}]*\}}", expr.strip()), expr


def test_dashboard_covers_the_brief() -> None:
    """Value, quality, alarms, failures by reason, dropped frames and latency quantiles all shown."""
    used = set().union(*(gauged_names_in(e) for e in expressions()))
    assert {"gauged_reading_value", "gauged_reading_quality", "gauged_alarm_active", "gauged_stage_failures_total",
            "gauged_frames_dropped_total", "gauged_stage_duration_seconds_bucket"} <= used
    assert any("histogram_quantile" in e for e in expressions())


def test_variables_used_are_defined() -> None:
    texts = [json.dumps(p) for p in PANELS] + [json.dumps(v.get("query", "")) for v in VARIABLES.values()]
    used = set().union(*(variables_in(t) for t in texts))
    assert used - BUILTIN_VARIABLES <= set(VARIABLES), used - BUILTIN_VARIABLES - set(VARIABLES)
    repeated = {p["repeat"] for p in PANELS if p.get("repeat")}
    assert all(VARIABLES[name]["multi"] or VARIABLES[name]["includeAll"] for name in repeated)


def test_variable_queries_read_exported_series() -> None:
    for variable in VARIABLES.values():
        if variable["type"] == "query":
            query = variable["query"]["query"]
            assert gauged_names_in(query) and gauged_names_in(query) <= exported_metric_names(), query


def test_queries_parse_with_promtool(tmp_path: Path) -> None:
    """Each query, with the variables filled in as Grafana would, is valid PromQL."""
    tool = require_tool("promtool", "prometheus")
    filled = [re.sub(r"\$\{?\w+\}?", lambda m: "5m" if "rate_interval" in m.group() else ".*", e)
              for e in expressions()]
    rules = {"groups": [{"name": "dashboard", "rules": [{"record": f"dashboard:query_{i}", "expr": e}
                                                        for i, e in enumerate(filled)]}]}
    path = tmp_path / "dashboard-queries.yml"
    path.write_text(yaml.safe_dump(rules))
    result = run_tool(tool, "check", "rules", str(path))
    assert result.returncode == 0, result.stdout + result.stderr
