"""Per-gauge smoothing and quality (docs/alarms.md).

``tracker.GaugeTracker`` is what the daemon uses: one per gauge, combining ``gauge_smoother`` (Hampel
outliers, plausible rate, Kalman/EMA) with ``gauged.alarms``; ``state_file`` saves and restores it.
Nothing is imported here: ``gauged.config`` imports ``tracking.config``, and an eager import of the
tracker would make that a cycle.
"""
