"""A one-screen, human-readable summary of a validated config."""

from __future__ import annotations

from gauged.config.model import GaugedConfig


def _limits(alarms) -> str:
    parts = [f"{name}={getattr(alarms, name):g}" for name in ("low_low", "low", "high", "high_high")
             if getattr(alarms, name) is not None]
    return " ".join(parts) or "no limits"


def summarize(config: GaugedConfig) -> str:
    """Sites, cameras, gauges and outputs in a few lines each (what ``check-config`` prints)."""
    lines = [f"site {config.site}  (zenoh {config.zenoh.mode}"
             + (f", connect {', '.join(config.zenoh.connect)}" if config.zenoh.connect else "") + ")"]
    lines.append(f"cameras ({len(config.cameras)}):")
    for camera in config.cameras:
        src = camera.source
        where = f"zenoh {src.key}" if src.type == "zenoh" else f"mcap {src.path} {src.topic} ({src.pace}{', loop' if src.loop else ''})"
        rate = f", max {camera.max_rate_hz:g} Hz" if camera.max_rate_hz else ""
        lines.append(f"  {camera.id:<16} {where}{rate}")
    lines.append(f"gauges ({len(config.gauges)}):")
    for gauge in config.gauges:
        where = f"roi {list(gauge.roi)}" if gauge.roi else "detected"
        scale = (f"scale {gauge.scale.min:g}..{gauge.scale.max:g} {gauge.scale.unit or ''}".rstrip()
                 if gauge.scale else "scale by OCR")
        lines.append(f"  {gauge.id:<16} on {gauge.camera}, {where}, {scale}, alarms: {_limits(gauge.alarms)}")
    out = config.outputs
    sinks = []
    if out.zenoh.enabled:
        sinks.append(f"zenoh {out.zenoh.prefix}/<gauge>/reading")
    if out.mcap.enabled:
        sinks.append(f"mcap {out.mcap.dir}/ (rotate {out.mcap.rotate_mb:g} MiB / {out.mcap.rotate_s:g} s)")
    if out.prometheus.enabled:
        sinks.append(f"prometheus http://{out.prometheus.listen}/metrics")
    lines.append("outputs: " + ("; ".join(sinks) if sinks else "none"))
    lines.append(f"state: {config.state.dir} (kept {config.state.max_age_s:g} s)")
    return "\n".join(lines)
