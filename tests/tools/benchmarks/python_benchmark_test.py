"""Tests of tools/benchmarks/python_benchmark.py: the statistics that decide its verdicts (the
median's order-statistic interval, the verdict against a target) and the pose comparison. Nothing
is timed here."""

import math
import os
import pathlib
import sys

import numpy as np
import pytest

sys.path.insert(0, str(pathlib.Path(os.environ["PHOTOPOSE_SOURCE_DIR"]) / "tools" / "benchmarks"))
import python_benchmark as bench  # noqa: E402

# Sums of binomial coefficients are exact; the coverage is a quotient of them.
kCoverageTolerance = 1e-12


def test_interval_of_twenty_is_sixth_to_fifteenth():
    # n = 20: P(B <= 5) = (1 + 20 + 190 + 1140 + 4845 + 15504) / 2^20 = 21700 / 1048576, so
    # k = 6 covers 1 - 2 * 21700 / 2^20 = 0.9586; k = 7 would cover 1 - 2 * 60460 / 2^20 = 0.885.
    values = [float(v) for v in range(20, 0, -1)]  # unsorted on purpose
    median, low, high, coverage = bench.median_interval(values)
    assert median == 10.5
    assert (low, high) == (6.0, 15.0)
    assert coverage == pytest.approx(1.0 - 2.0 * 21700 / 2**20, abs=kCoverageTolerance)


def test_interval_of_fifteen_is_fourth_to_twelfth():
    # n = 15: P(B <= 3) = 576 / 32768 (k = 4 covers 0.965), P(B <= 4) = 1941 / 32768 (0.882).
    values = [10.0 * v for v in range(1, 16)]
    median, low, high, coverage = bench.median_interval(values)
    assert median == 80.0
    assert (low, high) == (40.0, 120.0)
    assert coverage == pytest.approx(1.0 - 2.0 * 576 / 32768, abs=kCoverageTolerance)


def test_too_few_values_give_the_whole_range_and_its_coverage():
    # n = 5: even the whole range covers only 1 - 2 / 32 < 95 %; the coverage says so.
    median, low, high, coverage = bench.median_interval([3.0, 1.0, 2.0, 5.0, 4.0])
    assert (median, low, high) == (3.0, 1.0, 5.0)
    assert coverage == pytest.approx(1.0 - 2.0 / 32, abs=kCoverageTolerance)
    assert coverage < bench.CONFIDENCE


def test_no_values_raise():
    with pytest.raises(ValueError, match="no values"):
        bench.median_interval([])


def test_binomial_cdf_is_exact():
    assert bench.binomial_half_cdf(0, 3) == 1 / 8
    assert bench.binomial_half_cdf(1, 3) == 4 / 8
    assert bench.binomial_half_cdf(3, 3) == 1.0
    assert bench.binomial_half_cdf(5, 20) == 21700 / 2**20


def test_verdict_needs_the_whole_interval():
    target = 0.05
    assert bench.verdict(0.97, 1.04, target) == "met"
    assert bench.verdict(0.97, 1.05, target) == "met"        # the target's bound included
    assert bench.verdict(0.99, 1.06, target) == "undecided"  # the median may be under it
    assert bench.verdict(1.051, 1.10, target) == "not met"
    assert bench.verdict(1.05, 1.10, target) == "undecided"


def test_pose_difference():
    a = np.arange(18, dtype=float).reshape(3, 6)
    assert bench.pose_difference(a, a.copy()) == 0.0
    b = a.copy()
    b[1, 4] += 2.5e-14
    assert bench.pose_difference(a, b) == pytest.approx(2.5e-14, rel=1e-3)
    # An image solved on one side only is never a small difference.
    c = a.copy()
    c[2] = np.nan
    assert math.isinf(bench.pose_difference(a, c))
    d = c.copy()
    assert bench.pose_difference(c, d) == 0.0
    assert math.isinf(bench.pose_difference(a, a[:2]))
    # Nothing solved on either side: no difference.
    e = np.full((2, 6), np.nan)
    assert bench.pose_difference(e, e.copy()) == 0.0
