from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from gauged.tracking.hampel import HampelWindow


def _verdicts(window: HampelWindow, values: list[float]) -> list[bool]:
    return [window.push(v).outlier for v in values]


@pytest.mark.parametrize(
    ("name", "size", "values", "expected"),
    [
        ("spike", 5, [1, 1, 1, 1, 9, 1], [False, False, False, False, True, False]),
        ("two-frame spike", 5, [1, 1, 1, 1, 9, 9, 1], [False, False, False, False, True, True, False]),
        ("step size 5 waits 2 frames", 5, [1, 1, 1, 1, 5, 5, 5, 5], [False] * 4 + [True, True, False, False]),
        ("step size 3 waits 1 frame", 3, [1, 1, 1, 5, 5, 5], [False] * 3 + [True, False, False]),
        ("step size 7 waits 3 frames", 7, [1] * 7 + [5] * 5, [False] * 7 + [True, True, True, False, False]),
        ("too few to judge", 5, [1, 9], [False, False]),
        ("disabled", 1, [1, 1, 100, 1], [False] * 4),
        ("jitter under the floor", 5, [1.0, 1.02, 0.98, 1.01, 0.97, 1.03], [False] * 6),
    ],
)
def test_hampel_window_verdicts(name: str, size: int, values: list[float], expected: list[bool]) -> None:
    assert _verdicts(HampelWindow(size, k=3.0, floor=0.05), [float(v) for v in values]) == expected, name


def test_hampel_window_reset_forgets_old_values() -> None:
    window = HampelWindow(5, k=3.0, floor=0.05)
    _verdicts(window, [1.0] * 5)
    window.reset()
    assert len(window) == 0
    assert _verdicts(window, [9.0, 9.0, 9.0]) == [False, False, False]


def test_hampel_window_verdict_reports_median_and_floored_spread() -> None:
    window = HampelWindow(5, k=3.0, floor=0.05)
    verdict = [window.push(v) for v in (2.0, 2.0, 2.0)][-1]
    assert (verdict.median, verdict.spread, verdict.judged) == (2.0, 0.05, True)


@pytest.mark.parametrize(("size", "k", "floor"), [(0, 3.0, 0.1), (5, 0.0, 0.1), (5, 3.0, -1.0)])
def test_hampel_window_rejects_bad_arguments(size: int, k: float, floor: float) -> None:
    with pytest.raises(ValueError):
        HampelWindow(size, k, floor)


@given(size=st.integers(3, 9), before=st.floats(-100, 100), height=st.floats(1, 1000) | st.floats(-1000, -1))
def test_hampel_window_accepts_any_step_after_half_the_window(size: int, before: float, height: float) -> None:
    window = HampelWindow(size, k=3.0, floor=0.01)
    _verdicts(window, [before] * size)
    after = _verdicts(window, [before + height] * size)
    delay = (size - 1) // 2
    assert after == [True] * delay + [False] * (size - delay)
