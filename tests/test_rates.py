"""The statistics behind hz/bw/delay: exact for large values (a delay against a zero stamp is ~1.8e9 s)."""

from __future__ import annotations

import statistics

import pytest

from rostool.graph.rates import RunningStats


@pytest.mark.parametrize("window", [None, 20])
def test_std_dev_of_large_values(window: int | None) -> None:
    values = [1_795_320_964.39 + i * 0.05 for i in range(55)]
    stats = RunningStats(window)
    for value in values:
        stats.add(value)
    summary = stats.summary()
    assert summary is not None
    kept = values[-window:] if window else values
    assert summary.std_dev == pytest.approx(statistics.pstdev(kept), rel=1e-6)
    assert summary.mean == pytest.approx(statistics.fmean(kept), abs=1e-5)
    assert (summary.minimum, summary.maximum, summary.count) == (min(kept), max(kept), len(kept))
