"""FAO/FAC baselines (baselines/fao.py): mechanism unit tests and the claims of Sagara et al.
1998 on its plant, steamtemp/SupercriticalFSH-v0.

The paper's test (section 5, Fig. 7): load 100 -> 50 % at 5 %/min from minute 20 to 30
(``load_ramp_100_50``); "the deviation in the outlet steam temperature that appeared in
the early period of load change is suppressed to 60 % by delay compensation and to 33 % by
the combination of delay and disturbance compensations compared with that of no
compensations". The uncompensated case is the unchanged conventional loop, cascade_pi.
Two readings of "the early period" are measured, on the true outlet temperature, as the
ratio of the 8-seed means of the peak |outlet - setpoint|:

- early excursion: from the ramp start to the first sign change of the error after the
  ramp end (the deviation the load change causes);
- whole window: minutes 20-40 (the ramp and the 10 min after it, so also the undershoot
  after the ramp).

Tolerance of the paper's numbers: +-0.10 (the paper states rounded percentages read off
its Fig. 7; the 8-seed means' standard errors here are 0.01-0.04).
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import baselines
import steamtemp_gym  # noqa: F401  (registers the ids)
from agents.evaluation import run_batch
from baselines.cascade_pi import inner_schedule
from baselines.fao import F_GAINS, KK1, KK2, FaoFAC, FaoSF
from baselines.fao_fuzzy import CENTRES, FAM, HALF_WIDTH, LABELS, fac_output
from baselines.fao_observer import DH0_J_KG, fsh_unit_K
from steamtemp_gym.scenarios import Scenario
from steamtemp_gym.steam import h_pT

FSH = "steamtemp/SupercriticalFSH-v0"
SEEDS = range(8)
RAMP_START_S, RAMP_END_S, WINDOW_END_S = 1200.0, 1800.0, 2400.0
PAPER_RATIO = {"fao_sf": 0.60, "fao_fac": 0.33}
PAPER_TOL = 0.10


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
    """Per policy: time (steps,), true outlet error, true and estimated Q (MW) (steps, seeds)
    on load_ramp_100_50, seeds SEEDS in one vector env; valve travel and quiet p2p."""
    n = len(SEEDS)
    venv = gym.make_vec(
        FSH, num_envs=n, vectorization_mode="vector_entry_point", scenario="load_ramp_100_50"
    )
    runs = {}
    for name in ("cascade_pi", "cascade_pi_ff", "fao_sf", "fao_fac"):
        pol = baselines.make(name, venv)
        obs, _ = venv.reset(seed=list(SEEDS))
        pol.reset()
        t, e, q, q_hat, start = [], [], [], [], np.ones(n, bool)
        while True:
            a, _ = pol.predict(obs, episode_start=start)
            start[:] = False
            obs, _, term, trunc, info = venv.step(a)
            t.append(info["time_s"][0])
            e.append(info["outlet_temp_C"] - info["setpoint_C"])
            q.append(info["heat_absorption_MW"])
            q_hat.append(pol.comp[0][1].q_hat * 1e-6 if name.startswith("fao") else q[-1])
            assert not term.any()
            if trunc.all():
                break
        runs[name] = (np.array(t), np.array(e), np.array(q), np.array(q_hat))
        runs[name, "metrics"] = [r["metrics"] for r in run_batch(venv, pol, list(SEEDS))]
    return runs


def _peaks(run, window: str) -> np.ndarray:
    """Peak |error| per seed over the early excursion or the whole window (module doc)."""
    t, e = run[0], run[1]
    out = []
    for k in range(e.shape[1]):
        if window == "whole":
            end = WINDOW_END_S
        else:
            sign = np.sign(e[np.searchsorted(t, RAMP_END_S), k])
            later = np.flatnonzero((t > RAMP_END_S) & (np.sign(e[:, k]) != sign))
            end = t[later[0]] if len(later) else WINDOW_END_S
        w = (t >= RAMP_START_S) & (t <= end)
        out.append(np.abs(e[w, k]).max())
    return np.array(out)


def _ratio(runs, name: str, window: str) -> float:
    return float(_peaks(runs[name], window).mean() / _peaks(runs["cascade_pi"], window).mean())


def test_claim_observer_estimates_the_heat_absorption(ramp_runs):
    """The FAO estimates the unmeasured heat absorption (sections 3.2, 6). During the ramp
    (min 20-40) the estimate lags the true Q by about a minute (the Q -> measured-outlet
    path: tube metal, line, thermocouple, 5 s filter): measured max error 7.7 % and rms
    4.2 % of Q_0 (seed 0). Tolerance: max 12 %, rms 6 % of Q_0; once the load is held
    (min 40-60) the mean absolute error is within 3 % of Q_0."""
    q0 = 630.56 * DH0_J_KG * 1e-6  # M_0 (h_a0 - h_e0), MW
    t, _, q, q_hat = ramp_runs["fao_sf"]
    err = (q_hat - q) / q0
    ramp = (t >= RAMP_START_S) & (t <= WINDOW_END_S)
    assert np.abs(err[ramp]).max() < 0.12
    assert np.sqrt(np.mean(err[ramp] ** 2, axis=0)).max() < 0.06
    assert np.abs(err[t > WINDOW_END_S]).mean(axis=0).max() < 0.03


def test_claim_each_compensation_lowers_the_early_deviation(ramp_runs):
    """SF below the uncompensated loop, SF + FAC below SF, in both readings (measured
    early excursion 0.92 / 0.74, whole window 0.89 / 0.70)."""
    for window in ("early", "whole"):
        sf, fac = _ratio(ramp_runs, "fao_sf", window), _ratio(ramp_runs, "fao_fac", window)
        assert fac < sf < 1.0, (window, sf, fac)


_NOT = {
    ("fao_sf", "early"): "measured 0.92 (seeds 0-7) against the paper's 0.60",
    ("fao_sf", "whole"): "measured 0.89 (seeds 0-7) against the paper's 0.60",
    ("fao_fac", "early"): "measured 0.74 (seeds 0-7) against the paper's 0.33",
    ("fao_fac", "whole"): "measured 0.70 (seeds 0-7) against the paper's 0.33",
}


@pytest.mark.parametrize("window", ["early", "whole"])
@pytest.mark.parametrize("name", ["fao_sf", "fao_fac"])
def test_claim_peak_deviation_ratio(ramp_runs, name, window, request):
    """SF to 60 % and SF + FAC to 33 % of the uncompensated peak deviation (+-0.10)."""
    request.applymarker(pytest.mark.xfail(strict=True, reason=_NOT[name, window]))
    ratio = _ratio(ramp_runs, name, window)
    print(f"{name} {window}: {ratio:.3f} (paper {PAPER_RATIO[name]})")
    assert ratio == pytest.approx(PAPER_RATIO[name], abs=PAPER_TOL)


def test_pin_peak_deviation_ratios(ramp_runs):
    """Regression pin of the measured ratios (seeds 0-7): early excursion SF 0.915, SF + FAC
    0.736; whole window 0.888, 0.698. Tolerance about 3 standard errors of the 8-seed mean
    (spread of the per-seed ratios 0.014 / 0.044 SF, 0.10 / 0.11 SF + FAC)."""
    got = {
        (n, w): _ratio(ramp_runs, n, w) for n in ("fao_sf", "fao_fac") for w in ("early", "whole")
    }
    assert got["fao_sf", "early"] == pytest.approx(0.915, abs=0.02)
    assert got["fao_sf", "whole"] == pytest.approx(0.888, abs=0.05)
    assert got["fao_fac", "early"] == pytest.approx(0.736, abs=0.11)
    assert got["fao_fac", "whole"] == pytest.approx(0.698, abs=0.12)


def test_realism_on_the_papers_ramp(ramp_runs):
    """Valve travel within 3x cascade_pi_ff's, quiet p2p within max(2x, 1.5 K), no trip."""
    ref = ramp_runs["cascade_pi_ff", "metrics"]
    for name in ("fao_sf", "fao_fac"):
        for m, f in zip(ramp_runs[name, "metrics"], ref, strict=True):
            assert m["tripped"] == 0.0
            assert m["valve_travel"] <= 3.0 * f["valve_travel"], name
            assert m["quiet_p2p_K"] <= max(2.0 * f["quiet_p2p_K"], 1.5), name


def test_claim_compensation_is_zero_at_nominal_operation():
    """Section 3.2: deviations from the nominal values are fed back "so that the
    compensator output is zero at nominal operation": in the undisturbed steady state at
    100, 75 and 50 % load (no noise) the bias stays within 0.05 K over 200 s."""
    for load in (1.0, 0.75, 0.5):
        env = gym.make(FSH, scenario=Scenario(name="steady", duration_s=200.0, load=((0.0, load),)))
        pol = FaoFAC(env)
        obs, _ = env.reset(seed=0)
        start = True
        for _ in range(100):
            a, _ = pol.predict(obs, episode_start=np.array([start]))
            start = False
            assert np.abs(pol.bias).max() < 0.05, (load, pol.bias)
            obs, *_ = env.step(a)


def test_unit_conversion_moves_the_inlet_enthalpy_by_one_normalized_unit():
    """One normalized unit of bias (h_a0 - h_e0 = 217.8 kJ/kg on the FSH inlet, eq. 2 and
    9) as kelvin of the attemperator outlet: a change of 0.01 unit of the inner setpoint
    in the plant's undisturbed steady state moves the inlet enthalpy by 2.178 kJ/kg (+-1 %)
    at 100 and 50 % load (63 and 80 K per unit: not the FSH's average 68.5 K)."""
    u3, unit = fsh_unit_K(FSH, "{}")
    loads, T_in = inner_schedule(FSH, "{}", "attemp_out_temp_meas_C")
    p = inner_schedule(FSH, "{}", "pressure_MPa")[1] * 1e6
    for load in (1.0, 0.5):
        k = int(np.argmin(np.abs(loads - load)))
        T = T_in[k] + 273.15
        dh = h_pT(p[k], T + 0.01 * unit[k]) - h_pT(p[k], T)
        assert dh == pytest.approx(0.01 * DH0_J_KG, rel=0.01)
    assert unit[np.argmin(np.abs(loads - 0.5))] > 1.1 * 68.5


def test_knobs_scale_the_compensations_and_bad_values_raise():
    env = gym.make(FSH, scenario="load_ramp_100_50")
    assert [k.name for k in FaoFAC.KNOBS] == ["kk1", "kk2"]
    assert [k.name for k in FaoSF.KNOBS] == ["kk2"]
    default = FaoFAC(env)
    assert (default.kk1, default.kk2) == (KK1, KK2)
    obs, _ = env.reset(seed=0)
    biases = []
    for kw in (
        {"sf": False},
        {"sf": False, "kk1": 2 * KK1},
        {"fuzzy": False},
        {"fuzzy": False, "kk2": 2 * KK2},
    ):
        pol = FaoFAC(env, **kw)
        o = obs.copy()
        for k in range(30):
            pol.predict(o, episode_start=np.array([k == 0]))
            o = o + 0.002  # a drifting observation: nonzero compensations
        biases.append(pol.bias[0, 0])
    assert biases[0] != 0.0 and biases[2] != 0.0
    assert biases[1] == pytest.approx(2 * biases[0], rel=1e-9)
    assert biases[3] == pytest.approx(2 * biases[2], rel=1e-9)
    for bad in (float("nan"), -0.1, 0.0, "x"):
        with pytest.raises(ValueError, match="kk1"):
            FaoFAC(env, kk1=bad)
