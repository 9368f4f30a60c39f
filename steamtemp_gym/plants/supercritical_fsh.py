"""Final superheater (FSH) of a supercritical, sliding-pressure once-through boiler.

Source: Sagara et al. (JSME Int. J. Ser. C, 1998), Fig. 1 and eq. (1)
and (9): an n-division distributed heating surface with flow-dependent heat
transfer (Nusselt exponent m = 0.8), a spray attemperator at the FSH inlet fed
by the outlet of the superheater one step upstream, heat absorption Q and steam
flow M as disturbances whose *ratio* is disturbed by load changes (its Fig. 4),
heat absorption not measured. Segment physics: plants/superheater.py.

Model (states in SI):

- load dynamics (boiler master, unit coordinated control): steam flow
  fraction L_w follows the load demand L_d with tau_steam (turbine and sliding
  pressure). Firing is a coal unit's: the fuel demand L_d + T_bir dL_d/dt
  (boiler-input-rate feed-forward) reaches the burners through the coal mill
  (grinding and pulverized-coal inventory, lag tau_mill) and becomes heat through
  the furnace (lag tau_firing): two lags in series,

      dL_m/dt = (L_d + T_bir dL_d/dt - L_m)/tau_mill,   dL_f/dt = (L_m - L_f)/tau_firing.

  Fuel systems of pulverized-coal units respond with a dead time of tens of seconds
  and time constants of minutes (IEEE Working Group on Prime Mover and Energy
  Supply Models, "Dynamic models for fossil fueled steam units in power system
  studies", IEEE Trans. Power Systems 6(2), 753-761, 1991; G. Zhou, J. Si, C.W.
  Taft, "Modeling and simulation of C-E deep bowl pulverizer", IEEE Trans. Energy
  Conversion 15(3), 312-322, 2000); 60 s + 90 s: plausible defaults in that range,
  unverified for this unit. The BIR lead (30 s) compensates only part of the
  150 s lag, as on real units: during ramps L_f/L_w departs from 1, the
  disturbance of the ratio Q/M in Sagara et al. 1998 Fig. 4 and the main driver of the
  steam-temperature excursion (a feed-forward on the load demand and its rate can
  anticipate it).
- pressure slides with steam flow: p = p_nom above 90 % load, linear down to
  p_min at 30 % (turbine at fixed throttle opening, Stodola-like p ~ W).
- upstream superheater outlet enthalpy h_up (first-order lag tau_upstream)
  towards

      h_up* = h_sched(L_w) + [c_fwr (L_f/L_w - 1) + m(L_w) + c_bias b] (h_sched - h_fw),

  h_sched: the fuel/water-ratio (FWR) schedule, set so that the design spray
  fraction would hold T_out at every load; c_fwr (fwr_coupling): share of a
  firing/flow ratio error reaching the FSH inlet (once-through enthalpy balance
  h_out - h_fw = Q/W, partly corrected by the separator-temperature loop);
  m(L) = m_50 4 L (1 - L) (fwr_mismatch m_50 = 0.8 % of the enthalpy rise at 50 %
  load, zero at rated): the schedule is not perfect, as on every real unit (set at
  commissioning at a few loads; plausible default, unverified), so a frozen valve
  drifts after a load change and the design spray is not exactly what holds the
  setpoint at part load; b: the relative heat-absorption error D[2] (scenario
  bias and the coloured slagging/coal-quality disturbance), of which the share
  c_bias (bias_upstream_share 0.3, plausible default, unverified) reaches the
  upstream superheaters' outlet, the rest being corrected by the FWR loop; the
  FSH gas side sees b directly (below).
- design spray (output design_spray_kg_s): what the schedule is designed for,
  spray_design_fraction x W; the steady spray that holds T_out differs from it by
  the schedule error m(L) (0 at rated load, about +20 % at 50-75 % load).
- spray attemperator: feedwater after the HP heaters (T_fw falls with load),
  taken at feed-pump discharge p + dp_boiler (dp_boiler ~ W^2), linear valve,
  w_sp = v C_v sqrt(rho dp); mixing by mass and energy balance.
- FSH: N segments of fluid + tube metal (superheater.py), steam-side kA ~
  (W/W_nom)^0.8, convective gas side UA_g ~ L_f^0.6 times fouling times
  (1 + heat-absorption bias), gas temperature falling with firing.
- attemperator protection (built-in interlock, attemperator.protected_spray_out):
  spray is capped so the attemperator outlet stays >= Tsat(p) + 12 K; active only
  where the sliding pressure is subcritical (p < 21.56 MPa, below ~83 % load) and
  there far from binding (the full valve cools by < 100 K at ~500 C): kept for
  random actions at low load.
- outlet header and main-steam line to the turbine: the shared unheated steam line of
  superheater.py (pipe_rhs: n_line = 3 mixing cells of steam plus wall metal at the
  steam temperature, (rho V + C_m dT/dh) dh_k/dt = W (h_k-1 - h_k)), 20 m3 of steam and
  55 t of effective header/pipe/valve-chest metal: about 18 s of storage at rated flow,
  growing as 1/flow. The true outlet temperature outlet_temp_C is the turbine-inlet
  temperature after it (the FSH's own outlet is fsh_outlet_temp_C). Volume and metal are
  plausible defaults, unverified, set so that the true outlet's Tu/Tg for a spray step
  is about 0.3 (field step tests, REFERENCE_DATA.md).
- actuator: valve lag, rate limit and saturation (valve.py); thermocouples in
  thermowells, two lags each, on the turbine-inlet main steam and the attemperator
  outlet (sensors.py).

Spray: design 4 % of the steam flow, valve capacity 12 % (valve at 0.33 at rated
load; 0.2-0.5 over fouling 0.85-1.15 and 35-100 % load; plausible defaults for a
once-through unit, unverified).

Nominal values: the paper gives h_a0 - h_e0 = 217.8 kJ/kg and T_a0 - T_e0 =
68.5 K across the FSH at rated load (eq. 9 normalization). With IAPWS-IF97 both
hold together at 24.8 MPa and 593 C outlet (inlet 524.5 C): the FSH of a
24.1 MPa / 593 C ultra-supercritical unit of the paper's era (turbine throttle
24.1 MPa after the main-steam-line drop). Rated flow 2270 t/h (the rated flow of
Toyoda and Wada 1999 Table 1, a unit of the same class). Tube geometry,
metal mass and gas-side figures are plausible defaults sized from the IDAES
320 MW platen and ClaRa figures in REFERENCE_DATA.md (unverified for this unit);
the gas-side conductance is sized so that the rated balance above holds.

Validation (tests/test_supercritical_fsh.py): rated steady state reproduces
217.8 kJ/kg and 68.5 K; steady states at 100/75/50 % hold the setpoint with
the valve inside its range; the linearized n-division model eq. (1)-(5)
reproduces Table 1 (delay nu n T); spray step responses at 100 % and 50 % load
(gain and time constant larger at 50 %; Tu/Tg of the true turbine-inlet
temperature 0.2-0.4, measured 0.30/0.30 true and 0.44/0.40 thermocouple at
100/50 %); the heat-absorption bias reaches h_up; the design-spray output against
the steady spray; the protection. Integrator accuracy: tests/test_integrator.py.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from steamtemp_gym._jit import njit, read_only
from steamtemp_gym.plants.attemperator import mix, protected_spray_out, spray_flow
from steamtemp_gym.plants.base import (
    D_FOULING,
    D_HEAT_BIAS,
    D_LOAD,
    D_LOAD_RATE,
    D_SPRAY_T,
    Plant,
    Signal,
    validate_params,
)
from steamtemp_gym.plants.integrator import pattern_arrays
from steamtemp_gym.plants.sensors import thermowell_rhs
from steamtemp_gym.plants.superheater import (
    chain_pattern,
    chain_rhs,
    chain_steady,
    pipe_pattern,
    pipe_rhs,
    pipe_steady,
    steam_side_kA,
)
from steamtemp_gym.plants.valve import steady_opening
from steamtemp_gym.steam import T_dTdh_ph, Tsat_p, h_pT, rho_ph

K0 = 273.15
P_CRIT_PA = 22.064e6  # critical pressure of water (IAPWS-IF97)


@dataclass(frozen=True)
class FSHParams:
    """Parameters of the supercritical FSH (units in the names; sources in the module doc)."""

    n_segments: int = 8  # divisions along the tube (Sagara et al. 1998 uses n = 3 in its observer)
    W_nom_kg_s: float = 2270e3 / 3600.0  # rated main-steam flow, 2270 t/h
    p_nom_MPa: float = 24.8  # FSH outlet pressure at rated load
    p_min_MPa: float = 8.0  # sliding-pressure floor
    slide_high_load: float = 0.9  # constant pressure above this load
    slide_low_load: float = 0.3  # p_min at and below this load
    T_out_C: float = 593.0  # outlet temperature setpoint
    dh_fsh_nom_kJ_kg: float = 217.8  # h_a0 - h_e0 at rated load (Sagara et al. 1998)
    n_tubes: int = 480
    tube_length_m: float = 50.0
    tube_id_m: float = 0.036
    tube_od_m: float = 0.0508
    rho_metal_kg_m3: float = 7800.0  # steel (IDAES)
    c_metal_J_kgK: float = 550.0  # alloy steel near 550 C
    alpha_nom_W_m2K: float = 3500.0  # effective steam-side coefficient incl. half the wall
    Tg_nom_C: float = 1000.0  # flue gas at the FSH, rated firing
    dTg_dload_K: float = 300.0  # gas temperature drop per unit firing reduction
    gas_flow_exponent: float = 0.6  # convective UA_g ~ gas flow^0.6
    spray_design_fraction: float = 0.04  # steady spray / main-steam flow the FWR schedule aims at
    spray_max_fraction: float = 0.12  # spray / main-steam flow with the valve fully open
    dp_boiler_nom_MPa: float = 4.0  # feed-pump discharge minus FSH pressure at rated flow
    T_fw_nom_C: float = 290.0  # feedwater after the HP heaters at rated load
    dT_fw_dload_K: float = 70.0  # feedwater temperature drop per unit load reduction
    tau_mill_s: float = 60.0  # coal mill: grinding and pulverized-coal inventory lag
    tau_firing_s: float = 90.0  # furnace and waterwall heat release behind the mills
    T_bir_s: float = 30.0  # boiler-input-rate feed-forward lead (imperfect: < the lags)
    tau_steam_s: float = 20.0  # steam-flow response to load demand
    tau_upstream_s: float = 120.0  # upstream superheaters' thermal lag
    fwr_coupling: float = 0.3  # share of a firing/flow ratio error reaching the FSH inlet
    fwr_mismatch: float = 0.008  # FWR schedule error: relative enthalpy-rise error at 50 % load
    bias_upstream_share: float = 0.3  # share of a heat-absorption bias reaching h_up
    n_line: int = 3  # mixing cells of the outlet header and main-steam line
    line_volume_m3: float = 20.0  # their steam volume
    line_metal_t: float = 55.0  # their effective metal at steam temperature
    attemp_margin_K: float = 12.0  # protection: attemperator outlet >= Tsat + margin
    tau_valve_s: float = 2.0
    valve_rate_per_s: float = 0.1  # full stroke in 10 s
    tau_tc1_s: float = 5.0  # thermocouple
    tau_tc2_s: float = 20.0  # thermowell
    dt_s: float = 2.0  # control interval
    n_substeps: int = 2  # ROS2 steps per control interval (1 step: 0.074 K error on the ramp)

    def __post_init__(self) -> None:
        validate_params(
            self,
            positive=tuple(
                n
                for n in self.__dataclass_fields__
                if n
                not in (
                    "dTg_dload_K",
                    "dT_fw_dload_K",
                    "T_bir_s",
                    "fwr_coupling",
                    "fwr_mismatch",
                    "bias_upstream_share",
                )
            ),
            bounds={
                "n_segments": (1, 40),
                "p_nom_MPa": (15.0, 31.0),
                "p_min_MPa": (1.0, 31.0),
                "T_out_C": (450.0, 650.0),
                "spray_design_fraction": (0.0, 0.2),
                "spray_max_fraction": (0.01, 0.3),
                "fwr_coupling": (0.0, 1.0),
                "fwr_mismatch": (-0.05, 0.05),
                "bias_upstream_share": (0.0, 1.0),
                "n_line": (1, 8),
                "line_volume_m3": (0.1, 200.0),
                "line_metal_t": (0.1, 500.0),
                "tau_mill_s": (1.0, 600.0),
                "tau_firing_s": (1.0, 900.0),
                "attemp_margin_K": (1.0, 50.0),
                "T_bir_s": (0.0, 600.0),
                "dTg_dload_K": (0.0, 800.0),
                "dT_fw_dload_K": (0.0, 200.0),
                "T_fw_nom_C": (100.0, 350.0),
            },
        )
        if self.tube_od_m <= self.tube_id_m:
            raise ValueError("FSHParams.tube_od_m must exceed tube_id_m")
        if self.p_min_MPa > self.p_nom_MPa:
            raise ValueError("FSHParams.p_min_MPa must not exceed p_nom_MPa")
        if not self.slide_low_load < self.slide_high_load:
            raise ValueError("FSHParams.slide_low_load must be below slide_high_load")
        if self.spray_design_fraction >= self.spray_max_fraction:
            raise ValueError("FSHParams.spray_design_fraction must be below spray_max_fraction")
        if self.Tg_nom_C - self.dTg_dload_K * 0.8 <= self.T_out_C:
            raise ValueError(
                "FSHParams: gas temperature at 20 % firing must exceed the steam outlet"
            )


# ---------------------------------------------------------------- packed parameters
# Indices into P (module constants, frozen into the kernels).
I_N, I_WNOM, I_PNOM, I_PMIN, I_SLH, I_SLL = 0, 1, 2, 3, 4, 5
I_KA, I_V, I_CM, I_UAG, I_TGN, I_DTG, I_GEXP = 6, 7, 8, 9, 10, 11, 12
I_CV, I_DPB, I_TFW, I_DTFW = 13, 14, 15, 16
I_TAUF, I_TBIR, I_TAUW, I_TAUUP, I_FWR = 17, 18, 19, 20, 21
I_TAUV, I_RATEV, I_TC1, I_TC2 = 22, 23, 24, 25
I_TAUM, I_MIS, I_BUP, I_NL, I_LV, I_SPD, I_MARG, I_LCM = 26, 27, 28, 29, 30, 31, 32, 33
I_TAB = 34  # start of the load tables: h_up, dh_up, h_fw, cp_fw, dcp_fw, rho_fw
TAB_LOADS = np.linspace(0.2, 1.2, 21)
N_TAB = TAB_LOADS.shape[0]
T_HUP, T_DHUP, T_HFW, T_CPFW, T_DCPFW, T_RHOFW = (I_TAB + k * N_TAB for k in range(6))
N_P = I_TAB + 6 * N_TAB
# State indices; after the chain (2 n states): the coal mill, then the n_line line cells
S_LF, S_LW, S_HUP, S_V, S_TC1, S_TC2, S_TA1, S_TA2 = 0, 1, 2, 3, 4, 5, 6, 7
S_CHAIN = 8
INLET_COLS = (S_HUP, S_V)  # states the FSH inlet enthalpy depends on
# Output indices (order of FSHPlant.outputs)
(Z_TOUT, Z_TOUTM, Z_TATT, Z_TATTM, Z_TUP, Z_W, Z_P, Z_V, Z_WSP, Z_LF, Z_Q, Z_TMMAX,
 Z_DSP, Z_TFSH, Z_MILL) = range(15)  # fmt: skip


@njit(cache=True)
def s_mill(n):
    """State index of the coal-mill output (fraction of rated fuel) for n FSH segments."""
    return S_CHAIN + 2 * n


@njit(cache=True)
def s_line(n):
    """State index of the first outlet-header / main-steam-line cell (enthalpy, J/kg)."""
    return S_CHAIN + 2 * n + 1


@njit(cache=True, error_model="numpy")
def _pressure(P, lw):
    """Sliding pressure (Pa) at steam-flow fraction lw."""
    lo, hi = P[I_SLL], P[I_SLH]
    r = min(max((lw - lo) / (hi - lo), 0.0), 1.0)
    return P[I_PMIN] + r * (P[I_PNOM] - P[I_PMIN])


@njit(cache=True, error_model="numpy")
def _table(P, off, load):
    """Linear interpolation of a schedule table stored in P over TAB_LOADS."""
    x = (min(max(load, 0.2), 1.2) - 0.2) / 0.05
    k = min(int(x), N_TAB - 2)
    a = x - k
    return (1.0 - a) * P[off + k] + a * P[off + k + 1]


def _spray_water_exact(P: np.ndarray, lw: float, dT: float) -> tuple[float, float, float]:
    """Spray water (h J/kg, rho kg/m3, valve dp Pa) from IF97 at steam-flow fraction lw."""
    p = _pressure(P, lw)
    dp = P[I_DPB] * lw * lw
    T_fw = P[I_TFW] - P[I_DTFW] * (1.0 - lw) + dT
    h = h_pT(p + dp, T_fw)
    return h, rho_ph(p + dp, h), dp


@njit(cache=True, error_model="numpy")
def spray_water(P, lw, dT):
    """Spray water (h J/kg, rho kg/m3, valve dp Pa) at steam-flow fraction lw and offset dT (K).

    Feed-pump discharge water, tabulated over load from IF97 at pack time; the
    temperature offset enters by a second-order Taylor step in T
    (h + cp dT + dcp/dT dT^2 / 2; error < 0.05 kJ/kg at +-15 K).
    """
    cp = _table(P, T_CPFW, lw)
    h = _table(P, T_HFW, lw) + dT * (cp + 0.5 * dT * _table(P, T_DCPFW, lw))
    return h, _table(P, T_RHOFW, lw), P[I_DPB] * lw * lw


@njit(cache=True, error_model="numpy")
def _boundary(x, u, d, P):
    """Algebraic part shared by rhs and outputs.

    Returns (W, p, w_sp, h0, h_sp, kA_seg, UAg_seg, Tg, capped) for state x, command u,
    disturbance d. kA_seg is the pair (kA, dkA/dW); capped: the spray is limited below the
    valve's flow (attemperator protection or the 0.5 W bound), so the valve has no effect.
    """
    lw = min(max(x[S_LW], 0.05), 1.3)
    lf = min(max(x[S_LF], 0.05), 1.3)
    W = lw * P[I_WNOM]
    p = _pressure(P, lw)
    h_sp, rho_sp, dp = spray_water(P, lw, d[D_SPRAY_T])
    w_valve = spray_flow(x[S_V], P[I_CV], rho_sp, dp)
    w_sp = min(w_valve, 0.5 * W)
    if p < P_CRIT_PA - 0.5e6:  # subcritical: the attemperator protection (module docstring)
        h_min = h_pT(p, Tsat_p(p) + P[I_MARG])
        w_sp = protected_spray_out(w_sp, W, x[S_HUP], h_sp, h_min)
    capped = w_sp < w_valve
    _, h0 = mix(W - w_sp, x[S_HUP], w_sp, h_sp)
    kA = steam_side_kA(P[I_KA], W, P[I_WNOM])
    gas = max(d[D_FOULING] * (1.0 + d[D_HEAT_BIAS]), 0.0)
    UAg = P[I_UAG] * lf ** P[I_GEXP] * gas
    Tg = P[I_TGN] - P[I_DTG] * (1.0 - lf)
    return W, p, w_sp, h0, h_sp, kA, UAg, Tg, capped


@njit(cache=True, error_model="numpy")
def _h_up_target(P, lf, lw, bias):
    """Upstream SH outlet enthalpy: fuel/water-ratio schedule, its error and ratio error.

    ``bias`` is the relative heat-absorption error (D[2]); its share bias_upstream_share
    of the enthalpy rise from the feedwater reaches the upstream superheaters' outlet.
    """
    lw = min(max(lw, 0.05), 1.3)
    lf = min(max(lf, 0.05), 1.3)
    h_up = _table(P, T_HUP, lw)
    dh_rise = _table(P, T_DHUP, lw)
    mis = P[I_MIS] * 4.0 * lw * (1.0 - lw)  # FWR schedule error, zero at rated load
    return h_up + (P[I_FWR] * (lf / lw - 1.0) + mis + P[I_BUP] * bias) * dh_rise


@njit(cache=True, error_model="numpy")
def _dpressure(P, lw):
    """d(sliding pressure)/d(steam-flow fraction) (Pa)."""
    if P[I_SLL] < lw < P[I_SLH]:
        return (P[I_PNOM] - P[I_PMIN]) / (P[I_SLH] - P[I_SLL])
    return 0.0


@njit(cache=True, error_model="numpy")
def rhs(x, u, d, P, f, jd, ju, jl, want_jac):
    """dx/dt of the FSH plant (see module docstring); Jacobian pattern from FSHPlant.pack."""
    n = int(P[I_N])
    sm = s_mill(n)
    fd = min(max(d[D_LOAD] + P[I_TBIR] * d[D_LOAD_RATE], 0.05), 1.3)
    f[sm] = (fd - x[sm]) / P[I_TAUM]
    f[S_LF] = (x[sm] - x[S_LF]) / P[I_TAUF]
    f[S_LW] = (d[D_LOAD] - x[S_LW]) / P[I_TAUW]
    f[S_HUP] = (_h_up_target(P, x[S_LF], x[S_LW], d[D_HEAT_BIAS]) - x[S_HUP]) / P[I_TAUUP]
    f[S_V] = u[0]  # exact chord velocity of the valve (plants/integrator.py)
    W, p, w_sp, h0, h_sp, kA, UAg, Tg, capped = _boundary(x, u, d, P)
    # dh0/d(h_up) and dh0/dv (attemperator balance, linear valve), order of INLET_COLS
    v = min(max(x[S_V], 1e-6), 1.0)
    dh0 = ((W - w_sp) / W, (h_sp - x[S_HUP]) * w_sp / v / W)
    if capped:
        dh0 = (dh0[0], 0.0)
    dW = P[I_WNOM] if 0.05 < x[S_LW] < 1.3 else 0.0
    dp = _dpressure(P, x[S_LW])
    _, _, _ = chain_rhs(
        x, S_CHAIN, n, h0, dh0, W, dW, p, dp, kA[0], kA[1], P[I_V], P[I_CM], UAg, Tg, 0.0,
        f, jd, ju, jl, 0, want_jac, True,
    )  # fmt: skip
    # outlet header and main-steam line (superheater.pipe_rhs; module docstring)
    T_out, _ = pipe_rhs(x, s_line(n), int(P[I_NL]), x[S_CHAIN + 2 * n - 1], (1.0,), W, 0.0, p,
                     P[I_LV], P[I_LCM], f, jd, jl, 4 * n + 1, want_jac, False)  # fmt: skip
    T_att, _ = T_dTdh_ph(p, h0)
    f[S_TC1], f[S_TC2], j1, j2 = thermowell_rhs(T_out, x[S_TC1], x[S_TC2], P[I_TC1], P[I_TC2])
    f[S_TA1], f[S_TA2], j3, j4 = thermowell_rhs(T_att, x[S_TA1], x[S_TA2], P[I_TC1], P[I_TC2])
    if want_jac:
        jd[S_LF] = -1.0 / P[I_TAUF]
        jd[S_LW] = -1.0 / P[I_TAUW]
        jd[S_HUP] = -1.0 / P[I_TAUUP]
        jd[S_V] = 0.0
        jd[S_TC1], jd[S_TC2], jd[S_TA1], jd[S_TA2] = j1, j2, j3, j4
        jd[sm] = -1.0 / P[I_TAUM]


@njit(cache=True, error_model="numpy")
def outputs(x, u, d, P, z):
    """Physical outputs (order of FSHPlant.outputs)."""
    n = int(P[I_N])
    W, p, w_sp, h0, h_sp, kA, UAg, Tg, capped = _boundary(x, u, d, P)
    T_fsh, _ = T_dTdh_ph(p, x[S_CHAIN + 2 * n - 1])
    T_out, _ = T_dTdh_ph(p, x[s_line(n) + int(P[I_NL]) - 1])
    T_att, _ = T_dTdh_ph(p, h0)
    T_up, _ = T_dTdh_ph(p, x[S_HUP])
    q = 0.0
    tm_max = 0.0
    for i in range(n):
        tm = x[S_CHAIN + 2 * i]
        q += UAg * (Tg - tm)
        tm_max = max(tm_max, tm)
    z[Z_TOUT] = T_out - K0
    z[Z_TOUTM] = x[S_TC2] - K0
    z[Z_TATT] = T_att - K0
    z[Z_TATTM] = x[S_TA2] - K0
    z[Z_TUP] = T_up - K0
    z[Z_W] = W
    z[Z_P] = p * 1e-6
    z[Z_V] = x[S_V]
    z[Z_WSP] = w_sp
    z[Z_LF] = x[S_LF]
    z[Z_Q] = q * 1e-6
    z[Z_TMMAX] = tm_max - K0
    z[Z_DSP] = P[I_SPD] * W
    z[Z_TFSH] = T_fsh - K0
    z[Z_MILL] = x[s_mill(n)]


@njit(cache=True, error_model="numpy")
def project(x, P):
    """Keep states inside their physical ranges after a step."""
    n = int(P[I_N])
    x[S_V] = min(max(x[S_V], 0.0), 1.0)
    x[S_LF] = min(max(x[S_LF], 0.05), 1.3)
    x[S_LW] = min(max(x[S_LW], 0.05), 1.3)
    x[S_HUP] = min(max(x[S_HUP], 2.0e6), 4.0e6)
    x[s_mill(n)] = min(max(x[s_mill(n)], 0.05), 1.3)
    for k in range(int(P[I_NL])):
        x[s_line(n) + k] = min(max(x[s_line(n) + k], 1.5e6), 4.2e6)
    for i in range(n):
        x[S_CHAIN + 2 * i] = min(max(x[S_CHAIN + 2 * i], 400.0), 1300.0)
        x[S_CHAIN + 2 * i + 1] = min(max(x[S_CHAIN + 2 * i + 1], 1.5e6), 4.2e6)


@njit(cache=True, error_model="numpy")
def _outlet_steady(x, v, d, P, lw):
    """Steady FSH outlet enthalpy for valve opening v (x holds h_up; chain written into x)."""
    n = int(P[I_N])
    x[S_V] = v
    W, p, w_sp, h0, h_sp, kA, UAg, Tg, capped = _boundary(x, x[S_V : S_V + 1], d, P)
    return chain_steady(x, S_CHAIN, n, h0, W, p, kA[0], UAg, Tg, 0.0)


@njit(cache=True, error_model="numpy")
def _outlet_T(x, v, d, P, aux):  # noqa: N803
    """Steady outlet temperature (K) at opening v; aux = (pressure Pa, load)."""
    return T_dTdh_ph(aux[0], _outlet_steady(x, v, d, P, aux[1]))[0]


_opening_for = steady_opening("SupercriticalFSH", _outlet_T)


@njit(cache=True, error_model="numpy")
def steady(D, sp_K, P, X):
    """Steady state at each row's disturbances, valve set by bisection to hold sp_K."""
    for b in range(X.shape[0]):
        x = X[b]
        d = D[b]
        L = min(max(d[D_LOAD], 0.05), 1.3)
        n = int(P[I_N])
        x[S_LF] = L
        x[s_mill(n)] = L
        x[S_LW] = L
        x[S_HUP] = _h_up_target(P, L, L, d[D_HEAT_BIAS])
        p = _pressure(P, L)
        v = _opening_for(x, d, P, (p, L), sp_K[b])
        h_out = _outlet_steady(x, v, d, P, L)
        W, p, w_sp, h0, h_sp, kA, UAg, Tg, capped = _boundary(x, x[S_V : S_V + 1], d, P)
        T_out, _ = T_dTdh_ph(p, h_out)
        T_att, _ = T_dTdh_ph(p, h0)
        x[S_TC1] = T_out
        x[S_TC2] = T_out
        pipe_steady(x, s_line(n), int(P[I_NL]), h_out)
        x[S_TA1] = T_att
        x[S_TA2] = T_att


@njit(cache=True, error_model="numpy")
def _design_inlet(P, lw, h_target, x):
    """Inlet enthalpy h_e such that the steady chain at load lw gives outlet h_target (secant)."""
    n = int(P[I_N])
    W = lw * P[I_WNOM]
    p = _pressure(P, lw)
    kA = steam_side_kA(P[I_KA], W, P[I_WNOM])[0]
    UAg = P[I_UAG] * lw ** P[I_GEXP]
    Tg = P[I_TGN] - P[I_DTG] * (1.0 - lw)
    a = h_target - 300e3
    b = h_target - 100e3
    fa = chain_steady(x, S_CHAIN, n, a, W, p, kA, UAg, Tg, 0.0) - h_target
    fb = chain_steady(x, S_CHAIN, n, b, W, p, kA, UAg, Tg, 0.0) - h_target
    for _ in range(60):
        if fb == fa:
            break
        c = b - fb * (b - a) / (fb - fa)
        a, fa = b, fb
        b = c
        fb = chain_steady(x, S_CHAIN, n, b, W, p, kA, UAg, Tg, 0.0) - h_target
        if abs(fb) < 1e-4:
            break
    return b


def _calibrate(params: FSHParams, P: np.ndarray, n_x: int) -> None:
    """Size the gas side and the fuel/water-ratio schedule (writes P in place).

    UA_g is set so that, at rated load with inlet enthalpy h_a0 - 217.8 kJ/kg, the
    steady FSH delivers h_a0 = h(p_nom, T_out) (Sagara et al. 1998's rated balance). The
    schedule h_up(L) is what the fuel/water-ratio control must deliver for the
    design spray fraction to hold T_out at every load.
    """
    x = np.zeros(n_x)
    Pk = read_only(P)  # what the kernels read (see steamtemp_gym._jit.read_only)
    p_nom = params.p_nom_MPa * 1e6
    h_a0 = h_pT(p_nom, params.T_out_C + K0)
    h_e0 = h_a0 - params.dh_fsh_nom_kJ_kg * 1e3
    n = params.n_segments
    W = params.W_nom_kg_s
    kA = P[I_KA]

    # secant on UAg for the rated balance
    def out(uag: float) -> float:
        return chain_steady(x, S_CHAIN, n, h_e0, W, p_nom, kA, uag, P[I_TGN], 0.0) - h_a0

    q0 = W * (h_a0 - h_e0) / n
    a, b = q0 / 400.0, q0 / 300.0
    fa, fb = out(a), out(b)
    for _ in range(60):
        if fb == fa:
            break
        a, b, fa = b, b - fb * (b - a) / (fb - fa), fb
        fb = out(b)
        if abs(fb) < 1e-4:
            break
    P[I_UAG] = b
    s = params.spray_design_fraction
    for k, L in enumerate(TAB_LOADS):
        h_sp, rho_sp, _ = _spray_water_exact(Pk, L, 0.0)
        h_p, _, _ = _spray_water_exact(Pk, L, 1.0)
        h_m, _, _ = _spray_water_exact(Pk, L, -1.0)
        P[T_HFW + k], P[T_RHOFW + k] = h_sp, rho_sp
        P[T_CPFW + k] = 0.5 * (h_p - h_m)
        P[T_DCPFW + k] = h_p - 2.0 * h_sp + h_m
        p = _pressure(Pk, L)
        h_out = h_pT(p, params.T_out_C + K0)
        h_e = _design_inlet(Pk, L, h_out, x)
        P[T_HUP + k] = (h_e - s * h_sp) / (1.0 - s)
        P[T_DHUP + k] = P[T_HUP + k] - h_sp
    # Valve coefficient: fully open passes spray_max_fraction of rated flow at rated load.
    h_sp, rho_sp, dp = _spray_water_exact(Pk, 1.0, 0.0)
    P[I_CV] = params.spray_max_fraction * W / math.sqrt(rho_sp * dp)


@functools.lru_cache(maxsize=32)
def _pack(params: FSHParams) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    n = params.n_segments
    area_flow = math.pi / 4.0 * params.tube_id_m**2
    area_metal = math.pi / 4.0 * (params.tube_od_m**2 - params.tube_id_m**2)
    seg_len = params.tube_length_m / n
    P = np.zeros(N_P)
    P[I_N] = n
    P[I_WNOM] = params.W_nom_kg_s
    P[I_PNOM] = params.p_nom_MPa * 1e6
    P[I_PMIN] = params.p_min_MPa * 1e6
    P[I_SLH] = params.slide_high_load
    P[I_SLL] = params.slide_low_load
    P[I_KA] = params.alpha_nom_W_m2K * math.pi * params.tube_id_m * seg_len * params.n_tubes
    P[I_V] = area_flow * seg_len * params.n_tubes
    P[I_CM] = area_metal * seg_len * params.n_tubes * params.rho_metal_kg_m3 * params.c_metal_J_kgK
    P[I_TGN] = params.Tg_nom_C + K0
    P[I_DTG] = params.dTg_dload_K
    P[I_GEXP] = params.gas_flow_exponent
    P[I_DPB] = params.dp_boiler_nom_MPa * 1e6
    P[I_TFW] = params.T_fw_nom_C + K0
    P[I_DTFW] = params.dT_fw_dload_K
    P[I_TAUF] = params.tau_firing_s
    P[I_TBIR] = params.T_bir_s
    P[I_TAUW] = params.tau_steam_s
    P[I_TAUUP] = params.tau_upstream_s
    P[I_FWR] = params.fwr_coupling
    P[I_TAUV] = params.tau_valve_s
    P[I_RATEV] = params.valve_rate_per_s
    P[I_TC1] = params.tau_tc1_s
    P[I_TC2] = params.tau_tc2_s
    P[I_TAUM] = params.tau_mill_s
    P[I_MIS] = params.fwr_mismatch
    P[I_BUP] = params.bias_upstream_share
    P[I_NL] = params.n_line
    P[I_LV] = params.line_volume_m3 / params.n_line
    P[I_LCM] = params.line_metal_t * 1e3 * params.c_metal_J_kgK / params.n_line
    P[I_SPD] = params.spray_design_fraction
    P[I_MARG] = params.attemp_margin_K
    n_x = S_CHAIN + 2 * n + 1 + params.n_line
    _calibrate(params, P, n_x)
    pat = chain_pattern(S_CHAIN, n, INLET_COLS, S_LW)
    assert len(pat) == 4 * n + 1  # rhs writes the line's entries from here on
    sl = S_CHAIN + 2 * n + 1
    pat += pipe_pattern(sl, params.n_line, (S_CHAIN + 2 * n - 1,))
    jrow, jcol = pattern_arrays(pat)
    P.setflags(write=False)
    return P, jrow, jcol, n_x


#: compiled parts of the shared ROS2 kernel (bound here: in the class body
#: ``outputs`` names the Signal tuple)
KERNELS = (rhs, outputs, project)


class SupercriticalFSH(Plant):
    """Plant of ``steamtemp/SupercriticalFSH-v0`` (Sagara et al. 1998)."""

    id = "steamtemp/SupercriticalFSH-v0"
    source = "Sagara et al., JSME Int. J. Ser. C, 1998"
    Params = FSHParams
    actions = (Signal("spray_valve_cmd", "1", 0.5, 0.5, description="spray valve command"),)
    outputs = (
        Signal("outlet_temp_C", "C", 593.0, 20.0, observed=False, description="true FSH outlet"),
        Signal("outlet_temp_meas_C", "C", 593.0, 20.0, noisy=True, description="thermocouple"),
        Signal("attemp_out_temp_C", "C", 525.0, 30.0, observed=False),
        Signal("attemp_out_temp_meas_C", "C", 525.0, 30.0, noisy=True),
        Signal("attemp_in_temp_C", "C", 545.0, 30.0, noisy=True, description="upstream SH outlet"),
        Signal("steam_flow_kg_s", "kg/s", 472.0, 160.0),
        Signal("pressure_MPa", "MPa", 17.0, 8.0),
        Signal("spray_valve", "1", 0.5, 0.5, description="valve position feedback"),
        Signal("spray_flow_kg_s", "kg/s", 20.0, 20.0),
        Signal("firing_rate", "1", 0.75, 0.3, description="fuel flow, fraction of rated"),
        Signal("heat_absorption_MW", "MW", 100.0, 50.0, observed=False, description="hidden"),
        Signal("metal_temp_max_C", "C", 620.0, 40.0, observed=False),
        Signal(
            "design_spray_kg_s",
            "kg/s",
            14.0,
            14.0,
            observed=False,
            description="spray the FWR schedule is designed for: design fraction x flow",
        ),
        Signal(
            "fsh_outlet_temp_C",
            "C",
            593.0,
            20.0,
            observed=False,
            description="FSH outlet, ahead of the outlet header and main-steam line",
        ),
        Signal("mill_output", "1", 0.75, 0.3, observed=False, description="coal to burners"),
    )
    setpoint_C = 593.0
    design_spray = "design_spray_kg_s"
    extra_info = ("attemp_out_temp_C", "heat_absorption_MW", "pressure_MPa", "steam_flow_kg_s")

    pack = staticmethod(_pack)
    kernels = KERNELS
    actuators = ((S_V, I_TAUV, I_RATEV),)
    setpoint_param = "T_out_C"

    def steady_state(self, D: np.ndarray, setpoint_C: np.ndarray, X: np.ndarray) -> None:
        steady(D, setpoint_C + K0, self.P, X)
