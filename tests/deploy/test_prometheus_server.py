"""A real Prometheus server scrapes a real gauged and loads deploy/prometheus/gauged.rules.yml.

The daemon replays the demo recording (four gauges); Prometheus (the Debian package's
/usr/bin/prometheus) runs on a free loopback port with a tmp storage directory, scrapes the daemon
every second and evaluates the shipped rules. Through Prometheus's HTTP API the test then finds a
``gauged_reading_value`` series for every demo gauge (a numeric value inside the gauge's scale;
NaN is allowed for a gauge whose frames the reader refuses), the target up with its site label,
every shipped rule loaded and evaluating without error, and the recorded reading quality of every
gauge: the series gauged exports are the ones the rules read.
"""

from __future__ import annotations

import json
import math
import subprocess
import time
import urllib.parse
from pathlib import Path

import pytest
import yaml

from tests.deploy.daemon_process import (
    DEMO_CONFIG,
    demo_config,
    free_port,
    http_get,
    require_daemon_inputs,
    running_daemon,
    write_config,
)
from tests.deploy.unit_file import DEPLOY

PROMETHEUS = Path("/usr/bin/prometheus")
RULES = DEPLOY / "prometheus" / "gauged.rules.yml"
DEADLINE_S = 60.0

pytestmark = [pytest.mark.slow, pytest.mark.timeout(180)]


def api(port: int, path: str, **params: str) -> dict:
    url = f"http://127.0.0.1:{port}/api/v1/{path}"
    if params:
        url += "?" + urllib.parse.urlencode(params)
    body = json.loads(http_get(url))
    assert body["status"] == "success", body
    return body["data"]


def query(port: int, promql: str) -> list[dict]:
    return api(port, "query", query=promql)["result"]


def wait_until(what: str, check, deadline: float, alive) -> object:
    """Poll ``check()`` every 0.5 s until it returns something truthy; fail at ``deadline``."""
    last: object = None
    while time.monotonic() < deadline:
        problem = alive()
        if problem:
            pytest.fail(problem)
        try:
            last = check()
        except OSError as exc:  # server not listening yet
            last = exc
        else:
            if last:
                return last
        time.sleep(0.5)
    pytest.fail(f"timed out waiting for {what}; last answer: {last!r}")


def test_prometheus_scrapes_the_daemon_and_loads_the_rules(tmp_path: Path) -> None:
    if not PROMETHEUS.is_file():
        pytest.skip(f"{PROMETHEUS} not found: run deploy/ci/install-system-deps.sh as root, "
                    "or: sudo apt-get install -y prometheus")
    require_daemon_inputs()
    started = time.monotonic()
    deadline = started + DEADLINE_S
    metrics_port, web_port = free_port(), free_port()
    config = demo_config(tmp_path / "out", metrics_port)
    config_path = write_config(tmp_path / "gauged.yaml", config)
    scales = {g["id"]: g["scale"] for g in yaml.safe_load(DEMO_CONFIG.read_text())["gauges"]}

    prom_config = tmp_path / "prometheus.yml"
    prom_config.write_text(yaml.safe_dump({
        "global": {"scrape_interval": "1s", "scrape_timeout": "1s", "evaluation_interval": "1s"},
        "rule_files": [str(RULES)],
        "scrape_configs": [{"job_name": "gauged", "static_configs": [
            {"targets": [f"127.0.0.1:{metrics_port}"], "labels": {"site": "test-site"}}]}],
    }, sort_keys=False))
    prom_log = tmp_path / "prometheus.log"
    figures: dict[str, float] = {}

    with running_daemon(config_path, tmp_path) as daemon, open(prom_log, "wb") as log:
        prometheus = subprocess.Popen(
            [str(PROMETHEUS), f"--config.file={prom_config}", f"--storage.tsdb.path={tmp_path / 'tsdb'}",
             f"--web.listen-address=127.0.0.1:{web_port}", "--storage.tsdb.retention.time=1h",
             "--log.level=warn"],
            cwd=tmp_path, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT,
            start_new_session=True)
        try:
            def alive() -> str | None:
                if not daemon.alive():
                    return f"gauged exited: {daemon.describe()}"
                if prometheus.poll() is not None:
                    return f"prometheus exited with {prometheus.returncode}:\n{prom_log.read_text()[-3000:]}"
                return None

            def every_gauge_has_a_series():
                series = {r["metric"].get("gauge"): r for r in query(web_port, "gauged_reading_value")}
                return series if set(scales) <= set(series) else None

            # The rules are loaded at start: an invalid file would have stopped the server.
            groups = wait_until("the rules", lambda: api(web_port, "rules")["groups"], deadline, alive)
            figures["prometheus_up_s"] = time.monotonic() - started

            series = wait_until("a gauged_reading_value series of every demo gauge", every_gauge_has_a_series,
                                deadline, alive)
            figures["all_gauges_in_prometheus_s"] = time.monotonic() - started

            numeric = {}
            for gauge, scale in scales.items():
                metric, (_, text) = series[gauge]["metric"], series[gauge]["value"]
                assert metric["job"] == "gauged" and metric["site"] == "test-site", metric
                assert metric["instance"] == f"127.0.0.1:{metrics_port}", metric
                value = float(text)  # Prometheus writes NaN as "NaN"
                if not math.isnan(value):
                    assert metric["unit"] == scale["unit"], metric
                    assert scale["min"] <= value <= scale["max"], f"{gauge} = {value} outside {scale}"
                    numeric[gauge] = value
            assert numeric, f"no gauge has a numeric reading: {series}"
            print("readings in Prometheus:", {g: float(s["value"][1]) for g, s in series.items()})

            (target,) = api(web_port, "targets")["activeTargets"]
            assert target["health"] == "up", target

            # Every shipped rule is loaded, and is evaluated without error on the daemon's series.
            shipped = yaml.safe_load(RULES.read_text())["groups"]
            assert {g["name"]: len(g["rules"]) for g in groups} == {g["name"]: len(g["rules"]) for g in shipped}

            def rules_evaluated():
                loaded = api(web_port, "rules")["groups"]
                rules = [r for g in loaded for r in g["rules"]]
                pending = [r["name"] for r in rules if r["health"] != "ok"]
                return loaded if not pending else None

            loaded = wait_until("every rule evaluated with health ok", rules_evaluated, deadline, alive)
            errors = {r["name"]: r.get("lastError") for g in loaded for r in g["rules"] if r.get("lastError")}
            assert not errors, errors

            def quality_recorded():
                recorded = {r["metric"]["gauge"] for r in query(web_port, "gauge:gauged_reading_quality:code")}
                return recorded if set(scales) <= recorded else None

            wait_until("gauge:gauged_reading_quality:code of every gauge", quality_recorded, deadline, alive)
            figures["rules_recorded_s"] = time.monotonic() - started
            # GaugedAbsent may be pending from an evaluation before the first scrape; with the daemon
            # scraped it must resolve (and GaugedDown never fire).
            wait_until("GaugedAbsent and GaugedDown inactive",
                       lambda: not query(web_port, 'ALERTS{alertname=~"GaugedDown|GaugedAbsent"}'), deadline, alive)
            figures["absent_alert_inactive_s"] = time.monotonic() - started
        finally:
            if prometheus.poll() is None:
                prometheus.terminate()
                try:
                    prometheus.wait(15)
                except subprocess.TimeoutExpired:
                    prometheus.kill()
                    prometheus.wait(5)
            print("measured:", ", ".join(f"{k}={v:.2f}" for k, v in figures.items()))
