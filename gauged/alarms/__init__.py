"""Alarm rules of one gauge and their ISA-18.2 states (docs/alarms.md).

``gauge_alarms.GaugeAlarms`` judges readings (limits with deadband and delays, rate, stale, failure);
``lifecycle`` holds the alarm state machine and ``AlarmEvent``; ``commands`` parses and applies
operator ack/shelve/unshelve payloads. Nothing is imported here, to keep ``gauged.config`` acyclic.
"""
