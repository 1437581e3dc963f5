"""experiments.first_frame's comparison of two keypoint modes (no timing asserted: made-up runs)."""
from __future__ import annotations

import pytest

from experiments.first_frame import mode_ratios


def test_two_modes_are_compared_best_over_best_and_run_by_run():
    first = [{"first_row_s": s} for s in (3.6, 3.5, 5.0)]        # the third run met a busy machine...
    second = [{"first_row_s": s} for s in (2.9, 2.5, 4.0)]       # ...as the second mode's third did
    best, median, low, high = mode_ratios(first, second)
    assert best == pytest.approx(3.5 / 2.5)
    assert (low, median, high) == pytest.approx((3.6 / 2.9, 5.0 / 4.0, 3.5 / 2.5))
    with pytest.raises(ValueError, match="as many runs"):
        mode_ratios(first, second[:2])
