"""agents/stats.py: IQM, stratified bootstrap, probability of improvement, performance
profiles, normalization and ranks, on hand-computable cases and against the plain
percentile bootstrap."""

from __future__ import annotations

import numpy as np
import pytest

from agents import stats


def test_iqm_is_the_mean_of_the_middle_half():
    assert stats.iqm(np.arange(8.0)) == pytest.approx(np.mean([2, 3, 4, 5]))
    assert stats.iqm(np.array([0.0, 1, 1, 1, 1, 1, 1, 100])) == pytest.approx(1.0)


def test_two_runs_bootstrap_mean_spans_both():
    """Mean of two resampled values of {0, 1}: 0 (1/4), 0.5 (1/2), 1 (1/4)."""
    point, lo, hi = stats.stratified_bootstrap_ci([np.array([0.0, 1.0])], stats.mean)
    assert (point, lo, hi) == (0.5, 0.0, 1.0)


def test_constant_scores_give_a_zero_width_interval():
    assert stats.stratified_bootstrap_ci([np.full(5, 3.0), np.full(2, 3.0)]) == (3.0, 3.0, 3.0)


def test_stratification_keeps_every_task_in_every_replicate():
    """Task A all 0, task B all 1, three runs each: every stratified replicate holds three
    of each (mean exactly 0.5); the pooled bootstrap mixes them (a wide interval)."""
    tasks = [np.zeros(3), np.ones(3)]
    assert stats.stratified_bootstrap_ci(tasks, stats.mean) == (0.5, 0.5, 0.5)
    _, lo, hi = stats.percentile_bootstrap_ci(np.concatenate(tasks), stats.mean)
    assert lo < 0.3 and hi > 0.7


def test_one_task_equals_the_plain_percentile_bootstrap():
    x = np.random.default_rng(1).normal(size=20)
    for f in (stats.mean, stats.iqm):
        assert stats.stratified_bootstrap_ci([x], f, seed=4) == stats.percentile_bootstrap_ci(
            x, f, seed=4
        )


def test_mean_interval_matches_the_normal_approximation():
    x = np.random.default_rng(2).normal(10.0, 2.0, size=400)
    point, lo, hi = stats.stratified_bootstrap_ci([x], stats.mean, n_boot=4000)
    half = 1.96 * x.std() / np.sqrt(x.size)
    assert point == pytest.approx(x.mean())
    assert lo == pytest.approx(point - half, abs=0.15 * half)
    assert hi == pytest.approx(point + half, abs=0.15 * half)


def test_probability_of_improvement_hand_computed():
    # task 1: X {1, 2} vs Y {0, 3}: 2 of 4 pairs -> 0.5; task 2: X {5} vs Y {5}: a tie -> 0.5
    # task 3: X {2} vs Y {1, 1}: 1.0  => mean 2 / 3
    x = [np.array([1.0, 2.0]), np.array([5.0]), np.array([2.0])]
    y = [np.array([0.0, 3.0]), np.array([5.0]), np.array([1.0, 1.0])]
    point, lo, hi = stats.probability_of_improvement(x, y)
    assert point == pytest.approx(2 / 3)
    assert lo <= point <= hi
    # task 2 and 3 cannot vary under resampling; task 1 ranges over {0, 1/4, ..., 1}
    assert lo == pytest.approx((0 + 0.5 + 1) / 3) and hi == pytest.approx((1 + 0.5 + 1) / 3)
    assert stats.probability_of_improvement(y, x)[0] == pytest.approx(1 - 2 / 3)


def test_performance_profile_averages_tasks():
    scores = [np.array([0.0, 1.0]), np.array([1.0, 1.0, 1.0, 0.0])]
    prof = stats.performance_profile(scores, np.array([-1.0, 0.5, 1.0]))
    np.testing.assert_allclose(prof, [1.0, (0.5 + 0.75) / 2, 0.0])


def test_normalize_and_small_headroom():
    np.testing.assert_allclose(
        stats.normalize(np.array([-100.0, -50.0, -10.0]), -100.0, -10.0), [0.0, 50 / 90, 1.0]
    )
    # headroom below MIN_SPAN of the reference's cost: the scale is held at MIN_SPAN |R0|
    span = stats.MIN_SPAN * 100.0
    assert stats.score_span(-100.0, -99.0) == pytest.approx(span)
    np.testing.assert_allclose(
        stats.normalize(np.array([-99.0, -110.0]), -100.0, -99.0), [1.0 / span, -10.0 / span]
    )
    assert stats.score_span(-100.0, -120.0) == pytest.approx(span)  # an oracle that lost
    with pytest.raises(ValueError, match="finite"):
        stats.score_span(-100.0, float("nan"))


def test_ranks_share_ties():
    assert stats.ranks({"a": 0.5, "b": 0.9, "c": 0.5, "d": 0.1}) == {"b": 1, "a": 2, "c": 2, "d": 4}


def test_bad_input_is_a_value_error():
    with pytest.raises(ValueError, match="empty"):
        stats.stratified_bootstrap_ci([np.array([])])
    with pytest.raises(ValueError, match="finite"):
        stats.stratified_bootstrap_ci([np.array([np.nan])])
    with pytest.raises(ValueError, match="tasks"):
        stats.probability_of_improvement([np.ones(2)], [np.ones(2), np.ones(2)])
