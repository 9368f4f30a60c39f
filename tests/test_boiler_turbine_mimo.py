"""Validation of steamtemp/BoilerTurbineMIMO-v0 against Toyoda and Wada 1999.

- Table 1: the heat-exchanger section of eq. (1)-(6) (the platen secondary SH, a fluid and a
  metal state) has Jacobian eigenvalues whose time constants are within 10 % of 6.5 s and
  137 s at 2270 t/h and of 8.3 s and 217 s at 1135 t/h (the extracted -0.046 1/s is
  1/217 s = 0.0046 1/s), at the plant's own steady operating points;
- steady states at 25/50/90/100 % load hold STE and RTE with SP1, SP2 and RGD inside (0, 1)
  and are stationary;
- Fig. 6: unit step responses of STE and RTE to SP1, SP2 and RGD differ strongly between
  25 % and 90 % load (gain or time-constant ratio >= 1.5 for every pair);
- the optional FF bias action raises both temperatures;
- ROS2 at the control interval against 16 substeps over a load ramp.
"""

import gymnasium as gym
import numpy as np
import pytest

import steamtemp_gym  # noqa: F401  (registers the ids)
from steamtemp_gym import scenarios
from steamtemp_gym.envs.kernels import schedules
from steamtemp_gym.metrics import step_response_metrics
from steamtemp_gym.plants import boiler_turbine_mimo as bt

NO_OU = np.zeros(2)  # no coloured heat-absorption disturbance in these tests
PLANT = bt.BoilerTurbineMIMO()
ENV_ID = "steamtemp/BoilerTurbineMIMO-v0"
ACT = [bt.IX.V1, bt.IX.V2, bt.IX.G]
TABLE1 = {1.0: (6.5, 137.0), 0.5: (8.3, 217.0)}  # load: (fast, slow) time constants in s
#: the columns of z of the main-steam and reheat temperatures
STE_RTE = [bt.IZ.outlet_temp_C, bt.IZ.reheat_temp_C]


def steady(loads, plant=PLANT, fouling=1.0, bias=0.0, spray_dT=0.0):
    loads = np.atleast_1d(loads).astype(float)
    D = np.zeros((loads.size, 5))
    D[:, 0], D[:, 2], D[:, 3], D[:, 4] = loads, bias, fouling, spray_dT
    X = np.zeros((loads.size, plant.n_x))
    plant.steady_state(D, np.full(loads.size, plant.setpoint_C), X)
    Z = np.zeros((loads.size, plant.n_z))
    U = X[:, [bt.IX.V1, bt.IX.V2, bt.IX.G, bt.IX.FB][: plant.n_u]].copy()
    plant.kernel()(X, U, D, plant.P, plant.jrow, plant.jcol, 0.0, 1, Z)
    return X, D, Z, U


def section_jacobian(x, u, d):
    """Central-difference Jacobian of the plant rhs on the platen's (metal, fluid) states."""
    P = PLANT.P
    o_pl = bt.offsets(P)[1]
    idx, eps = [o_pl, o_pl + 1], [1e-2, 10.0]  # K, J/kg
    J = np.zeros((2, 2))
    for j, (i, e) in enumerate(zip(idx, eps, strict=True)):
        cols = []
        for s in (1.0, -1.0):
            xs = x.copy()
            xs[i] += s * e
            cols.append(PLANT.continuous_rhs(xs, u, d)[idx])
        J[:, j] = (cols[0] - cols[1]) / (2.0 * e)
    return J


@pytest.mark.parametrize("load", [1.0, 0.5])
def test_table1_eigenvalues_of_the_heat_exchanger_section(load):
    assert PLANT.params.n_seg_platen == 1  # the section of eq. (1)-(3): one fluid, one metal
    X, D, Z, U = steady(load)
    # t/h of Table 1
    assert Z[0, bt.IZ.steam_flow_kg_s] * 3.6 == pytest.approx(2270.0 * load, rel=1e-9)
    eig = np.linalg.eigvals(section_jacobian(X[0], U[0], D[0]))
    assert np.all(np.abs(eig.imag) < 1e-12) and np.all(eig.real < 0)
    tau_fast, tau_slow = np.sort(-1.0 / eig.real)
    fast_ref, slow_ref = TABLE1[load]
    print(
        f"\n{2270 * load:.0f} t/h at {Z[0, bt.IZ.pressure_MPa]:.2f} MPa: tau = {tau_fast:.2f} s "
        f"({tau_fast / fast_ref - 1:+.1%}), {tau_slow:.1f} s ({tau_slow / slow_ref - 1:+.1%})"
    )
    assert tau_fast == pytest.approx(fast_ref, rel=0.10)
    assert tau_slow == pytest.approx(slow_ref, rel=0.10)


@pytest.mark.parametrize("load", [0.25, 0.5, 0.9, 1.0])
def test_steady_state_holds_both_setpoints_with_actuators_inside(load):
    X, D, Z, U = steady(load)
    assert Z[0, bt.IZ.outlet_temp_C] == pytest.approx(PLANT.params.T_ms_C, abs=0.01)
    assert Z[0, bt.IZ.reheat_temp_C] == pytest.approx(PLANT.params.T_rh_C, abs=0.01)
    for i in (bt.IZ.sp1_valve, bt.IZ.sp2_valve, bt.IZ.rgd_damper):
        assert 0.02 < Z[0, i] < 0.98, (load, i, Z[0, i])
    # stationary: 200 s with the inputs held change nothing measurable
    Z0 = Z.copy()
    for _ in range(100):
        PLANT.step(X, U, D, Z)
    temps = [bt.IZ.outlet_temp_C, bt.IZ.reheat_temp_C, bt.IZ.sp1_out_temp_C, bt.IZ.sp2_out_temp_C]
    np.testing.assert_allclose(Z[0, temps], Z0[0, temps], atol=1e-3)
    # the sprays absorb moderate disturbances (STE held, both valves inside their range)
    for dist in ({"bias": 0.05}, {"bias": -0.05}, {"fouling": 0.9}, {"spray_dT": 15.0}):
        _, _, Zd, _ = steady(load, **dist)
        assert Zd[0, bt.IZ.outlet_temp_C] == pytest.approx(PLANT.params.T_ms_C, abs=0.01), dist
        assert 0.0 < Zd[0, bt.IZ.sp1_valve] < 1.0 and 0.0 < Zd[0, bt.IZ.sp2_valve] < 1.0, dist


def step_responses(loads=(0.25, 0.9), du=0.05, steps=3000):
    """Metrics of STE and RTE after a +du step of SP1, SP2, RGD: {(load, input, output): dict}."""
    rows = [(L, k) for L in loads for k in range(3)]
    X, D, Z, U = steady([L for L, _ in rows])
    PLANT.step(X, U, D, Z)
    for b, (_, k) in enumerate(rows):
        U[b, k] += du
    y = [Z[:, STE_RTE].copy()]
    for _ in range(steps):
        PLANT.step(X, U, D, Z)
        y.append(Z[:, STE_RTE].copy())
    y = np.array(y)
    t = np.arange(steps + 1) * PLANT.dt_s
    out = {}
    for b, (L, k) in enumerate(rows):
        for o, name in enumerate(("STE", "RTE")):
            assert abs(y[-1, b, o] - y[-50, b, o]) < 0.01 * abs(y[-1, b, o] - y[0, b, o])  # settled
            out[(L, ("SP1", "SP2", "RGD")[k], name)] = step_response_metrics(t, y[:, b, o])
    return out


def test_step_responses_depend_strongly_on_load():
    """Fig. 6: 25 % (slow) vs 90 % load; tau = Tu + Tg of the inflection tangent."""
    m = step_responses()
    sign = {"SP1": -1.0, "SP2": -1.0, "RGD": 1.0}  # more spray colder; more recirculation hotter
    lines = [
        f"{'pair':10s} {'K 25%':>7s} {'K 90%':>7s} {'tau 25%':>8s} {'tau 90%':>8s} "
        f"{'K ratio':>7s} {'tau ratio':>9s}"
    ]
    for inp in ("SP1", "SP2", "RGD"):
        for out in ("STE", "RTE"):
            lo, hi = m[(0.25, inp, out)], m[(0.9, inp, out)]
            assert np.sign(lo["gain"]) == np.sign(hi["gain"]) == sign[inp], (inp, out)
            k_ratio = max(lo["gain"] / hi["gain"], hi["gain"] / lo["gain"])
            tau_lo, tau_hi = lo["Tu_s"] + lo["Tg_s"], hi["Tu_s"] + hi["Tg_s"]
            assert tau_lo > tau_hi  # slower at low load (less steam flow)
            lines.append(
                f"{inp}->{out:6s} {lo['gain']:7.2f} {hi['gain']:7.2f} {tau_lo:8.0f} "
                f"{tau_hi:8.0f} {k_ratio:7.2f} {tau_lo / tau_hi:9.2f}"
            )
            assert max(k_ratio, tau_lo / tau_hi) >= 1.5, (inp, out, k_ratio, tau_lo / tau_hi)
    print("\nstep +0.05 opening, K in K:\n" + "\n".join(lines))


def test_fuel_bias_option_adds_an_action_that_heats_both_outputs():
    env = gym.make(ENV_ID, scenario="setpoint_step", params={"fuel_bias_action": True})
    obs, info = env.reset(seed=0)
    assert env.action_space.shape == (4,) and len(info["spray_valve"]) == 4
    assert "fuel_bias" in [s.name for s in env.unwrapped.signals.observation]
    assert gym.make(ENV_ID).action_space.shape == (3,)
    plant = bt.BoilerTurbineMIMO(fuel_bias_action=True)
    X, D, Z, U = steady([0.9, 0.9], plant=plant)
    U[1, 3] += 0.125  # bias = fuel_bias_max (2 u - 1): +2.5 % of rated firing
    for _ in range(600):
        plant.step(X, U, D, Z)
    dT = Z[1, STE_RTE] - Z[0, STE_RTE]
    assert Z[1, bt.IZ.firing_rate] - Z[0, bt.IZ.firing_rate] == pytest.approx(0.025, rel=1e-3)
    print(f"\nFF +2.5 %, 20 min at 90 % load: STE {dT[0]:+.1f} K, RTE {dT[1]:+.1f} K")
    assert dT[0] > 2.0 and dT[1] > 1.0, dT


def test_reheat_temperature_is_observed_and_reported():
    env = gym.make(ENV_ID, scenario="load_ramp_100_50")
    obs, info = env.reset(seed=0)
    names = [s.name for s in env.unwrapped.signals.observation]
    assert "reheat_temp_meas_C" in names and "reheat_temp_C" not in names
    assert info["reheat_temp_C"] == pytest.approx(566.0, abs=0.01)
    decoded = env.unwrapped.signals.decode(obs)
    # the named scenarios add thermocouple noise (0.25 K std): six sigma
    assert decoded["reheat_temp_meas_C"] == pytest.approx(566.0, abs=1.5)


def test_ros2_at_the_control_interval_matches_16_substeps():
    """100 -> 50 % ramp with all three actuators moving: STE and RTE within 0.1 K."""
    fine = bt.BoilerTurbineMIMO(n_substeps=16)
    sc = scenarios.get("load_ramp_100_50")
    bp_t, bp_v = np.zeros((1, 5, 8)), np.zeros((1, 5, 8))
    bp_n = np.ones((1, 5), np.int64)
    scenarios.pack(sc, bp_t[0], bp_v[0], bp_n[0])
    D, sp = np.zeros((2, 5)), np.zeros(2)
    schedules(0, 0, 1000.0, bp_t, bp_v, bp_n, 538.0, NO_OU, D, sp)
    D[1] = D[0]
    X, _, Z, U0 = steady([D[0, 0]] * 2)
    err = np.zeros(2)
    for k in range(int(1800.0 / PLANT.dt_s)):
        t = 1000.0 + k * PLANT.dt_s
        schedules(0, 0, t, bp_t, bp_v, bp_n, 538.0, NO_OU, D, sp)
        D[1] = D[0]
        U = U0 + 0.05 * np.sin(2 * np.pi * t / np.array([300.0, 420.0, 600.0]))
        PLANT.step(X[:1], U[:1], D[:1], Z[:1])
        fine.step(X[1:], U[1:], D[1:], Z[1:])
        err = np.maximum(err, np.abs(Z[0, STE_RTE] - Z[1, STE_RTE]))
    print(f"\nROS2 dt = {PLANT.dt_s} s vs 16 substeps: max STE {err[0]:.3f} K, RTE {err[1]:.3f} K")
    assert np.all(err < 0.1), err


# ------------------------------------------------------------------ load-change physics
def test_heat_absorption_bias_reaches_the_evaporator_outlet():
    """The bias shifts the evaporator outlet enthalpy by the uncorrected share of its
    heat/flow ratio error: fwr_coupling * bias_upstream_share * bias * (h_up - h_fw)."""
    q = PLANT.params
    for load in (1.0, 0.5):
        X0, *_ = steady(load)
        X1, *_ = steady(load, bias=0.05)
        rise = bt.table(PLANT.P, bt.ITAB.RISE, load)
        expected = q.fwr_coupling * q.bias_upstream_share * 0.05 * rise
        assert X1[0, bt.IX.HUP] - X0[0, bt.IX.HUP] == pytest.approx(expected, rel=1e-6)
        assert expected > 10e3  # J/kg


def test_mill_and_furnace_lags_delay_the_firing():
    """Fuel-demand step through the mill and furnace lags (two lags in series): the heat
    release reaches 63 % after about tau_mill + tau_firing, not at once."""
    plant = bt.BoilerTurbineMIMO(fuel_bias_action=True)
    X, D, Z, U = steady([0.9], plant=plant)
    U[0, 3] += 0.125
    q = plant.params
    lf0, n = X[0, bt.IX.LF], int(round((q.tau_mill_s + q.tau_firing_s) / plant.dt_s))
    for _ in range(n):
        plant.step(X, U, D, Z)
    frac = (X[0, bt.IX.LF] - lf0) / 0.025
    # two lags in series at t = T1 + T2 (T1 = 100 s, T2 = 15 s): 0.60
    t, a, b = q.tau_mill_s + q.tau_firing_s, q.tau_mill_s, q.tau_firing_s
    expected = 1.0 - (a * np.exp(-t / a) - b * np.exp(-t / b)) / (a - b)
    assert frac == pytest.approx(expected, abs=0.03)


def test_design_spray_and_the_schedule_error():
    """design_spray_kg_s is the steady spray of the undisturbed plant at rated load (where
    the schedule error is zero); at half load the FWR schedule's commissioning error
    (fwr_schedule_error_kJ_kg) moves the steady spray away from design."""
    X, D, Z, U = steady([1.0, 0.5])
    w = Z[:, bt.IZ.sp1_flow_kg_s] + Z[:, bt.IZ.sp2_flow_kg_s]
    assert Z[0, bt.IZ.design_spray_kg_s] == pytest.approx(w[0], rel=0.01)
    q = PLANT.params
    assert Z[0, bt.IZ.design_spray_kg_s] == pytest.approx(
        (q.sp1_design_fraction + q.sp2_design_fraction) * q.W_nom_kg_s, rel=1e-6
    )
    print(f"\n50 %: design spray {Z[1, bt.IZ.design_spray_kg_s]:.1f} kg/s, steady {w[1]:.1f} kg/s")
    design = Z[1, bt.IZ.design_spray_kg_s]
    assert abs(w[1] - design) > 0.1 * design  # the documented mismatch
    exact = bt.BoilerTurbineMIMO(fwr_schedule_error_kJ_kg=0.0)
    X, D, Z, U = steady([0.5], plant=exact)
    sprays = Z[0, bt.IZ.sp1_flow_kg_s] + Z[0, bt.IZ.sp2_flow_kg_s]
    assert sprays == pytest.approx(Z[0, bt.IZ.design_spray_kg_s], rel=0.02)
