"""FAO/FAC baselines (baselines/fao.py): mechanism unit tests and the claim check of
Sagara et al. (JSME 1998) on its plant, steamtemp/SupercriticalFSH-v0."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import baselines
import steamtemp_gym  # noqa: F401  (registers the ids)
from baselines.fao import CENTRES, DH0_J_KG, F_GAINS, FAM, HALF_WIDTH, LABELS, fac_output

FSH = "steamtemp/SupercriticalFSH-v0"
SEEDS = range(5)
RAMP_START_S, EARLY_END_S = 1200.0, 2400.0  # ramp minute 20-30 and the 10 min after it


def test_sf_gains_of_eq4():
    np.testing.assert_allclose(F_GAINS, [6.0, 12.0, 8.0])


def test_fam_bank_holds_the_papers_rules_and_is_antisymmetric():
    ix = {s: i for i, s in enumerate(LABELS)}
    assert FAM[ix["ZE"], ix["LN"]] == ix["MN"]  # rule 1
    assert FAM[ix["LN"], ix["LN"]] == ix["LN"]  # rule 2
    assert FAM[ix["LP"], ix["LN"]] == ix["SP"]  # rule 3
    np.testing.assert_array_equal(FAM, 6 - FAM[::-1, ::-1])  # rule 4: the opposite signs
    assert FAM[ix["ZE"], ix["ZE"]] == ix["ZE"]


def _reference_fac(dta: float, dratio: float) -> float:
    """Eq. (12)-(13) evaluated directly: scikit-fuzzy memberships, the summed product-scaled
    output sets on a fine universe and skfuzzy's centroid."""
    skfuzzy = pytest.importorskip("skfuzzy")
    u_in = np.linspace(-1.0, 1.0, 2001)
    xi = np.linspace(-1.0 - HALF_WIDTH, 1.0 + HALF_WIDTH, 8001)
    sets = [skfuzzy.trimf(u_in, [c - HALF_WIDTH, c, c + HALF_WIDTH]) for c in CENTRES]
    out_sets = [skfuzzy.trimf(xi, [c - HALF_WIDTH, c, c + HALF_WIDTH]) for c in CENTRES]
    ga = [skfuzzy.interp_membership(u_in, s, np.clip(dta, -1, 1)) for s in sets]
    gr = [skfuzzy.interp_membership(u_in, s, np.clip(dratio, -1, 1)) for s in sets]
    agg = np.zeros_like(xi)
    for i in range(7):
        for j in range(7):
            agg += min(ga[i], gr[j]) * out_sets[FAM[i, j]]
    return float(skfuzzy.defuzz(xi, agg, "centroid"))


def test_fac_inference_matches_a_direct_reference():
    grid = np.linspace(-1.2, 1.2, 13)
    a, r = np.meshgrid(grid, grid, indexing="ij")
    fast = fac_output(a, r)
    ref = np.vectorize(_reference_fac)(a, r)
    np.testing.assert_allclose(fast, ref, atol=2e-4)  # discretization of the centroid
    assert fac_output(np.array(0.0), np.array(0.0)) == pytest.approx(0.0)
    assert fac_output(np.array(0.0), np.array(-1.0)) == pytest.approx(-2.0 / 3.0)  # (ZE,LN;MN)


def test_batched_predict_equals_single_rows_over_steps():
    env = gym.make(FSH, scenario="load_ramp_100_50")
    pol = baselines.make("fao_fac", env)
    envs = [gym.make(FSH, scenario="load_ramp_100_50") for _ in range(3)]
    obs = np.stack([e.reset(seed=s)[0] for s, e in enumerate(envs)])
    singles = [baselines.make("fao_fac", env) for _ in range(3)]
    start = np.ones(3, bool)
    for _ in range(40):
        a_b, _ = pol.predict(obs, episode_start=start)
        for i in range(3):
            a_i, _ = singles[i].predict(obs[i], episode_start=start[i : i + 1])
            np.testing.assert_allclose(a_b[i], a_i, atol=1e-12)
        obs = np.stack([e.step(a)[0] for e, a in zip(envs, a_b, strict=True)])
        start[:] = False


@pytest.fixture(scope="module")
def ramp_runs():
    """Per policy and seed on load_ramp_100_50: time, true outlet error, true and estimated Q."""
    env = gym.make(FSH, scenario="load_ramp_100_50")
    runs = {}
    for name in ("cascade_pi", "fao_sf", "fao_fac"):
        pol = baselines.make(name, env)
        for seed in SEEDS:
            obs, _ = env.reset(seed=seed)
            pol.reset()
            rec, start = [], True
            while True:
                a, _ = pol.predict(obs, episode_start=np.array([start]))
                start = False
                obs, _, term, trunc, info = env.step(a)
                q_hat = pol.comp[0][1].q_hat[0] * 1e-6 if name != "cascade_pi" else np.nan
                rec.append((info["time_s"], info["outlet_temp_C"] - info["setpoint_C"],
                            info["heat_absorption_MW"], q_hat))  # fmt: skip
                assert not term
                if trunc:
                    break
            runs[name, seed] = np.array(rec)
    return runs


def _early_peak(run: np.ndarray) -> float:
    w = (run[:, 0] >= RAMP_START_S) & (run[:, 0] <= EARLY_END_S)
    return float(np.abs(run[w, 1]).max())


def test_observer_tracks_the_true_heat_absorption(ramp_runs):
    """During the ramp (min 20-40) the estimate lags the true Q by about a minute (the Q ->
    measured-outlet path: tube metal, line, thermocouple, 5 s filter): measured max error
    7.7 % and rms 4.2 % of Q_0 (seed 0). Tolerance: max 12 %, rms 6 % of Q_0; once the load
    is held (min 40-60) the mean absolute error is within 3 % of Q_0."""
    q0 = 630.56 * DH0_J_KG * 1e-6  # M_0 (h_a0 - h_e0), MW
    for seed in SEEDS:
        r = ramp_runs["fao_sf", seed]
        err = (r[:, 3] - r[:, 2]) / q0
        ramp = (r[:, 0] >= RAMP_START_S) & (r[:, 0] <= EARLY_END_S)
        assert np.abs(err[ramp]).max() < 0.12
        assert np.sqrt(np.mean(err[ramp] ** 2)) < 0.06
        assert np.abs(err[r[:, 0] > EARLY_END_S]).mean() < 0.03


def test_claim_early_peak_ratios(ramp_runs):
    """Paper (section 5, Fig. 7): early peak deviation at 60 % (SF) and 33 % (SF + FC) of
    the uncompensated loop's. Measured here (peak |true outlet - setpoint| over min 20-40,
    ratio of the means over seeds 0-4 against cascade_pi): about 0.84 (SF) and 0.72
    (SF + FAC), see the module docstring. The ordering reproduces, the magnitudes do not.
    Tolerance +-0.06 (SF) and +-0.10 (FAC): about 2.5 standard errors of a 5-seed mean
    (per-seed spread 0.03 and 0.09)."""
    base = np.mean([_early_peak(ramp_runs["cascade_pi", s]) for s in SEEDS])
    sf = np.mean([_early_peak(ramp_runs["fao_sf", s]) for s in SEEDS]) / base
    fac = np.mean([_early_peak(ramp_runs["fao_fac", s]) for s in SEEDS]) / base
    print(f"early-peak ratios vs cascade_pi: SF {sf:.3f} (paper 0.60), "
          f"SF+FAC {fac:.3f} (paper 0.33)")  # fmt: skip
    assert fac < sf < 1.0
    assert sf == pytest.approx(0.84, abs=0.06)
    assert fac == pytest.approx(0.72, abs=0.10)
