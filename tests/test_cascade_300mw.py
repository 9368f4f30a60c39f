"""Validation of steamtemp/Cascade300MW-v0 against Zhang et al. 2012.

The plant is the paper's pair -2.01/(1+16 s)^2 (spray -> intermediate) and
2.09/(1+22.3 s)^4 (intermediate -> outlet) at 1 s sampling. Analytic step
characteristics of K/(1+Ts)^n are the analytic values (TABLE, to 3 digits);
those of the series are computed here from the exact continuous response.
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from scipy import optimize, signal

import steamtemp_gym  # noqa: F401  (registers the ids)
from steamtemp_gym import scenarios
from steamtemp_gym.metrics import step_response_metrics
from steamtemp_gym.plants import make
from steamtemp_gym.plants.cascade_300mw import IX, CascadeParams

ID = "steamtemp/Cascade300MW-v0"
# analytic (Tu/T, Tg/T, t90/T) of K/(1+Ts)^n: Tu from the inflection tangent, Tg balance time
TABLE = {2: (0.282, 2.718, 3.890), 4: (1.425, 4.463, 6.681)}
QUIET = {"omega_halfwidth_K": 0.0, "omega2_scale_kg_s": 0.0}
N_STEPS = 3000  # 3000 s: every response settled to < 1e-6 of its gain


def simulate(plant, load=1.0, dv=0.0, bias=0.0, spray_dT=0.0, n=N_STEPS):
    """Steady state at ``load``, then at t = 0 a valve step dv and/or disturbance steps.

    Returns (t, outlet, intermediate, valve) sampled at 0, 1, ..., n periods.
    """
    D = np.array([[load, 0.0, 0.0, 1.0, 0.0]])
    X = np.zeros((1, plant.n_x))
    Z = np.zeros((1, plant.n_z))
    plant.steady_state(D, np.array([plant.setpoint_C]), X)
    plant.kernel()(X, X[:, [IX.V]].copy(), D, plant.P, plant.jrow, plant.jcol, 0.0, 1, Z)
    U = X[:, [IX.V]] + dv
    D[0, 2], D[0, 4] = bias, spray_dT
    out = [Z[0].copy()]
    for _ in range(n):
        plant.step(X, U, D, Z)
        out.append(Z[0].copy())
    z = np.array(out)
    idx = plant.index
    t = np.arange(n + 1) * plant.dt_s
    return t, z[:, idx["outlet_temp_C"]], z[:, idx["intermediate_temp_C"]], z[:, idx["spray_valve"]]


def residues(poles):
    """Partial fractions of 1 / prod (s - p)^m: [(p, j, c)] with c the coefficient of 1/(s - p)^j.

    c = a_(m - j), a_k the Taylor coefficients at p of prod_(q != p) (s - q)^(-m_q), from
    (p - q + d)^(-m) = (p - q)^(-m) sum_k (-1)^k C(m + k - 1, k) (d / (p - q))^k. Elementwise
    arithmetic only (no matrix exponential, no BLAS).
    """
    out = []
    for p, m in poles:
        a = np.zeros(m)
        a[0] = 1.0
        for q, mq in poles:
            if q == p:
                continue
            series = np.array(
                [(-1) ** k * math.comb(mq + k - 1, k) * (p - q) ** (-mq - k) for k in range(m)]
            )
            a = np.convolve(a, series)[:m]
        out += [(p, j, a[m - j]) for j in range(1, m + 1)]
    return out


def inverse_laplace(terms, t, deriv=0):
    """f(t) (deriv 0) or f'(t) (deriv 1) of sum c / (s - p)^j: c t^(j-1) e^(pt) / (j-1)!."""
    t = np.asarray(t, dtype=float)
    f = np.zeros_like(t)
    for p, j, c in terms:
        g = t ** (j - 1) / math.factorial(j - 1)
        if deriv:
            g = p * g + (t ** (j - 2) / math.factorial(j - 2) if j > 1 else 0.0)
        f = f + c * g * np.exp(p * t)
    return f


def analytic_metrics(sections):
    """Exact gain, Tu, Tg, t90 of a series of lags K/(1+Ts)^n, sections = [(K, T, n), ...]."""
    gain = float(np.prod([K for K, _, _ in sections]))
    poles = [(-1.0 / T, n) for _, T, n in sections]
    scale = 1.0 / float(np.prod([T**n for _, T, n in sections]))  # normalized: unit gain
    h_terms = [(p, j, c * scale) for p, j, c in residues(poles)]
    y_terms = [(p, j, c * scale) for p, j, c in residues(poles + [(0.0, 1)])]
    mean_time = sum(n * T for _, T, n in sections)  # the impulse peak lies before it
    grid = np.linspace(1e-3 * mean_time, mean_time, 400)
    dh = inverse_laplace(h_terms, grid, deriv=1)
    k = int(np.flatnonzero((dh[:-1] > 0) & (dh[1:] <= 0))[0])
    ti = optimize.brentq(lambda t: float(inverse_laplace(h_terms, t, 1)), grid[k], grid[k + 1])
    slope = float(inverse_laplace(h_terms, ti))
    return {
        "gain": gain,
        "Tu_s": ti - float(inverse_laplace(y_terms, ti)) / slope,
        "Tg_s": 1.0 / slope,
        "t90_s": optimize.brentq(
            lambda t: float(inverse_laplace(y_terms, t)) - 0.9, 1e-3, 5.0 * mean_time, xtol=1e-12
        ),
    }


@pytest.fixture(scope="module")
def plant():
    return make(ID, **QUIET)


# ------------------------------------------------------------------ step metrics
def test_analytic_helper_reproduces_reference_table():
    for n, (tu, tg, t90) in TABLE.items():
        m = analytic_metrics([(1.0, 1.0, n)])
        assert m["Tu_s"] == pytest.approx(tu, abs=6e-4)
        assert m["Tg_s"] == pytest.approx(tg, abs=6e-4)
        assert m["t90_s"] == pytest.approx(t90, abs=6e-4)


@pytest.mark.parametrize("section", ["leading", "inertia", "series"])
def test_step_metrics_within_1pct(plant, section):
    dv, r = 0.1, 0.05
    w_max = plant.params.spray_max_kg_s
    cq = plant.params.ht_rise_K / plant.params.inertia_gain  # K at the inertia input per unit r
    if section == "leading":
        t, _, y, _ = simulate(plant, dv=dv)
        unit, ref = dv * w_max, [(-2.01, 16.0, 2)]
        published = (-2.01, *(x * 16.0 for x in TABLE[2]))
    elif section == "inertia":  # heat-absorption step enters at the inertia-section input
        t, y, _, _ = simulate(plant, bias=r)
        unit, ref = r * cq, [(2.09, 22.3, 4)]
        published = (2.09, *(x * 22.3 for x in TABLE[4]))
    else:
        t, y, _, _ = simulate(plant, dv=dv)
        unit, ref = dv * w_max, [(-2.01, 16.0, 2), (2.09, 22.3, 4)]
        published = None
    m = step_response_metrics(t, y)
    exact = analytic_metrics(ref)
    assert m["gain"] / unit == pytest.approx(exact["gain"], rel=1e-6)
    for key in ("Tu_s", "Tg_s", "t90_s"):
        assert m[key] == pytest.approx(exact[key], rel=0.01), key
    if published is not None:  # the analytic values of TABLE (3 digits)
        for got, want in zip(
            (m["gain"] / unit, m["Tu_s"], m["Tg_s"], m["t90_s"]), published, strict=True
        ):
            assert got == pytest.approx(want, rel=0.01)


def test_zoh_exact_at_sample_instants(plant):
    dv = 0.1
    t, y, yi, v = simulate(plant, dv=dv, n=800)
    u = dv * plant.params.spray_max_kg_s
    lead = signal.ZerosPolesGain([], [-1 / 16.0] * 2, -2.01 * u / 16.0**2)
    series = signal.ZerosPolesGain(
        [], [-1 / 16.0] * 2 + [-1 / 22.3] * 4, -2.01 * 2.09 * u / (16.0**2 * 22.3**4)
    )
    _, ref_i = signal.step(lead, T=t)
    _, ref = signal.step(series, T=t)
    np.testing.assert_allclose(yi - yi[0], ref_i, rtol=0, atol=1e-10)
    np.testing.assert_allclose(y - y[0], ref, rtol=0, atol=1e-10)
    assert np.all(v[1:] == pytest.approx(v[0] + dv))


# --------------------------------------------------------------- load dependence
def test_load_table_monotone_and_paper_pair_at_full_load():
    p = CascadeParams()
    assert p.section_model(1.0) == (-2.01, 16.0, 2.09, 22.3)
    loads = np.linspace(1.1, 0.3, 17)
    rows = np.array([p.section_model(L) for L in loads])
    k2, t2, k1, t1 = np.abs(rows).T
    for col in (k2, t2, t1):
        assert np.all(np.diff(col) > 0)  # strictly growing as load falls
    assert np.all(np.diff(k1) >= 0)
    # observed trend of superheaters: spray-to-outlet gain and time constants ~ 1/load
    K2, T2, K1, T1 = p.section_model(0.37)
    assert abs(K2 * K1) / (2.01 * 2.09) == pytest.approx(1 / 0.37, rel=1e-9)
    assert T1 / 22.3 == pytest.approx(1 / 0.37, rel=1e-9)
    fixed = CascadeParams(load_dependent=False)
    assert fixed.section_model(0.5) == (-2.01, 16.0, 2.09, 22.3)


def test_load_dependent_kernel_matches_table(plant):
    """At the 50 % grid load the kernel is the exact ZOH of the table's transfer functions."""
    dv = 0.05
    u = dv * plant.params.spray_max_kg_s
    prev = None
    for load in (1.0, 0.75, 0.5):
        t, y, _, _ = simulate(plant, load=load, dv=dv)
        K2, T2, K1, T1 = plant.params.section_model(load)
        ref = signal.ZerosPolesGain(
            [], [-1 / T2] * 2 + [-1 / T1] * 4, K2 * K1 * u / (T2**2 * T1**4)
        )
        _, yref = signal.step(ref, T=t[:600])
        np.testing.assert_allclose(y[:600] - y[0], yref, rtol=0, atol=1e-8)
        m = step_response_metrics(t, y)
        if prev is not None:
            assert abs(m["gain"]) > abs(prev["gain"]) and m["t90_s"] > prev["t90_s"]
        prev = m
    fixed = make(ID, load_dependent=False, **QUIET)
    t, y, _, _ = simulate(fixed, load=0.5, dv=dv)
    m = step_response_metrics(t, y)
    assert m["gain"] / u == pytest.approx(-2.01 * 2.09, rel=1e-6)


# --------------------------------------------------------- steady state, disturbances
def test_steady_state_holds_setpoint_valve_inside():
    plant = make(ID, **QUIET)
    grid = np.array(np.meshgrid((0.5, 0.75, 1.0), (-0.08, 0.0, 0.08), (0.85, 1.15), (-15.0, 15.0)))
    L, b, f, dT = grid.reshape(4, -1)
    D = np.column_stack([L, np.zeros_like(L), b, f, dT])
    X = np.zeros((len(D), plant.n_x))
    Z = np.zeros((len(D), plant.n_z))
    sp = np.full(len(D), 535.0)
    plant.steady_state(D, sp, X)
    U = X[:, [IX.V]].copy()
    assert np.all((U > 0.0) & (U < 1.0))
    for _ in range(50):
        plant.step(X, U, D, Z)  # an equilibrium: nothing moves
    np.testing.assert_allclose(Z[:, plant.index["outlet_temp_C"]], 535.0, atol=1e-9)
    r = (1 + D[:, 2]) * D[:, 3] - 1  # relative heat absorption: y_i compensates it
    np.testing.assert_allclose(
        Z[:, plant.index["intermediate_temp_C"]] - 470.0, -65.0 / 2.09 * r, atol=1e-9
    )


def test_disturbance_mapping(plant):
    # heat absorption: outer input, moves the outlet by ht_rise_K * r, not the intermediate
    t, y, yi, _ = simulate(plant, bias=0.04, n=1500)
    assert y[-1] - y[0] == pytest.approx(65.0 * 0.04, rel=1e-6)
    assert np.ptp(yi) == 0.0
    # warmer spray water: inner input, the intermediate temperature rises first
    t, y, yi, v = simulate(plant, spray_dT=15.0, n=1500)
    p = plant.params
    from steamtemp_gym.steam import cp_pT, h_pT

    P, Tw = p.attemp_pressure_MPa * 1e6, p.spray_water_temp_C + 273.15
    c_sw = cp_pT(P, Tw) / (h_pT(P, 470.0 + 273.15) - h_pT(P, Tw))
    du = -v[0] * p.spray_max_kg_s * c_sw * 15.0
    assert yi[-1] - yi[0] == pytest.approx(-2.01 * du, rel=1e-6)
    assert y[-1] - y[0] == pytest.approx(-2.01 * 2.09 * du, rel=1e-6)
    assert 0.3 < y[-1] - y[0] < 1.5  # a fraction of a kelvin per 10 K: physically small
    assert yi[20] - yi[0] > 5 * (y[20] - y[0])  # inner loop sees it first


def run_rows(plant, D, n, keys):
    X = np.zeros((len(D), plant.n_x))
    Z = np.zeros((len(D), plant.n_z))
    plant.seed_rows(X, np.asarray(keys, dtype=np.uint64))
    plant.steady_state(D, np.full(len(D), 535.0), X)
    U = X[:, [IX.V]].copy()
    om = np.empty((n, len(D), 2))
    for k in range(n):
        plant.step(X, U, D, Z)
        om[k] = Z[:, [plant.index["omega_K"], plant.index["omega2_kg_s"]]]
    return X, om


def test_nongaussian_disturbances_statistics_and_determinism():
    plant = make(ID)
    a, b = plant.params.omega_halfwidth_K, plant.params.omega2_scale_kg_s
    tau = plant.params.omega_corr_time_s
    D = np.array([[1.0, 0, 0, 1, 0], [0.8, 0, 0, 1, 0], [1.0, 0, 0.02, 1, 0], [0.6, 0, 0, 1, 3.0]])
    X, om = run_rows(plant, D, 25000, [11, 12, 13, 14])
    # many independent episodes for the marginal of the coloured omega
    _, many = run_rows(plant, np.repeat(D[:1], 200, axis=0), 3000, np.arange(200))
    w, w2 = many[..., 0], om[..., 1].ravel()
    n = w2.size
    assert np.all(np.abs(w) <= a) and np.all(w2 >= -b)
    assert abs(w.mean()) < 0.05 * a and abs(w2.mean()) < 4 * b / np.sqrt(n)
    assert w.std() == pytest.approx(a / np.sqrt(3), rel=0.02)  # uniform marginal
    assert w2.std() == pytest.approx(b, rel=0.02)
    kurt = np.mean((w - w.mean()) ** 4) / w.var() ** 2 - 3.0
    skew = np.mean((w2 - w2.mean()) ** 3) / w2.std() ** 3
    assert kurt == pytest.approx(-1.2, abs=0.05)  # uniform, not Gaussian (0)
    assert skew == pytest.approx(2.0, abs=0.15)  # exponential, not Gaussian (0)
    # omega coloured: the autocorrelation of a Gaussian AR(1) through the copula,
    # (6/pi) asin(rho/2) with rho = exp(-lag/tau); omega_2 white
    for lag in (1, 150, 300):
        acf = np.mean(w[:-lag] * w[lag:]) / (a * a / 3.0)
        assert acf == pytest.approx(6 / np.pi * np.arcsin(np.exp(-lag / tau) / 2), abs=0.03)
    assert abs(np.corrcoef(w2[:-4], w2[4:])[0, 1]) < 0.02  # white
    # deterministic given the episode key, independent of the batch composition
    _, again = run_rows(plant, D[[2, 0]], 300, [13, 11])
    np.testing.assert_array_equal(again[:, 0], om[:300, 2])
    np.testing.assert_array_equal(again[:, 1], om[:300, 0])
    assert not np.array_equal(om[:300, 0], om[:300, 1])
    # seed_rows: per-episode keys make different sequences, equal keys equal ones
    Xs = np.zeros((3, plant.n_x))
    plant.seed_rows(Xs, np.array([7, 8, 7], dtype=np.uint64))
    plant.steady_state(D[[0, 0, 0]], np.full(3, 535.0), Xs)
    assert Xs[0, IX.SEED] == Xs[2, IX.SEED] != Xs[1, IX.SEED] and np.all(Xs[:, IX.CNT] == 0)
    Z = np.zeros((3, plant.n_z))
    U = Xs[:, [IX.V]].copy()
    seq = []
    for _ in range(50):
        plant.step(Xs, U, D[[0, 0, 0]], Z)
        seq.append(Z[:, plant.index["omega_K"]].copy())
    seq = np.array(seq)
    np.testing.assert_array_equal(seq[:, 0], seq[:, 2])
    assert not np.array_equal(seq[:, 0], seq[:, 1])


# ---------------------------------------------------------------------- scenarios
def test_setpoint_step_535_545_scenario():
    assert "setpoint_step_535_545" in scenarios.names(ID)
    sc = scenarios.get("setpoint_step_535_545", ID)
    assert sc.value("setpoint_offset_C", 499.9) == 0.0 and sc.value("load", 600.0) == 1.0
    env = gym.make(ID, scenario="setpoint_step_535_545")
    _, info = env.reset(seed=0)
    assert info["setpoint_C"] == 535.0 and info["outlet_temp_C"] == pytest.approx(535.0)
    a = np.zeros(1, dtype=np.float32)
    sps = {}
    for _ in range(501):
        *_, info = env.step(a)
        sps[round(info["time_s"])] = info["setpoint_C"]
    assert sps[499] == 535.0 and sps[500] == 545.0 and sps[501] == 545.0
    ramp = scenarios.get("load_ramp_100_50_100_2pct", ID)
    assert ramp.value("load", 500.0) == 1.0
    assert ramp.value("load", 500.0 + 750.0) == pytest.approx(0.75)  # 2 %/min
    assert ramp.value("load", 2000.0) == pytest.approx(0.5)


def cascade_run(env, kc2=8.0, kp=0.5, ti=100.0, steps=2000, seed=0):
    """The paper's cascade structure: inner P G_C2 = kc2 (kg/s per K), outer PI (K/K)."""
    sig = env.unwrapped.signals
    names = [s.name for s in sig.observation]
    dec = sig.decode
    w_max = env.unwrapped.plant.params.spray_max_kg_s
    obs, info = env.reset(seed=seed)
    v0 = info["spray_valve"]
    integ = 0.0
    rows = []
    for _ in range(steps):
        o = dec(obs)
        e = o["setpoint_C"] - o["outlet_temp_meas_C"]
        integ += e / ti
        r_i = kp * (e + integ)  # intermediate-temperature setpoint deviation
        yi_dev = o["intermediate_temp_C"] - 470.0
        v = v0 - kc2 * (r_i - yi_dev) / w_max  # reverse acting: spray cools
        obs, _, term, trunc, info = env.step(np.array([2 * np.clip(v, 0, 1) - 1], np.float32))
        rows.append(
            (info["time_s"], info["outlet_temp_C"], info["setpoint_C"], info["spray_valve"])
        )
        assert "omega_K" in names and not term
        if trunc:
            break
    return np.array(rows)


def test_paper_cascade_tracks_setpoint_step():
    """The paper's cascade on its test: the +10 K step is tracked; what remains is the
    coloured omega's error, of the order of the paper's 1.7 K std (Section 5)."""
    env = gym.make(ID, scenario="setpoint_step_535_545")
    means, stds, peaks, sat = [], [], [], []
    for seed in range(3):
        t, y, sp, v = cascade_run(env, seed=seed).T
        assert t[-1] == 2000.0
        after = t >= 1200.0
        means.append(np.mean(y[after] - sp[after]))
        stds.append(np.std(y[after] - sp[after]))
        peaks.append(np.max(y) - 545.0)
        sat.append(np.sum((v <= 0.005) | (v >= 0.995)))
    assert abs(np.mean(means)) < 0.75
    assert 1.0 <= np.mean(stds) <= 2.5
    assert np.mean(peaks) < 8.0
    # 0.25 K sensor noise through G_C2 = 8 kg/s per K chatters the valve into its stops
    # part of the time (the paper's plant has no sensor noise); it is not pinned
    assert max(sat) < 0.35 * len(t)
