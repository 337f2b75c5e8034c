"""A causal Hampel outlier test over the last few raw readings of one gauge.

The Hampel identifier (Hampel 1974; Pearson, "Outliers in process modeling and identification",
IEEE TCST 10(1), 2002) flags a sample whose distance from the window median exceeds ``k`` times the
scaled median absolute deviation ``1.4826 * MAD`` (1.4826 makes the MAD a consistent estimate of a
Gaussian standard deviation). This version is *causal*: the window holds the current reading and
the ones before it, because a published value cannot wait for future frames. Every valid reading
enters the window, rejected ones too, so a real step wins the median after ``(size - 1) // 2``
frames, while a spike of at most that many frames never does.

>>> window = HampelWindow(size=5, k=3.0, floor=0.05)
>>> [window.push(v).outlier for v in (1.0, 1.0, 1.0, 1.0, 9.0)]
[False, False, False, False, True]
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

MAD_TO_SIGMA = 1.4826  # consistency constant of the MAD for Gaussian noise
MIN_JUDGED = 3  # a median of fewer samples cannot outvote a single bad one


@dataclass(frozen=True, slots=True)
class HampelVerdict:
    """The test of one reading: ``outlier`` is True when it is rejected.

    ``median`` and ``spread`` (the scaled MAD, floored) describe the window including this reading;
    ``judged`` is False while the window holds fewer than three readings (nothing is rejected then).
    """

    outlier: bool
    median: float
    spread: float
    judged: bool


class HampelWindow:
    """Trailing window of raw values with the Hampel test.

    ``size`` is the number of readings kept (1 disables the test), ``k`` the threshold in spreads,
    and ``floor`` the smallest spread in gauge units: on a still needle the MAD is zero and, without
    a floor, any jitter would count as an outlier.
    """

    def __init__(self, size: int, k: float, floor: float) -> None:
        if size < 1 or k <= 0 or floor < 0:
            raise ValueError(f"need size >= 1, k > 0, floor >= 0; got size={size}, k={k}, floor={floor}")
        self.size = size
        self.k = k
        self.floor = floor
        self._values: deque[float] = deque(maxlen=size)

    def __len__(self) -> int:
        return len(self._values)

    def reset(self) -> None:
        """Forget every reading (after a dropout the old values say nothing about the new ones)."""
        self._values.clear()

    def median(self) -> float:
        """Median of the readings in the window (the window must not be empty)."""
        return float(np.median(np.fromiter(self._values, dtype=float)))

    def push(self, value: float) -> HampelVerdict:
        """Add ``value`` to the window and test it against the window's median."""
        self._values.append(float(value))
        values = np.fromiter(self._values, dtype=float)
        median = float(np.median(values))
        spread = max(MAD_TO_SIGMA * float(np.median(np.abs(values - median))), self.floor)
        judged = self.size >= MIN_JUDGED and len(values) >= MIN_JUDGED
        outlier = judged and abs(value - median) > self.k * spread
        return HampelVerdict(outlier=outlier, median=median, spread=spread, judged=judged)
