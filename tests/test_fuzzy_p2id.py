"""Fuzzy P²ID (baselines/fuzzy_p2id.py): rule base vs scikit-fuzzy, the P+P+I mechanism, the
TSK scheduler, the knobs, and the paper's claims on BensonSubcritical-v0."""

from __future__ import annotations

import functools

import gymnasium as gym
import numpy as np
import pytest

from baselines import fuzzy_p2id as fp
from baselines.cascade_pi import CascadePI

BENSON = "steamtemp/BensonSubcritical-v0"
CLAIM_SCENARIOS = ("load_ramp_100_50", "load_ramp_50_100", "load_following")
SEEDS = (0, 1, 2, 3, 4)


def test_inference_matches_skfuzzy_control_system():
    """:func:`infer` against scikit-fuzzy's ControlSystem (the same sets and rules) on a
    23 x 23 grid over the input square. Tolerance 0.02 of the (0, 20) output: skfuzzy
    samples the aggregated set on its 61-point universe (plus the clip-level crossings),
    our centroid is exact; with a 601-point universe the gap falls to 1e-4."""
    from skfuzzy import control as ctrl

    g = np.linspace(0.0, 1.0, 23)
    x1, x2 = np.meshgrid(g, g, indexing="ij")
    sim = ctrl.ControlSystemSimulation(fp.control_system())
    sim.input["x1"], sim.input["x2"] = x1, x2
    sim.compute()
    ref = sim.output["u"]
    assert np.abs(fp.infer(x1, x2) - ref).max() < 0.02
    assert ref.min() < 2.0 and ref.max() > 18.0  # the rule base spans the output range


def test_surface_interpolation_matches_inference():
    """The per-step bilinear surface against the exact inference at random inputs
    (0.02 of the 0-20 output; the min/max kinks are what the grid smooths)."""
    f, _ = fp.surface()
    rng = np.random.default_rng(0)
    x1, x2 = rng.uniform(-1.0, 1.0, (2, 2000))
    exact = (fp.infer((1 + x1) / 2, (1 + x2) / 2) - 10.0) / 10.0
    assert np.abs(fp.evaluate_surface(f, x1, x2) - exact).max() * 10.0 < 0.02
    # inputs beyond the universe saturate
    big, one = np.array([5.0]), np.array([1.0])
    np.testing.assert_allclose(fp.evaluate_surface(f, big, big), fp.evaluate_surface(f, one, one))


def test_rule_base_is_odd_and_monotone_on_the_axes():
    """Odd, zero at the origin, increasing along each input through the origin. (Off the
    axes min-max-centroid surfaces have small dips, up to 0.0035 of the unit range here.)"""
    f, s0 = fp.surface()
    c = (fp.SURFACE_N - 1) // 2
    np.testing.assert_allclose(f, -f[::-1, ::-1], atol=1e-12)  # f(-x) = -f(x)
    assert abs(f[c, c]) < 1e-12
    assert (np.diff(f[:, c]) > 0).all() and (np.diff(f[c, :]) > 0).all()
    assert np.diff(f, axis=0).min() > -0.005
    assert 1.0 < s0 < 2.0


def test_tsk_scheduler():
    """Eq. 22-26: normalized firing, each rule dominant at its own load."""
    w = fp.tsk_weights(np.array(fp.RULE_LOADS + (0.6, 1.1)))
    np.testing.assert_allclose(w.sum(axis=1), 1.0)
    assert (np.diag(w[:3]) > 0.85).all()
    assert w[3, 0] > w[3, 1] > w[3, 2]


def _drive(policy, obs0: np.ndarray, errors: np.ndarray, i_err: int, scale: float):
    """Inner setpoint of the MAIN loop for a synthetic main-steam error sequence (K)."""
    out = []
    for k, e in enumerate(errors):
        obs = obs0.copy()
        obs[i_err] = e / scale
        policy.predict(obs, episode_start=np.array([k == 0]))
        out.append(policy.inner_setpoint[0, 1])
    return np.array(out)


def test_small_signal_is_p_plus_p_plus_i():
    """With (K_p, K_i, K_d) = (0.5, 1, 0) the P²ID is the SIMC PI for small errors: the
    FPI's integrated output gives K_p e + K_i int e / T0, the differenced FPD's the second
    K_p e. Driven by a 0.05 K sine the inner setpoint matches cascade_pi's within 8 %
    (measured 6 %: the surface is not additive, f(x, x) > f(x, 0) + f(0, x), and the
    bilinear slope in the first cell is 3 % below the exact one at the origin). With
    K_d > 0 the FPD adds a derivative action (leads the PI)."""
    env = gym.make(BENSON)
    obs0, _ = env.reset(seed=0)
    names = [s.name for s in env.unwrapped.signals.observation]
    i_err = names.index("error_K")
    scale = env.unwrapped.signals.observation[i_err].scale
    obs0[i_err] = 0.0
    t = np.arange(200) * env.unwrapped.plant.dt_s
    e = 0.05 * np.sin(2 * np.pi * t / 300.0)
    pi = _drive(CascadePI(env), obs0, e, i_err, scale)
    g = np.tile(np.array(fp.GAINS_PI), (2, 3, 1))
    fz = _drive(fp.FuzzyP2ID(env, gains=g), obs0, e, i_err, scale)
    dev_pi, dev_fz = pi - pi[0], fz - fz[0]
    assert np.abs(dev_fz - dev_pi).max() < 0.08 * np.abs(dev_pi).max()
    g[1, :, 2] = 0.5
    fd = _drive(fp.FuzzyP2ID(env, gains=g), obs0, e, i_err, scale) - fz[0]
    assert fd[1] > 3.0 * dev_fz[1] > 0.0  # the derivative kick of the rising error


def test_knobs_set_the_main_loop_rules_and_bad_knobs_are_refused():
    """``kp_L``/``ki_L``/``kd_L`` are the main-steam P²ID's gain set of rule L; the first
    stage keeps the SIMC-equivalent set; a bad knob is a ValueError."""
    env = gym.make(BENSON)
    p = fp.FuzzyP2ID(env, kp_50=2.0, ki_75=0.25, kd_100=0.3)
    main = [j for j in p.fuzzy if p.loops[j][1] == fp.MAIN]
    other = [j for j in p.fuzzy if j not in main]
    assert main and other
    np.testing.assert_allclose(p.gains[main[0], 0, 0], 2.0)
    np.testing.assert_allclose(p.gains[main[0], 1, 1], 0.25)
    np.testing.assert_allclose(p.gains[main[0], 2, 2], 0.3)
    np.testing.assert_array_equal(p.gains[other[0]], np.tile(fp.GAINS_PI, (3, 1)))
    for bad in ({"kp_60": 1.0}, {"kp_50": -1.0}, {"kd_75": float("nan")}):
        with pytest.raises(ValueError, match="knob|gains"):
            fp.FuzzyP2ID(env, **bad)


def _run(venv, policy, seeds) -> dict[str, np.ndarray]:
    """Per-row IAE (K s) and std (K) of the true outlet error, fuel (kg), spray (kg), trips."""
    obs, info = venv.reset(seed=list(seeds))
    policy.reset()
    sig = venv.unwrapped.signals.observation
    i_fuel = [s.name for s in sig].index("fuel_flow_kg_s")
    scale, center = sig[i_fuel].scale, sig[i_fuel].center
    n, dt = len(seeds), venv.unwrapped.plant.dt_s
    errs, fuel, spray, tripped = [], [], [], np.zeros(n, dtype=bool)
    start = np.ones(n, dtype=bool)
    while True:
        a, _ = policy.predict(obs, episode_start=start)
        start[:] = False
        obs, _, term, trunc, info = venv.step(a)
        tripped |= term
        errs.append(info["outlet_temp_C"] - info["setpoint_C"])
        fuel.append(obs[:, i_fuel] * scale + center)
        spray.append(info["spray_flow_kg_s"])
        if term.any() or trunc.any():
            break
    E = np.array(errs)
    return {
        "iae": np.abs(E).sum(axis=0) * dt,
        "std": E.std(axis=0),
        "fuel_kg": np.array(fuel).sum(axis=0) * dt,
        "spray_kg": np.array(spray).sum(axis=0) * dt,
        "tripped": tripped,
    }


@functools.lru_cache(maxsize=1)
def _claim() -> dict:
    """Per scenario and controller: the claim metrics over SEEDS on the native vector env."""
    out = {}
    for sc in CLAIM_SCENARIOS:
        for name, cls in (("fuzzy_p2id", fp.FuzzyP2ID), ("cascade_pi", CascadePI)):
            venv = gym.make_vec(
                BENSON, num_envs=len(SEEDS), vectorization_mode="vector_entry_point", scenario=sc
            )
            out[sc, name] = _run(venv, cls(venv), SEEDS)
    return out


def _ratios(scenario: str) -> tuple[float, float, float]:
    res = _claim()
    f, p = res[scenario, "fuzzy_p2id"], res[scenario, "cascade_pi"]
    assert not f["tripped"].any()
    return (
        f["iae"].mean() / p["iae"].mean(),
        f["std"].mean() / p["std"].mean(),
        f["fuel_kg"].mean() / p["fuel_kg"].mean(),
    )


#: Claim scenarios where the accuracy claim does not reproduce, with what was measured.
NOT_MORE_ACCURATE = {
    "load_ramp_100_50": (
        "measured: IAE ratio fuzzy_p2id / cascade_pi 1.031 (std ratio 0.859) on the 100 -> 50 % "
        "ramp with the gains the tuner chose under the commissioning checks on the corner "
        "plants (docs/baseline_tuning.md); the gains chosen without them gave 0.937"
    ),
}


@pytest.mark.parametrize(
    "scenario",
    [
        pytest.param(sc, marks=pytest.mark.xfail(strict=True, reason=NOT_MORE_ACCURATE[sc]))
        if sc in NOT_MORE_ACCURATE
        else sc
        for sc in CLAIM_SCENARIOS
    ],
)
def test_claim_more_accurate_and_less_fluctuation(scenario):
    """The paper: the P²ID is "more accurate and [has] less fluctuation" than the classic
    controller: a smaller IAE and a smaller std of the outlet temperature error than
    cascade_pi's on 50-100 % load changes (5 seeds, means)."""
    iae_ratio, std_ratio, _ = _ratios(scenario)
    assert iae_ratio < 1.0 and std_ratio < 1.0


@pytest.mark.xfail(
    strict=True,
    reason=(
        "measured: fuel ratio fuzzy_p2id / cascade_pi 1.0000 +- 1e-4 on the three load changes "
        "(BensonSubcritical's fuel follows the load demand through its fuel/water-ratio "
        "schedule; the spray loops hardly move it)"
    ),
)
def test_claim_less_fuel():
    """The paper: the P²ID also needs less fuel than the classic controller (5 seeds, means;
    at least 0.05 % less on every load change)."""
    for sc in CLAIM_SCENARIOS:
        assert _ratios(sc)[2] < 1.0 - 5e-4


@pytest.mark.parametrize("scenario", CLAIM_SCENARIOS)
def test_pin_claim_ratios(scenario):
    """Pins of the measured IAE and std ratios (+-0.05; the 5-seed means are deterministic),
    so a change that moves them shows."""
    iae_ratio, std_ratio, _ = _ratios(scenario)
    exp_iae, exp_std = MEASURED[scenario]
    assert iae_ratio == pytest.approx(exp_iae, abs=0.05)
    assert std_ratio == pytest.approx(exp_std, abs=0.05)


#: (IAE ratio, std ratio) fuzzy_p2id / cascade_pi measured on the claim scenarios.
MEASURED = {
    "load_ramp_100_50": (1.031, 0.859),
    "load_ramp_50_100": (0.798, 0.841),
    "load_following": (0.877, 0.895),
}
