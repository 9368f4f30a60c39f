"""The fuzzy applied observer (FAO): the models that estimate the unmeasured heat
absorption and the division-point states the SF and FAC compensations of baselines/fao.py
act on.

Source: Sagara et al. 1998 (docs/references.md), section 3.2; its plant is
``steamtemp/SupercriticalFSH-v0``.

Observer (FAO, section 3.2). On the paper's plant the observer is the n = 3 division
model of the FSH in the normalized variables of eq. (9): division-point enthalpies
X_i = h_i/(h_a0 - h_e0), tube temperatures X_{i+3} = T_m,i/(T_a0 - T_e0), inputs
U_1 = X_0 (inlet), U_2 = Q/Q_0 (heat absorption, unmeasured), U_3 = M/M_0 (steam flow),
with h_a0 - h_e0 = 217.8 kJ/kg and T_a0 - T_e0 = 68.5 K (section 5) and
Q_0 = M_0 (h_a0 - h_e0). Per division (the physics of eq. (1) before linearization):

    C_m dT_m,i/dt = Q/n - kA (T_m,i - T(p, h_i)),   kA = kA_0 U_3^m, m = 0.8
    0 = M (h_{i-1} - h_i) + kA (T_m,i - T(p, h_i))   (fluid storage: time constant
                                                      ~0.3 s << 2 s, quasi-steady)

followed by the outlet header/main-steam line (mixing cells with wall metal) and the
two-lag thermocouple, so that the model predicts the *measured* outlet temperature.
T(p, h) and h(p, T) are IAPWS-IF97 through the project's tables (steamtemp_gym.steam,
the paper's eq. (14) ``tph``). The inputs come from measurements: pressure, steam flow
and the inlet enthalpy from the attemperator mass/energy balance (measured upstream
temperature, spray flow and steam flow; spray water at the plant's feed-pump discharge
conditions). The tube metal, steam-side conductance, line and sensor figures are the
plant's parameters (model-based design, allowed to a baseline). The unmeasured input
U_2 is estimated by driving the model's predicted measurement onto the measured one.
The paper's FAO does this with a fuzzy controller (its 1st report, ref. (2), not among
the project's documents); here a PI law on the (5 s filtered) output error does it,
tuned by SIMC (Skogestad 2003, tau_c = theta) on the observer model's own response of
the predicted measurement to a step of U_2 in the nominal steady state at each schedule
load, and gain-scheduled on U_3 (:func:`_fsh_observer_gains`; a rated-load tuning alone
goes unstable at 50 % load, where the Q -> T gain and lags are about twice as large).
This replaces the fuzzy estimator of ref. (2), which we cannot reproduce.

Off the paper's plant the observer is the linearized n-division model of eq. (1) itself
(plants/ndivision.state_space with nu = 1, i.e. no feedback), on the section between
the inner (attemperator-outlet) temperature and the measured outlet, in deviations from
the episode start normalized by that section's rated temperature rise
Delta T_0 = T_set - T_inner(100 %) (the analogue of T_a0 - T_e0): u_1 = K (T_inner -
T_inner,start)/Delta T_0 and an unmeasured lumped input w (eq. (1): theta_i = x_i + w/n;
at steady state w = u_2 - u_3, the linearization of Delta(U_2/U_3), so w_hat is the
FAC's second input). K and the division time constant T come from the commissioning
spray step test of that actuator (baselines.identification.step_test at rated load):
K = K_outer/K_inner, and T from the paper's delay (eq. (6)-(8)): the delay of the FOPDT
K e^{-theta s}/(tau s + 1) is tau + theta, delays add along a chain (eq. (8)) and the
n-division chain G^n has delay n T (Table 1, nu = 1), so T = (D_outer - D_inner)/n. w is
estimated by the same SIMC-tuned PI law. SF feeds back theta_i = x_i + w/n and both
outputs are converted to kelvin with Delta T_0 (on the FSH: the calibration of
baselines/fao.py, "Units of the bias").
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np
from scipy.linalg import expm

from baselines.cascade_pi import FILTER_S, inner_schedule
from baselines.commissioned import commissioned
from baselines.identification import FOPDT, simc_pi, step_test
from steamtemp_gym import plants
from steamtemp_gym._jit import njit
from steamtemp_gym.metrics import step_response_metrics
from steamtemp_gym.plants.attemperator import mix, protected_spray_out
from steamtemp_gym.plants.ndivision import state_space
from steamtemp_gym.steam import P_MAX, P_MIN, T_MAX, T_MIN, T_dTdh_ph, T_ph, Tsat_p, h_pT, rho_ph

K0 = 273.15
#: Divisions of the observer model (section 5, item 1).
N_DIV = 3
#: Nominal enthalpy and temperature rise across the FSH, J/kg and K (section 5, item 3).
DH0_J_KG, DT0_K = 217.8e3, 68.5


# -- the FSH observer (eq. 9) --------------------------------------------------------------
@njit(cache=True, error_model="numpy")
def _fsh_inlet(T_up_C, w_sp, W, p, h_sp, margin_K):
    """FSH inlet enthalpy (J/kg) per row: the plant's attemperator balance (``mix``) of the
    measured upstream steam and spray with the plant's spray water ``h_sp`` at the measured
    flow (``spray_water_enthalpy`` of the plant; no offset known)."""
    n = W.shape[0]
    h0 = np.empty(n)
    for b in range(n):
        h_up = h_pT(p[b], T_up_C[b] + K0)
        # the plant's attemperator protection: a measured spray flow that would wet the
        # steam (only from a faulty signal) is capped as the interlock caps the real one
        h_min = h_pT(p[b], Tsat_p(p[b]) + margin_K)
        ws = protected_spray_out(min(max(w_sp[b], 0.0), 0.5 * W[b]), W[b], h_up, h_sp[b], h_min)
        h0[b] = mix(W[b] - ws, h_up, ws, h_sp[b])[1]
    return h0


@njit(cache=True, error_model="numpy")
def _fsh_observer_init(S, rows, h0, W, p, T_meas_C, nl):
    """Steady observer state for restarted rows; returns the steady heat absorption (W)."""
    q = np.zeros(rows.shape[0])
    for k in range(rows.shape[0]):
        b = rows[k]
        h_a = h_pT(p[b], T_meas_C[b] + K0)
        q[k] = W[b] * (h_a - h0[b])
        for i in range(3):
            S[b, 3 + i] = h0[b] + (i + 1) * (h_a - h0[b]) / 3.0
            S[b, i] = T_ph(p[b], S[b, 3 + i])  # + Q/(n kA): set on the first step
        for j in range(nl):
            S[b, 6 + j] = h_a
        S[b, 6 + nl] = T_meas_C[b] + K0
        S[b, 7 + nl] = T_meas_C[b] + K0
    return q


@njit(cache=True, error_model="numpy")
def _fsh_observer_step(S, h0, W, p, Q, par, dt, n_sub, first):
    """Advance the n = 3 division observer model of every row by dt with inputs held.

    S per row: T_m,1..3 (K), h_1..3 (J/kg), line cell enthalpies, thermocouple T1, T2 (K).
    par: (C_m per division J/K, kA_0 per division W/K, M_0 kg/s, line V per cell m3,
    line C_m per cell J/K, tau_tc1 s, tau_tc2 s, n_line). ``first`` rows get their metal
    at the steady value for Q.
    """
    nl = int(par[7])
    h_sub = dt / n_sub
    for b in range(S.shape[0]):
        w = W[b]
        kA = par[1] * max(w / par[2], 0.1) ** 0.8
        if first[b]:
            for i in range(3):
                S[b, i] = T_ph(p[b], S[b, 3 + i]) + Q[b] / 3.0 / kA
        for _ in range(n_sub):
            h_prev = h0[b]
            for i in range(3):
                h = S[b, 3 + i]
                Tm = S[b, i]
                for _it in range(4):  # quasi-steady fluid: M (h - h_prev) = kA (Tm - T)
                    T, dTdh = T_dTdh_ph(p[b], h)
                    g = w * (h - h_prev) - kA * (Tm - T)
                    h -= g / (w + kA * dTdh)
                T, dTdh = T_dTdh_ph(p[b], h)
                beta = kA * dTdh / (w + kA * dTdh)  # dT_i/dT_m through the fluid
                a = kA * (1.0 - beta)
                Tm_eq = Tm + (Q[b] / 3.0 - kA * (Tm - T)) / a
                S[b, i] = Tm_eq + (Tm - Tm_eq) * np.exp(-a / par[0] * h_sub)
                S[b, 3 + i] = h + beta / dTdh * (S[b, i] - Tm)
                h_prev = S[b, 3 + i]
        h_prev = S[b, 5]
        for j in range(nl):  # main-steam line: (rho V + C_m dT/dh) dh/dt = M (h_prev - h)
            h = S[b, 6 + j]
            T, dTdh = T_dTdh_ph(p[b], h)
            tau = (rho_ph(p[b], h) * par[3] + par[4] * dTdh) / w
            S[b, 6 + j] = h + (h_prev - h) * (1.0 - np.exp(-dt / tau))
            h_prev = S[b, 6 + j]
        T_line = T_ph(p[b], h_prev)
        S[b, 6 + nl] += (T_line - S[b, 6 + nl]) * (1.0 - np.exp(-dt / par[5]))
        S[b, 7 + nl] += (S[b, 6 + nl] - S[b, 7 + nl]) * (1.0 - np.exp(-dt / par[6]))


def _fsh_par(plant: Any) -> np.ndarray:
    """Observer parameters (see _fsh_observer_step) from the plant's FSHParams."""
    pp = plant.params
    a_metal = np.pi / 4.0 * (pp.tube_od_m**2 - pp.tube_id_m**2)
    Cm = a_metal * pp.tube_length_m * pp.n_tubes * pp.rho_metal_kg_m3 * pp.c_metal_J_kgK
    kA = pp.alpha_nom_W_m2K * np.pi * pp.tube_id_m * pp.tube_length_m * pp.n_tubes
    return np.array(
        [
            Cm / N_DIV,
            kA / N_DIV,
            pp.W_nom_kg_s,
            pp.line_volume_m3 / pp.n_line,
            pp.line_metal_t * 1e3 * pp.c_metal_J_kgK / pp.n_line,
            pp.tau_tc1_s,
            pp.tau_tc2_s,
            float(pp.n_line),
        ]
    )


@commissioned(maxsize=8)
def _fsh_nominal(env_id: str, params_json: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(U_3, h_e^nom, h_a^nom) of the undisturbed steady states at the schedule loads."""
    sig = {
        s: inner_schedule(env_id, params_json, s)[1]
        for s in (
            "attemp_in_temp_C",
            "spray_flow_kg_s",
            "steam_flow_kg_s",
            "pressure_MPa",
            "outlet_temp_meas_C",
        )
    }
    plant = plants.make(env_id, **json.loads(params_json))
    par = _fsh_par(plant)
    p = sig["pressure_MPa"] * 1e6
    W = sig["steam_flow_kg_s"]
    h_sp = plant.spray_water_enthalpy(W / par[2])
    h0 = _fsh_inlet(
        sig["attemp_in_temp_C"], sig["spray_flow_kg_s"], W, p, h_sp, plant.params.attemp_margin_K
    )
    ha = np.array([h_pT(pi, T + K0) for pi, T in zip(p, sig["outlet_temp_meas_C"], strict=True)])
    return sig["steam_flow_kg_s"] / par[2], h0, ha


@commissioned(maxsize=8)
def fsh_unit_K(env_id: str, params_json: str) -> tuple[np.ndarray, np.ndarray]:
    """(U_3, K per normalized unit): the attemperator-outlet temperature change that moves
    the FSH inlet enthalpy by one normalized unit, h_a0 - h_e0 = 217.8 kJ/kg, i.e.
    DH0 dT/dh(p, h) at the undisturbed steady state of each schedule load (the plant's
    steam tables, the paper's eq. (14) ``tph``)."""
    sig = {
        s: inner_schedule(env_id, params_json, s)[1]
        for s in ("attemp_out_temp_meas_C", "steam_flow_kg_s", "pressure_MPa")
    }
    plant = plants.make(env_id, **json.loads(params_json))
    pT = zip(sig["pressure_MPa"] * 1e6, sig["attemp_out_temp_meas_C"] + K0, strict=True)
    unit = np.array([DH0_J_KG * T_dTdh_ph(p, h_pT(p, T))[1] for p, T in pT])
    return sig["steam_flow_kg_s"] / plant.params.W_nom_kg_s, unit


def _pi_from_response(t: np.ndarray, y: np.ndarray, du: float, dt: float) -> tuple[float, float]:
    """SIMC PI (Kc, Ti) of the estimator from the model's step response y(t) to a step du."""
    m = step_response_metrics(t, y)
    model = FOPDT(m["gain"] / du, m["Tg_s"], m["Tu_s"] + FILTER_S + dt)
    return simc_pi(model)


@commissioned(maxsize=8)
def _fsh_observer_gains(env_id: str, params_json: str) -> tuple[np.ndarray, np.ndarray]:
    """(Kc in W/K, Ti in s) of the U_2 estimator at each schedule load (gain-scheduled on
    U_3): SIMC on the observer model's response of the predicted measurement to a +5 %
    step of Q in that load's nominal steady state (the model only: no plant, no scenario).
    Q -> T gain and lags grow about as 1/U_3, so one rated-load tuning would make the
    estimator unstable at 50 % load."""
    plant = plants.make(env_id, **json.loads(params_json))
    par = _fsh_par(plant)
    u3, h0n, han = _fsh_nominal(env_id, params_json)
    p_MPa = inner_schedule(env_id, params_json, "pressure_MPa")[1]
    kc, ti = np.zeros(len(u3)), np.zeros(len(u3))
    for k in range(len(u3)):
        W, p, h0 = np.array([u3[k] * par[2]]), np.array([p_MPa[k] * 1e6]), np.array([h0n[k]])
        S = np.zeros((1, 8 + int(par[7])))
        T_out = np.array([float(T_ph(p[0], han[k])) - K0])
        Q = _fsh_observer_init(S, np.array([0]), h0, W, p, T_out, int(par[7]))
        dq, first = 0.05 * Q, np.array([True])
        t, y = [0.0], [S[0, -1]]
        for i in range(900):
            _fsh_observer_step(S, h0, W, p, Q + dq, par, plant.dt_s, 2, first)
            first[0] = False
            t.append((i + 1) * plant.dt_s)
            y.append(S[0, -1])
        kc[k], ti[k] = _pi_from_response(np.array(t), np.array(y), float(dq[0]), plant.dt_s)
    return kc, ti


class FSHObserver:
    """The FAO of the paper's plant (see module docstring): IF97 n = 3 division model."""

    def __init__(self, env: Any, names: list[str], params_json: str) -> None:
        plant = env.unwrapped.plant
        self.par = _fsh_par(plant)
        self.plant = plant
        self.nl = int(self.par[7])
        self.dt = plant.dt_s
        self.ix = [
            names.index(s)
            for s in (
                "attemp_in_temp_C",
                "spray_flow_kg_s",
                "steam_flow_kg_s",
                "pressure_MPa",
                "outlet_temp_meas_C",
            )
        ]
        self.u3_tab, self.h0_tab, self.ha_tab = _fsh_nominal(plant.id, params_json)
        self.unit_tab = fsh_unit_K(plant.id, params_json)
        self.unit_K = np.zeros(0)
        self.kc, self.ti = _fsh_observer_gains(plant.id, params_json)
        self.q0 = self.par[2] * DH0_J_KG
        self.a_f = float(np.exp(-self.dt / FILTER_S))
        self.S = np.zeros((0, 8 + self.nl))
        self.qi = self.ef = np.zeros(0)
        self.first = np.zeros(0, dtype=bool)

    def __call__(self, y: np.ndarray, restart: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(theta_i deviations (n, 3), Delta(U2/U3) (n,)) after the measurement y (physical)."""
        T_up, w_sp, W, p_MPa, T_meas = (y[:, i] for i in self.ix)
        # signal validation, as a DCS does before a model uses a measurement: flow within
        # the plant's load range, pressure and temperatures within the steam tables
        p = np.clip(p_MPa * 1e6, P_MIN, P_MAX)
        W = np.clip(W, 0.05 * self.par[2], 1.3 * self.par[2])
        T_up = np.clip(T_up, T_MIN - K0, T_MAX - K0)
        T_meas = np.clip(T_meas, T_MIN - K0, T_MAX - K0)
        h_sp = self.plant.spray_water_enthalpy(W / self.par[2])
        h0 = _fsh_inlet(T_up, w_sp, W, p, h_sp, self.plant.params.attemp_margin_K)
        n = y.shape[0]
        if self.S.shape[0] != n:
            self.S = np.zeros((n, 8 + self.nl))
            self.qi, self.ef = np.zeros(n), np.zeros(n)
            self.first = np.zeros(n, dtype=bool)
            restart = np.ones(n, dtype=bool)
        if restart.any():
            rows = np.flatnonzero(restart)
            self.qi[rows] = _fsh_observer_init(self.S, rows, h0, W, p, T_meas, self.nl)
            self.ef[rows] = 0.0
            self.first[rows] = True
        # output error of the predicted measurement (5 s filter), PI estimate of Q
        e = T_meas + K0 - self.S[:, -1]
        self.ef = self.a_f * self.ef + (1.0 - self.a_f) * e
        self.ef[restart] = 0.0
        u3 = W / self.par[2]
        kc = np.interp(u3, self.u3_tab, self.kc)
        ti = np.interp(u3, self.u3_tab, self.ti)
        self.qi += kc * self.dt / ti * self.ef
        self.qi = np.clip(self.qi, 0.0, 2.5 * self.q0)
        self.q_hat = np.clip(self.qi + kc * self.ef, 0.0, 2.5 * self.q0)
        _fsh_observer_step(self.S, h0, W, p, self.q_hat, self.par, self.dt, 2, self.first)
        self.first[:] = False
        h0n = np.interp(u3, self.u3_tab, self.h0_tab)
        han = np.interp(u3, self.u3_tab, self.ha_tab)
        frac = np.arange(1, N_DIV + 1) / N_DIV
        x_nom = (h0n[:, None] + frac * (han - h0n)[:, None]) / DH0_J_KG
        theta = self.S[:, 3:6] / DH0_J_KG - x_nom
        dratio = (self.q_hat / W - (han - h0n)) / DH0_J_KG  # U2/U3 - (U2/U3)^nom
        self.last_dratio = dratio  # for analysis
        self.unit_K = np.interp(u3, *self.unit_tab)
        return theta, dratio


# ---------------------------------------------------------- generic linear observer (eq. 1)
@commissioned(maxsize=16)
def _section_model(env_id: str, params_json: str, j: int) -> tuple[float, float, float]:
    """(K, T_s, Delta T_0) of the section inner -> measured outlet of MAIN loop j.

    K = K_outer/K_inner and the division time constant T from the delays (eq. 6-8) of the
    spray step test at rated load; Delta T_0 = setpoint - inner temperature at 100 % load.
    """
    plant = plants.make(env_id, **json.loads(params_json))
    inner = plant.control_loops[j][0]
    m = step_test(env_id, j, [inner, plant.outlet_measured], params=json.loads(params_json))
    mi, mo = m[inner], m[plant.outlet_measured]
    d = (mo.tau_s + mo.theta_s) - (mi.tau_s + mi.theta_s)
    loads, temps = inner_schedule(env_id, params_json, inner)
    dT0 = plant.setpoint_C - float(np.interp(1.0, loads, temps))
    return mo.K / mi.K, max(d / N_DIV, plant.dt_s), dT0


@commissioned(maxsize=16)
def _linear_observer(env_id: str, params_json: str, j: int):
    """(Ad, Bd, K, Delta T_0, Kc, Ti): ZOH model of eq. (1) (nu = 1) and its w estimator."""
    plant = plants.make(env_id, **json.loads(params_json))
    K, T, dT0 = _section_model(env_id, params_json, j)
    A, B, _ = state_space(N_DIV, 1.0, T)
    nx = A.shape[0]
    M = np.zeros((nx + 2, nx + 2))
    M[:nx, :nx], M[:nx, nx:] = A, B
    E = expm(M * plant.dt_s)
    Ad, Bd = E[:nx, :nx], E[:nx, nx:]
    x = np.zeros(nx)
    t, y = [0.0], [0.0]
    for i in range(int(20 * N_DIV * T / plant.dt_s) + 50):
        x = Ad @ x + Bd[:, 1] * 0.1
        t.append((i + 1) * plant.dt_s)
        y.append(x[-1] + 0.1 / N_DIV)
    y[0] = 0.0
    kc, ti = _pi_from_response(np.array(t), np.array(y), 0.1, plant.dt_s)
    return Ad, Bd, K, dT0, kc, ti


class LinearObserver:
    """n-division observer of eq. (1) on an identified section (plants other than the FSH)."""

    def __init__(self, env: Any, names: list[str], params_json: str, j: int) -> None:
        plant = env.unwrapped.plant
        self.Ad, self.Bd, self.K, self.dT0, self.kc, self.ti = _linear_observer(
            plant.id, params_json, j
        )
        self.i_in = names.index(plant.control_loops[j][0])
        self.i_out = names.index(plant.outlet_measured)
        self.dt = plant.dt_s
        self.a_f = float(np.exp(-self.dt / FILTER_S))
        self.x = np.zeros((0, N_DIV))
        self.y0 = self.wi = self.ef = self.w = np.zeros(0)
        self.unit_K = np.zeros(0)

    def __call__(self, y: np.ndarray, restart: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        n = y.shape[0]
        if self.x.shape[0] != n:
            self.x = np.zeros((n, N_DIV))
            self.y0 = np.zeros((n, 2))
            self.wi, self.ef, self.w = np.zeros(n), np.zeros(n), np.zeros(n)
            restart = np.ones(n, dtype=bool)
        if restart.any():
            self.x[restart], self.wi[restart], self.ef[restart] = 0.0, 0.0, 0.0
            self.y0[restart] = y[restart][:, [self.i_in, self.i_out]]
        u1 = self.K * (y[:, self.i_in] - self.y0[:, 0]) / self.dT0
        ym = (y[:, self.i_out] - self.y0[:, 1]) / self.dT0
        e = ym - (self.x[:, -1] + self.w / N_DIV)
        self.ef = self.a_f * self.ef + (1.0 - self.a_f) * e
        self.ef[restart] = 0.0
        self.wi = np.clip(self.wi + self.kc * self.dt / self.ti * self.ef, -2.0, 2.0)
        self.w = np.clip(self.wi + self.kc * self.ef, -2.0, 2.0)
        self.x = self.x @ self.Ad.T + np.outer(u1, self.Bd[:, 0]) + np.outer(self.w, self.Bd[:, 1])
        self.unit_K = np.full(n, self.dT0)
        return self.x + self.w[:, None] / N_DIV, self.w
