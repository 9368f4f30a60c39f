"""Validation of steamtemp/BensonSubcritical-v0 against Ghaffari, Moosavian and Chaibakhsh.

- rated steady state: 18.1 MPa / 535 C main steam, 4.35 MPa / 530 C reheat, feedwater
  80 K above the deaerator, eq. (16) power near the 440 MW rating, both sprays inside
  their range, and stationary under the kernel;
- steady states at 50/75/100 % load (also disturbed) hold the setpoint with both valves
  strictly inside (0, 1);
- the paper's first-order section model eq. (7), T_out = (T_in + K m_fuel/m_in)/(1 + tau s),
  fitted by least squares to each section's response (5 s samples, the section's own
  simulated inputs as the paper fed its measured data) to a fuel step and to an
  inlet-temperature step; the fitted K, tau and R^2 are printed (pytest -s);
- pressure dynamics eq. (13) and once-through behaviour (steam-generation point moves);
- the ROS2 step at dt = 5 s against a fine reference (Radau; ROS2 with 40 substeps).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import least_squares

from steamtemp_gym import scenarios
from steamtemp_gym.envs.kernels import schedules
from steamtemp_gym.plants import benson_subcritical as bs
from steamtemp_gym.plants.benson_subcritical.layout import ITB
from steamtemp_gym.plants.valve import valve_travel
from steamtemp_gym.steam import cp_pT

NO_OU = np.zeros(2)  # no coloured heat-absorption disturbance in these tests
PLANT = bs.BensonSubcritical()
#: open-loop plant for the step tests: the fuel/water-ratio trim frozen (as in a field step test)
OPEN = bs.BensonSubcritical(fwr_ki_per_s=0.0)
V = slice(bs.IX.V1, bs.IX.V2 + 1)
# section -> (inlet, outlet, inlet flow) columns of section_temperatures
SECTIONS = {
    "eco": (0, 1, 11),
    "evap": (1, 2, 11),
    "sh1": (2, 3, 11),
    "sh2": (3, 4, 11),
    "sh3": (5, 6, 12),
    "sh4": (7, 8, 13),
    "rh": (9, 10, 14),
}
# the inlet-temperature experiment of each section: feedwater temperature +10 K reaches the
# economizer .. SH2; spray 1 closing by 0.1 heats the SH3 inlet, spray 2 the SH4 inlet and,
# through the main steam and eq. (14), the reheater inlet.
INLET_STEP = {
    "eco": "feedwater",
    "evap": "feedwater",
    "sh1": "feedwater",
    "sh2": "feedwater",
    "sh3": "spray1",
    "sh4": "spray2",
    "rh": "spray2",
}


def steady(plant, load, bias=0.0, fouling=1.0, dT=0.0, sp=535.0):
    D = np.array([[load, 0.0, bias, fouling, dT]])
    X = np.zeros((1, plant.n_x))
    plant.steady_state(D, np.array([sp]), X)
    Z = np.zeros((1, plant.n_z))
    plant.kernel()(X, X[:, V].copy(), D, plant.P, plant.jrow, plant.jcol, 0.0, 1, Z)
    return X, D, Z


def test_rated_steady_state_matches_the_paper():
    X, D, Z = steady(PLANT, 1.0)
    T = bs.section_temperatures(X[0], D[0], PLANT.P)
    W_t, W_rh, p_rh, p_crh, _ = bs.reheat(PLANT.P, X[0, bs.IX.P], 1.0)
    assert Z[0, bs.IZ.pressure_MPa] == pytest.approx(18.1, abs=0.01)
    assert Z[0, bs.IZ.outlet_temp_C] == pytest.approx(535.0, abs=0.01)
    assert Z[0, bs.IZ.reheat_temp_C] == pytest.approx(530.0, abs=2.0)
    assert p_rh * 1e-6 == pytest.approx(4.35, abs=0.01)
    assert T[0] - (PLANT.params.T_deaerator_C) == pytest.approx(80.0, abs=0.5)  # HP heaters
    assert 250.0 < T[9] < 400.0  # cold reheat by eq. (14)
    assert Z[0, bs.IZ.power_MW] == pytest.approx(440.0, rel=0.02)  # eq. (16) vs the 440 MW rating
    for v in (Z[0, bs.IZ.spray_valve_1], Z[0, bs.IZ.spray_valve_2]):
        assert 0.05 < v < 0.95
    z = dict(zip(bs.IZ._fields, Z[0], strict=True))
    assert z["steam_flow_kg_s"] == pytest.approx(
        z["feedwater_flow_kg_s"] + z["spray_flow_1_kg_s"] + z["spray_flow_2_kg_s"]
    )
    # subcooled economizer outlet, superheated evaporator outlet: once-through
    assert 0.0 < Z[0, bs.IZ.steam_generation_point] < 1.0
    # stationary: 20 control intervals change nothing measurable
    U = X[:, V].copy()
    for _ in range(20):
        PLANT.step(X, U, D, Z)
    assert Z[0, bs.IZ.outlet_temp_C] == pytest.approx(535.0, abs=1e-3)
    assert Z[0, bs.IZ.reheat_temp_C] == pytest.approx(530.0, abs=2.0)
    assert Z[0, bs.IZ.pressure_MPa] == pytest.approx(18.1, abs=1e-3)


@pytest.mark.parametrize("load", [1.0, 0.75, 0.5])
def test_steady_state_holds_setpoint_with_both_valves_inside(load):
    for dist in (
        {},
        {"bias": 0.08},
        {"bias": -0.08},
        {"fouling": 0.85},
        {"fouling": 1.15},
        {"dT": 15.0},
        {"dT": -15.0},
        {"sp": 545.0},
    ):
        X, D, Z = steady(PLANT, load, **dist)
        sp = dist.get("sp", 535.0)
        assert Z[0, bs.IZ.outlet_temp_C] == pytest.approx(sp, abs=0.01), dist
        assert 0.0 < Z[0, bs.IZ.spray_valve_1] < 1.0 and 0.0 < Z[0, bs.IZ.spray_valve_2] < 1.0, dist
        p_sp = bs.p_setpoint(PLANT.P, load) * 1e-6
        assert Z[0, bs.IZ.pressure_MPa] == pytest.approx(p_sp, rel=0.05)
        U = X[:, V].copy()
        PLANT.step(X, U, D, Z)
        assert Z[0, bs.IZ.outlet_temp_C] == pytest.approx(sp, abs=1e-3), dist


# --------------------------------------------------------------------- eq. (7) section fits
def _experiment(kind, steps=400):
    """Open-loop step test at rated load; rows of section_temperatures (fuel in kg/s)."""
    P = OPEN.P
    X, D, Z = steady(OPEN, 1.0)
    U = X[:, V].copy()
    rec = [bs.section_temperatures(X[0], D[0], P)]
    sgp = [Z[0, bs.IZ.steam_generation_point]]
    p = [Z[0, bs.IZ.pressure_MPa]]
    if kind == "fuel":
        X[0, int(P[bs.IP.STRIM])] += 0.05  # fuel demand +5 % (the trim is frozen)
    elif kind == "feedwater":
        D[0, 4] += 10.0  # deaerator/feedwater (and spray water) temperature
    elif kind == "spray1":
        U[0, 0] -= 0.1
    elif kind == "spray2":
        U[0, 1] -= 0.1
    for _ in range(steps):
        OPEN.step(X, U, D, Z)
        rec.append(bs.section_temperatures(X[0], D[0], P))
        sgp.append(Z[0, bs.IZ.steam_generation_point])
        p.append(Z[0, bs.IZ.pressure_MPa])
    r = np.array(rec)
    r[:, 15] *= P[bs.IP.FNOM]
    return r, np.array(sgp), np.array(p)


@pytest.fixture(scope="module")
def experiments():
    return {k: _experiment(k) for k in ("fuel", "feedwater", "spray1", "spray2")}


def first_order(tau, K, dT_in, d_ratio, dt=5.0):
    """Deviation response of eq. (7) to inputs sampled every dt (linear in between)."""
    a = np.exp(-dt / tau)
    u = dT_in + K * d_ratio
    y = np.zeros_like(u)
    for k in range(len(u) - 1):
        s = (u[k + 1] - u[k]) / dt
        y[k + 1] = u[k + 1] - s * tau + (y[k] - u[k] + s * tau) * a
    return y


def r_squared(y, y_hat):
    return 1.0 - np.sum((y - y_hat) ** 2) / np.sum((y - np.mean(y)) ** 2)


def section_data(r, sec):
    i_in, i_out, i_w = SECTIONS[sec]
    ratio = r[:, 15] / r[:, i_w]  # m_fuel / m_in
    return r[:, i_out] - r[0, i_out], r[:, i_in] - r[0, i_in], ratio - ratio[0]


def fit_section(experiments, sec):
    """Fitted eq. (7) of a section: (K, tau, R2) fuel step; (tau, R2) inlet step, same K;
    (gain, tau, R2) of a first-order fit with a free inlet gain (diagnostic)."""
    y, dTi, dr = section_data(experiments["fuel"][0], sec)
    res = least_squares(
        lambda th: first_order(th[0], th[1], dTi, dr) - y,
        [60.0, 1000.0],
        bounds=([1.0, -1e5], [5000.0, 1e5]),
    )
    tau_f, K = res.x
    fuel = (K, tau_f, r_squared(y, first_order(tau_f, K, dTi, dr)))
    y, dTi, dr = section_data(experiments[INLET_STEP[sec]][0], sec)
    res = least_squares(
        lambda th: first_order(th[0], K, dTi, dr) - y, [60.0], bounds=([1.0], [5000.0])
    )
    inlet = (res.x[0], r_squared(y, first_order(res.x[0], K, dTi, dr)))
    res = least_squares(
        lambda th: first_order(th[0], K, th[1] * dTi, dr) - y,
        [60.0, 1.0],
        bounds=([1.0, 0.0], [5000.0, 5.0]),
    )
    free = (res.x[1], res.x[0], r_squared(y, first_order(res.x[0], K, res.x[1] * dTi, dr)))
    return fuel, inlet, free


@pytest.mark.parametrize("sec", list(SECTIONS))
def test_eq7_fits_fuel_step_and_inlet_step_shape(experiments, sec):
    (K, tau, r2), (tau_i, r2_i), (g, tau_g, r2_g) = fit_section(experiments, sec)
    print(
        f"\n{sec:5s} fuel step: K = {K:7.0f} K, tau = {tau:5.1f} s, R2 = {r2:.4f} | inlet "
        f"step (same K): tau = {tau_i:5.1f} s, R2 = {r2_i:.4f} | free inlet gain "
        f"{g:.3f}, tau = {tau_g:5.1f} s, R2 = {r2_g:.4f}"
    )
    assert r2 >= 0.95
    assert K > 0.0 and 5.0 < tau < 600.0
    # the inlet response is first order too (its gain is tested below)
    assert r2_g >= 0.95 and 5.0 < tau_g < 600.0


#: Sections whose inlet-temperature gain departs from eq. (7)'s 1 by more than ~10 %:
#: the paper assumes a constant C_p, IAPWS-IF97 steam does not (see the radiant test).
CP_VARIES = {"eco", "evap", "sh1", "sh2", "sh3"}
XFAIL_REASON = (
    "eq. (7) has unit inlet gain (constant C_p); IF97 gives C_p,in/C_p,out times "
    "the convective factor: 0.65, 1.17, 1.17, 1.19, 1.05"
)


@pytest.mark.parametrize(
    "sec",
    [
        pytest.param(s, marks=pytest.mark.xfail(strict=True, reason=XFAIL_REASON))
        if s in CP_VARIES
        else s
        for s in SECTIONS
    ],
)
def test_eq7_with_unit_inlet_gain_describes_the_inlet_step(experiments, sec):
    _, (tau_i, r2_i), _ = fit_section(experiments, sec)
    assert r2_i >= 0.95


@pytest.mark.parametrize("sec", ["evap", "sh2"])
def test_radiant_section_inlet_gain_is_the_cp_ratio(experiments, sec):
    """Radiant heat does not depend on the steam temperature, so an inlet enthalpy change
    passes unchanged: dT_out/dT_in = C_p(inlet)/C_p(outlet), not eq. (7)'s 1."""
    *_, (g, _, _) = fit_section(experiments, sec)
    i_in, i_out, _ = SECTIONS[sec]
    X, D, _ = steady(OPEN, 1.0)
    r = experiments[INLET_STEP[sec]][0]
    P, p = OPEN.P, X[0, bs.IX.P]
    k_in, k_out = (bs.SEC.ECO, bs.SEC.EV) if sec == "evap" else (bs.SEC.SH1, bs.SEC.SH2)
    p_in, p_out = (p + bs.P_SHARE[k] * P[bs.IP.DPB] for k in (k_in, k_out))
    T_in, T_out = (0.5 * (r[0, i] + r[-1, i]) + 273.15 for i in (i_in, i_out))  # mean states
    ratio = cp_pT(p_in, T_in) / cp_pT(p_out, T_out)
    assert g == pytest.approx(ratio, rel=0.05)
    assert abs(g - 1.0) > 0.1


def test_fuel_step_moves_the_steam_generation_point_upstream(experiments):
    _, sgp, _ = experiments["fuel"]
    assert sgp[-1] < sgp[0] - 0.01


def test_pressure_follows_eq13(experiments):
    """Spray 2 closing reduces the water pumped in: p falls as a first-order lag with
    time constant tau m_v p / (p0 W_t) (eq. 13 with turbine flow proportional to p)."""
    r, _, p = experiments["spray2"]
    P = OPEN.P
    dp = p - p[0]
    t = 5.0 * np.arange(len(p))
    res = least_squares(lambda th: th[0] * (1 - np.exp(-t / th[1])) - dp, [dp[-1], 50.0])
    tau_expected = p[0] * 1e6 / (P[bs.IP.CSTOR] * P[bs.IP.WNOM])
    assert res.x[1] == pytest.approx(tau_expected, rel=0.05)
    W_in = r[-1, 13]  # economizer + sprays at the end = turbine flow at equilibrium
    assert p[-1] / p[0] == pytest.approx(W_in / r[0, 13], rel=1e-3)


# --------------------------------------------------------------------------- integrator
def _ramp_setup(t0):
    sc = scenarios.get("load_ramp_100_50")
    bp_t, bp_v, bp_n = np.zeros((1, 5, 8)), np.zeros((1, 5, 8)), np.ones((1, 5), np.int64)
    scenarios.pack(sc, bp_t[0], bp_v[0], bp_n[0])
    D, sp = np.zeros((1, 5)), np.zeros(1)
    schedules(0, 0, t0, bp_t, bp_v, bp_n, 535.0, NO_OU, D, sp)
    X = np.zeros((1, PLANT.n_x))
    PLANT.steady_state(D, sp, X)
    return (bp_t, bp_v, bp_n), D, sp, X


def test_ros2_at_5s_matches_a_fine_solution_over_the_load_ramp():
    """100 -> 50 % at 5 %/min with both valves commanded every interval (a slow sinusoid,
    then random steps of +-0.3 as an agent may send): one ROS2 step per 5 s interval
    against 40 substeps, and against Radau (rtol 1e-8, valves on their exact travel
    inside the interval) over the ramp start."""
    fine = bs.BensonSubcritical(n_substeps=40)
    t0, t1 = 1150.0, 2400.0
    bp, D, sp, X = _ramp_setup(t0)
    Xf = X.copy()
    v0 = X[0, V].copy()
    Z, Zf = np.zeros((1, PLANT.n_z)), np.zeros((1, PLANT.n_z))
    P, f = PLANT.P, np.empty(PLANT.n_x)
    x_ref, err_radau = X[0].copy(), 0.0
    rng = np.random.default_rng(0)
    err = {"smooth": np.zeros(3), "steps": np.zeros(3)}
    for k in range(int((t1 - t0) / PLANT.dt_s)):
        t = t0 + k * PLANT.dt_s
        schedules(0, 0, t, *bp, 535.0, NO_OU, D, sp)
        smooth = t < 1900.0
        if smooth:
            U = (v0 + 0.04 * np.sin(2 * np.pi * t / 300.0) * np.array([1.0, -1.0]))[None, :]
        else:
            U = np.clip(v0 + rng.uniform(-0.3, 0.3, 2), 0.0, 1.0)[None, :]
        v_start, u_cmd, d_now = X[0, V].copy(), U[0].copy(), D[0].copy()
        PLANT.step(X, U, D, Z)
        fine.step(Xf, U, D, Zf)
        e = err["smooth" if smooth else "steps"]
        for j, i in enumerate((bs.IZ.outlet_temp_C, bs.IZ.outlet_temp_meas_C, bs.IZ.reheat_temp_C)):
            e[j] = max(e[j], abs(Z[0, i] - Zf[0, i]))
        if t < 1400.0:

            def rhs(tau, x, v=v_start, u=u_cmd, d=d_now):
                tv, rv = P[bs.IP.TAUV], P[bs.IP.RATEV]
                ut = np.array([valve_travel(v[j], u[j], tv, rv, tau)[0] for j in range(2)])
                bs.derivatives(x, ut, d, P, f)
                return f.copy()

            sol = solve_ivp(
                rhs,
                (0.0, PLANT.dt_s),
                x_ref,
                method="Radau",
                rtol=1e-8,
                atol=1e-6 * np.maximum(1.0, np.abs(x_ref)),
            )
            assert sol.success
            x_ref = sol.y[:, -1]
            x_ref[V] = X[0, V]
            T_ref = bs.section_temperatures(x_ref, D[0], P)[16]  # turbine inlet
            err_radau = max(err_radau, abs(Z[0, bs.IZ.outlet_temp_C] - T_ref))
    for name, e in err.items():
        print(
            f"\nROS2 dt=5 s vs 40 substeps ({name} valves): main steam {e[0] * 1e3:.1f} mK, "
            f"measured {e[1] * 1e3:.1f} mK, reheat {e[2] * 1e3:.1f} mK"
        )
    print(f"vs Radau (smooth valves, ramp start): main steam {err_radau * 1e3:.1f} mK")
    assert err["smooth"][0] <= 0.05 and err["smooth"][2] <= 0.05
    assert err["smooth"][1] <= 0.15  # thermocouple lag of 5 s integrated at 5 s
    assert err["steps"][0] <= 0.15 and err["steps"][1] <= 0.25 and err["steps"][2] <= 0.1
    assert err_radau <= 0.05


# ------------------------------------------------------------------ load-change physics
def test_heat_absorption_bias_reaches_the_evaporator_outlet():
    """+5 % heat-absorption bias with the fuel/water-ratio trim frozen: the evaporator
    (furnace walls, bias_evap_share of it) outlet enthalpy rises, not only the SH stages."""
    X, D, Z = steady(OPEN, 1.0)
    h0 = bs.section_enthalpies(X[0], D[0], OPEN.P)
    D[0, 2] = 0.05
    U = X[:, V].copy()
    for _ in range(120):
        OPEN.step(X, U, D, Z)
    h1 = bs.section_enthalpies(X[0], D[0], OPEN.P)
    print(
        f"\nbias +5 %: evaporator outlet {1e-3 * (h1[2] - h0[2]):+.1f} kJ/kg, "
        f"SH2 outlet {1e-3 * (h1[4] - h0[4]):+.1f} kJ/kg"
    )
    assert h1[2] - h0[2] > 10e3
    # the closed enthalpy loop returns the evaporator outlet to its setpoint
    Xc, Dc, _ = steady(PLANT, 1.0, bias=0.05)
    assert bs.section_enthalpies(Xc[0], Dc[0], PLANT.P)[2] == pytest.approx(h0[2], abs=100.0)


def test_design_spray_and_the_schedule_error():
    """design_spray_kg_s is the steady spray of the undisturbed plant at rated load (where
    the schedule error is zero); at half load the enthalpy schedule's commissioning error
    (fwr_schedule_error_kJ_kg) makes the steady spray differ from design, so a frozen
    valve drifts after a load change."""
    X, D, Z = steady(PLANT, 1.0)
    w = Z[0, bs.IZ.spray_flow_1_kg_s] + Z[0, bs.IZ.spray_flow_2_kg_s]
    assert Z[0, bs.IZ.design_spray_kg_s] == pytest.approx(w, rel=0.01)
    assert Z[0, bs.IZ.design_spray_kg_s] == pytest.approx(0.05 * PLANT.params.W_nom_kg_s, rel=0.02)
    X, D, Z = steady(PLANT, 0.5)
    w = Z[0, bs.IZ.spray_flow_1_kg_s] + Z[0, bs.IZ.spray_flow_2_kg_s]
    print(f"\n50 %: design spray {Z[0, bs.IZ.design_spray_kg_s]:.2f} kg/s, steady {w:.2f} kg/s")
    design = Z[0, bs.IZ.design_spray_kg_s]
    assert abs(w - design) > 0.1 * design  # the documented mismatch
    assert bs.h_ev_setpoint(PLANT.P, 0.5) - bs.table(PLANT.P, ITB.HEV, 0.5) == pytest.approx(
        PLANT.params.fwr_schedule_error_kJ_kg * 1e3
    )
    # a design-spray plant (no schedule error) holds the setpoint with design openings
    exact = bs.BensonSubcritical(fwr_schedule_error_kJ_kg=0.0)
    X, D, Z = steady(exact, 0.5)
    w = Z[0, bs.IZ.spray_flow_1_kg_s] + Z[0, bs.IZ.spray_flow_2_kg_s]
    assert w == pytest.approx(Z[0, bs.IZ.design_spray_kg_s], rel=0.05)


def test_furnace_lag_delays_the_heat_release():
    """Fuel demand step: the heat release follows through the furnace lag tau_furnace_s."""
    X, D, Z = steady(OPEN, 1.0)
    lf0 = X[0, bs.IX.F]
    X[0, int(OPEN.P[bs.IP.STRIM])] += 0.05
    n = int(round(OPEN.params.tau_furnace_s / OPEN.dt_s))
    U = X[:, V].copy()
    for _ in range(n):
        OPEN.step(X, U, D, Z)
    frac = (X[0, bs.IX.F] - lf0) / (0.05 * lf0 / (1.0 + X[0, int(OPEN.P[bs.IP.STRIM])] - 0.05))
    assert frac == pytest.approx(1.0 - np.exp(-1.0), abs=0.05)
