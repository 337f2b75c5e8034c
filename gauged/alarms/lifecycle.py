"""The life of one alarm as operators know it (ANSI/ISA-18.2-2016 fig. 8, IEC 62682 fig. 6).

States: ``normal``; ``active_unacknowledged`` (new, flashing); ``active_acknowledged`` (seen, still
true); ``returned_unacknowledged`` (gone before anyone saw it); and ``shelved`` (hidden by an
operator for a limited time). The condition (is the value past the limit, after delays) is kept
apart from the state (what the operator has seen), so an alarm that activates and clears while
shelved comes back in the right state when the shelve ends.

Every method returns the :class:`AlarmEvent` of a state change, or ``None`` when the state did not
change: events exist only for changes.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass
from typing import Any

NS_PER_S = 1_000_000_000


class AlarmState(str, enum.Enum):
    """The ISA-18.2 alarm states that gauged uses (no suppression by design, no out-of-service)."""

    NORMAL = "normal"
    ACTIVE_UNACKNOWLEDGED = "active_unacknowledged"
    ACTIVE_ACKNOWLEDGED = "active_acknowledged"
    RETURNED_UNACKNOWLEDGED = "returned_unacknowledged"
    SHELVED = "shelved"


UNACKNOWLEDGED = (AlarmState.ACTIVE_UNACKNOWLEDGED, AlarmState.RETURNED_UNACKNOWLEDGED)


class Transition(str, enum.Enum):
    """Why the state changed."""

    ACTIVATED = "activated"
    CLEARED = "cleared"
    ACKNOWLEDGED = "acknowledged"
    SHELVED = "shelved"
    UNSHELVED = "unshelved"
    SHELVE_EXPIRED = "shelve_expired"


@dataclass(frozen=True, slots=True)
class AlarmEvent:
    """One alarm state change: the ``<prefix>/<gauge>/alarm`` contract plus what makes it auditable.

    ``value`` is the quantity the alarm watches (the gauge value for limits, units/s for ``rate``,
    the failure ratio for ``failure``; null for ``stale``); ``limit`` the threshold it is held to.
    """

    gauge: str
    stamp_ns: int
    level: str
    state: AlarmState
    previous: AlarmState
    transition: Transition
    value: float | None
    limit: float | None
    message: str
    who: str | None = None
    why: str | None = None

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "gauge": self.gauge,
            "stamp_ns": self.stamp_ns,
            "level": self.level,
            "state": self.state.value,
            "value": self.value,
            "limit": self.limit,
            "message": self.message,
            "previous": self.previous.value,
            "transition": self.transition.value,
        }
        if self.who is not None:
            out["who"] = self.who
        if self.why is not None:
            out["why"] = self.why
        return out


@dataclass(frozen=True, slots=True)
class AlarmStatus:
    """The current state of one alarm, for the queryable and the metrics."""

    level: str
    state: AlarmState
    active: bool
    limit: float | None
    value: float | None
    since_ns: int | None
    shelved_until_ns: int | None = None
    shelved_by: str | None = None
    shelve_why: str | None = None

    @property
    def annunciated(self) -> bool:
        """Active and not shelved: what ``gauged_alarm_active`` shows."""
        return self.active and self.state is not AlarmState.SHELVED

    def to_dict(self) -> dict[str, Any]:
        return {
            "level": self.level, "state": self.state.value, "active": self.active, "limit": self.limit,
            "value": self.value, "since_ns": self.since_ns, "shelved_until_ns": self.shelved_until_ns,
            "shelved_by": self.shelved_by, "shelve_why": self.shelve_why,
        }


class Alarm:
    """State machine of one alarm of one gauge (``level`` is ``high``, ``stale``, ...)."""

    def __init__(self, gauge: str, level: str, limit: float | None) -> None:
        self.gauge = gauge
        self.level = level
        self.limit = limit
        self.state = AlarmState.NORMAL
        self.active = False
        self.value: float | None = None
        self.since_ns: int | None = None
        self.shelved_until_ns: int | None = None
        self.shelved_by: str | None = None
        self.shelve_why: str | None = None

    def _change(self, new: AlarmState, transition: Transition, now_ns: int, message: str,
                who: str | None = None, why: str | None = None) -> AlarmEvent:
        previous, self.state = self.state, new
        self.since_ns = now_ns
        return AlarmEvent(self.gauge, now_ns, self.level, new, previous, transition, self.value, self.limit,
                          message, who, why)

    def _state_for_condition(self) -> AlarmState:
        return AlarmState.ACTIVE_UNACKNOWLEDGED if self.active else AlarmState.NORMAL

    def set_active(self, active: bool, now_ns: int, value: float | None, message: str) -> AlarmEvent | None:
        """The debounced condition became ``active`` (or not). Silent while shelved."""
        if active == self.active:
            return None
        self.active, self.value = active, value
        if self.state is AlarmState.SHELVED:
            return None
        if active:
            return self._change(AlarmState.ACTIVE_UNACKNOWLEDGED, Transition.ACTIVATED, now_ns, message)
        new = AlarmState.RETURNED_UNACKNOWLEDGED if self.state is AlarmState.ACTIVE_UNACKNOWLEDGED else AlarmState.NORMAL
        return self._change(new, Transition.CLEARED, now_ns, message)

    def acknowledge(self, who: str, why: str | None, now_ns: int) -> AlarmEvent | None:
        """Operator acknowledgement; ``None`` when the alarm is not awaiting one."""
        if self.state not in UNACKNOWLEDGED:
            return None
        new = AlarmState.ACTIVE_ACKNOWLEDGED if self.state is AlarmState.ACTIVE_UNACKNOWLEDGED else AlarmState.NORMAL
        note = f": {why}" if why else ""
        return self._change(new, Transition.ACKNOWLEDGED, now_ns,
                            f"{self.gauge} {self.level} acknowledged by {who}{note}", who, why)

    def shelve(self, who: str, why: str, now_ns: int, until_ns: int) -> AlarmEvent | None:
        """Hide the alarm until ``until_ns``. Re-shelving only moves the end (no state change, no event)."""
        self.shelved_until_ns, self.shelved_by, self.shelve_why = until_ns, who, why
        if self.state is AlarmState.SHELVED:
            return None
        minutes = (until_ns - now_ns) / NS_PER_S / 60.0
        return self._change(AlarmState.SHELVED, Transition.SHELVED, now_ns,
                            f"{self.gauge} {self.level} shelved by {who} for {minutes:.0f} min: {why}", who, why)

    def unshelve(self, who: str | None, why: str | None, now_ns: int) -> AlarmEvent | None:
        """End a shelve early; the alarm returns to the state its condition calls for (unacknowledged if active)."""
        return self._end_shelve(now_ns, Transition.UNSHELVED, who, why)

    def expire(self, now_ns: int) -> AlarmEvent | None:
        """End a timed shelve whose time is up."""
        if self.state is not AlarmState.SHELVED or self.shelved_until_ns is None or now_ns < self.shelved_until_ns:
            return None
        return self._end_shelve(now_ns, Transition.SHELVE_EXPIRED, None, "shelve expired")

    def _end_shelve(self, now_ns: int, transition: Transition, who: str | None, why: str | None) -> AlarmEvent | None:
        if self.state is not AlarmState.SHELVED:
            return None
        self.shelved_until_ns = self.shelved_by = self.shelve_why = None
        new = self._state_for_condition()
        by = f" by {who}" if who else ""
        condition = "active" if self.active else "normal"
        return self._change(new, transition, now_ns, f"{self.gauge} {self.level} unshelved{by} ({condition})", who, why)

    def status(self) -> AlarmStatus:
        return AlarmStatus(self.level, self.state, self.active, self.limit, self.value, self.since_ns,
                           self.shelved_until_ns, self.shelved_by, self.shelve_why)

    def snapshot(self) -> dict[str, Any]:
        """What survives a restart (see docs/alarms.md, "State file")."""
        return {
            "state": self.state.value, "active": self.active, "value": self.value, "since_ns": self.since_ns,
            "shelved_until_ns": self.shelved_until_ns, "shelved_by": self.shelved_by, "shelve_why": self.shelve_why,
        }

    def restore(self, saved: dict[str, Any]) -> None:
        """Take back a :meth:`snapshot`. Raises ``ValueError`` on a malformed one (nothing is changed then)."""
        try:
            state = AlarmState(saved["state"])
            active = saved["active"]
            if not isinstance(active, bool):
                raise ValueError(f"'active' must be true or false, got {active!r}")
            value = _optional(saved.get("value"), float)
            since = _optional(saved.get("since_ns"), int)
            until = _optional(saved.get("shelved_until_ns"), int)
            by = _optional(saved.get("shelved_by"), str)
            why = _optional(saved.get("shelve_why"), str)
        except (KeyError, TypeError, ValueError) as exc:
            raise ValueError(f"alarm {self.level!r}: {exc}") from None
        if state is AlarmState.SHELVED and until is None:
            raise ValueError(f"alarm {self.level!r}: shelved without shelved_until_ns")
        consistent = {AlarmState.ACTIVE_UNACKNOWLEDGED: True, AlarmState.ACTIVE_ACKNOWLEDGED: True,
                      AlarmState.RETURNED_UNACKNOWLEDGED: False, AlarmState.NORMAL: False}
        if consistent.get(state, active) != active:
            raise ValueError(f"alarm {self.level!r}: state {state.value} contradicts active={active}")
        self.state, self.active, self.value, self.since_ns = state, active, value, since
        self.shelved_until_ns, self.shelved_by, self.shelve_why = until, by, why


def _optional(value: Any, kind: type) -> Any:
    if value is None:
        return None
    if kind is float and isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value):
        return float(value)
    if kind is int and isinstance(value, int) and not isinstance(value, bool):
        return value
    if kind is str and isinstance(value, str):
        return value
    raise TypeError(f"expected a finite {kind.__name__} or null, got {value!r}")
