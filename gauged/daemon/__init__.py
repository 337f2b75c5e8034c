"""The daemon layer: wiring (app), per-camera frame loop (camera_worker), per-gauge reading (gauge_runner),
and matching detections to configured gauges (association)."""
