"""Natural-circulation drum boiler with primary superheater, spray attemperator and final SH.

Source: 003_6ab8c34c4d0cb71f.txt (from "Transcription:" on: Kim, "A Study on
Water-Tube Boiler Modeling", M.Sc. thesis, Inha Univ.): a natural-circulation
water-tube drum boiler in the Astrom-Bell form, inputs steam flow q_s, feedwater
q_f and riser heat Q_r (its Fig. 2), balances eq. (1)-(8), descriptor form eq. (21),
steady state eq. (22), step responses Fig. 6-8 and linearization at three operating
points eq. (23)-(31). Digits were lost in the extraction, so the drum parameters are
Astrom and Bell's (Automatica 36, 2000, 363-378; docs/references.md); the drum
model itself (four states V_wt, p, alpha_r, V_sd) is in drum.py.

Plant (states in SI; the env acts on the spray valve only):

- turbine / steam valve: the unit runs boiler-follow: the turbine load controller
  moves the governor valve so that main-steam flow W follows the load demand
  L_d W_nom through a first-order lag tau_steam (valve and load loop); drum pressure
  is held by the boiler (below), so the valve never needs to compensate pressure.
- drum pressure PI on firing (boiler master): firing demand
  u_f = L_d + T_bir dL_d/dt + K_p (p_sp - p)/p_sp + I_p, dI_p/dt = K_p/T_i (p_sp - p)/p_sp
  (load feed-forward with a boiler-input-rate lead; the feed-forward L_d is not the
  steady firing need Q(L)/Q_nom, which is larger per unit at low load: the imperfect
  static feed-forward of real units, removed by the integrator). Coal firing: u_f
  reaches the burners through the coal mill (grinding and pulverized-coal inventory,
  lag tau_mill) and heat through the furnace (lag tau_firing), two lags in series,
  dL_m/dt = (u_f - L_m)/tau_mill, dL_f/dt = (L_m - L_f)/tau_firing (fuel systems of
  pulverized-coal units: dead time of tens of seconds and time constants of minutes,
  IEEE Working Group on Prime Mover and Energy Supply Models, "Dynamic models for
  fossil fueled steam units in power system studies", IEEE Trans. Power Systems 6(2),
  753-761, 1991; G. Zhou, J. Si, C.W. Taft, "Modeling and simulation of C-E deep bowl
  pulverizer", IEEE Trans. Energy Conversion 15(3), 312-322, 2000). The BIR lead (45 s)
  compensates part of the 120 s of lags: during ramps the firing lags the steam flow,
  the main driver of the steam-temperature excursion. Heat to the risers
  Q = L_f Q_nom (Q_nom: Astrom-Bell's rated 85 MW).
- three-element level control: feedwater demand q_s + K_l (0 - l) + I_l,
  dI_l/dt = -K_l/T_l l, feedwater flow lags the demand by tau_fw (pump and valve).
- drum (drum.py) fed with q_s = W - w_sp (spray water bypasses the drum) and
  feedwater at T_fw = T_fw,nom - dT_fw (1 - W/W_nom) (HP heaters).
- primary SH: saturated steam h_v(p) at q_s, N segments of steam + tube metal
  (superheater.py), convective gas side UA_g1 L_f^0.6 (fouling, 1 + heat-absorption
  bias), gas temperature T_g1 = T_g1,nom - dT_g1 (1 - L_f).
- spray attemperator (attemperator.py): feedwater taken at drum-feed temperature
  (242 C at rated load, Astrom-Bell) plus the scenario's spray-water offset, linear
  valve w_sp = v C_v sqrt(rho dp_spray) across a constant pump-head margin dp_spray;
  mass and energy mixing. Built-in interlock (attemperator.protected_spray_out): the
  spray is capped so that the attemperator outlet stays >= Tsat(p_1) + 12 K (no water
  reaches the final SH; plants keep 10-15 K), whatever the valve; at 50 % load the
  fully open valve would pass ~18 % of the steam flow, the cap holds it to ~Tsat + 12 K.
  The heat-absorption bias (D[2]) multiplies both SH gas sides, so it reaches the
  primary SH outlet (upstream of the spray) as well as the final SH.
- final SH: N segments at main-steam flow W, gas side as the primary's at a hotter
  gas temperature (platen / pendant section). Steam pressures along the SH:
  p_1 = p - 0.4 dp_SH (W/W_nom)^2 (primary), p_2 = p - dp_SH (W/W_nom)^2 (main steam).
- outlet header and main-steam line to the turbine: the shared unheated steam line of
  superheater.py (pipe_rhs: n_line = 3 mixing cells of steam plus wall metal at the
  steam temperature), 2 m3 of steam and 5.5 t of effective metal: about 24 s of storage
  at rated flow, growing as 1/flow (plausible defaults, unverified, set so that the true
  outlet's Tu/Tg for a spray step is ~0.3 as in field step tests, REFERENCE_DATA.md).
  outlet_temp_C is the turbine-inlet temperature after it; the final SH's own outlet is
  sh2_outlet_temp_C.
- design spray (output design_spray_kg_s): the commissioning function generator,
  linear between the undisturbed steady sprays at 40/60/80/100 % load (exact there,
  within ~3 % between them; extrapolated linearly below 40 %).
- actuator and sensors: spray valve lag, rate limit and saturation (valve.py);
  thermocouples in thermowells on the main steam (turbine inlet) and attemperator
  outlet (sensors.py).

Parameters and their sources:

- drum: Astrom-Bell 2000 (REFERENCE_DATA.md); V_wt,nom = 57.2 m3 at 8.5 MPa /
  50 kg/s defines the normal water level (level 0). Drum metal m_d 40 t: plausible
  default, unverified (drum.py).
- operating point: drum pressure 8.5 MPa, drum steam flow 50 kg/s and feedwater
  242 C at rated load (Astrom-Bell); feedwater 40 K colder per unit load reduction
  (HP heaters; plausible default, unverified). Constant drum pressure over the load
  range (usual for drum units; the thesis's operating points instead let pressure rise
  with load).
- superheaters: plausible defaults, unverified, for a unit of this size. Rated main
  steam 52.6 kg/s (189 t/h: 50 kg/s from the drum plus 5 % spray), 8.1 MPa / 505 C at
  the SH outlet (the usual 500-510 C of ~9 MPa non-reheat units; 0.4 MPa drum-to-outlet
  pressure drop at rated flow). Heat to the steam at rated load: 85 MW in the risers
  plus 41 MW in the superheaters (~126 MW, a ~40-45 MWe non-reheat unit; the issue's
  "~60 MW class" is the nearest round class). Primary SH 96 tubes 34/42 mm x 70 m
  designed to deliver 440 C; final SH 72 tubes 32/42 mm x 60 m; steel 7800 kg/m3,
  550 J/(kg K); steam-side coefficient 3500 W/(m2 K) at rated flow, exponent 0.8
  (REFERENCE_DATA.md); 5 segments each. The gas-side conductances UA_g1, UA_g2 are
  calibrated so that the rated design holds: 440 C after the primary SH, 5 % spray
  (valve 0.50 of its 10 % capacity, 1.5 MPa across it; attemperator capacities of
  8-10 % of rated steam flow are usual), 400 C after the attemperator, 505 C out. Gas
  temperatures 750 C / 1050 C at the two SH at rated firing, falling 200 / 300 K per
  unit of firing: the spray need falls with load (valve 0.50, 0.37, 0.26 at 100, 75,
  50 %) and stays inside the valve range for fouling 0.85-1.15 (0.07-0.85).
- controls: tau_steam 10 s, tau_mill 60 s, tau_firing 60 s, T_bir 45 s, pressure PI
  K_p 1.5 (firing per relative pressure error), T_i 500 s (retuned for the two-lag
  firing: with K_p 3, T_i 300 s the pressure loop's damping fell to 0.14); level PI
  200 kg/s per m, T_i 200 s; tau_fw 5 s; valve 2 s lag and 10 %/s rate; thermocouple
  lags 5 s and 20 s (as the FSH plant). Plausible defaults, unverified, tuned on the
  linearized drum with its loops (slowest closed-loop mode ~400 s, damping >= 0.5).

Integration: ROS2 (integrator.py), one step per 2 s control interval. The matrix A
holds the stiff superheater couplings (chain_pattern, plus the firing column of every
metal row), the feedwater lag on steam flow and level integrator, the drum rows on the
states their inputs come from (exact sensitivities of the descriptor form by q_s, q_f,
Q and h_f) and the thermowells on what they measure (they come last in the state
vector so that these couplings are lower), the mill on the pressure loop, the line
lags on the final SH's outlet. Without the drum and firing columns the outlet error
against Radau over the 100 -> 50 % ramp was 0.22 K; with them 0.03 K (0.045 K with the
mill and line).

Validation (tests/test_drum_boiler.py): the rated steady state against Astrom-Bell's
(p 8.5 MPa, q_s 50 kg/s, Q 85.2 vs ~86 MW, q_dc 1190 vs ~1195 kg/s, alpha_r 0.0507 vs
~0.051, all within 3 %); the descriptor form against the mass and energy balances it
is derived from; shrink and swell (a +10 kg/s steam step raises the level by 3.8 cm
within 10 s open loop; a +10 % load step raises it by 2.3 cm under the loops);
linearization at 50/75/100 % load by finite differences of the rhs: the whole plant
and the drum with its PI loops are stable, the open-loop drum responses 150 s after a
step have the signs of the thesis's Fig. 6-8 (steam flow lowers pressure and level,
feedwater raises level and lowers pressure, heat raises pressure and level), and the
linear model follows the nonlinear drum (thesis Fig. 9). The open-loop drum with q_s
imposed has one slightly unstable pressure mode (+1e-4 to +2e-4 1/s: h_s falls with p
at 8.5 MPa, so less energy leaves with the same steam mass as pressure rises) next to
the zero of the mass balance; the pressure loop removes both. Spray step: more spray
lowers the outlet (-17.0 K per kg/s, t63 146 s at 100 % load; -32.4 K per kg/s, t63
252 s at 50 %; Tu/Tg of the true outlet 0.27/0.29, thermocouple 0.36/0.37); the
design spray inside the valve range at 35-100 % load and fouling 0.85-1.15; the
protection holding the attemperator outlet at Tsat + 12 K with the valve fully open.
ROS2 against Radau as above; every state at rest in the steady states.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from steamtemp_gym.plants import drum as dr
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
from steamtemp_gym.steam import T_dTdh_ph, Tsat_p, h_pT, rho_ph, sat_p

K0 = 273.15


@dataclass(frozen=True)
class DrumBoilerParams:
    """Parameters of the drum boiler plant (units in the names; sources in the module doc)."""

    # drum, Astrom and Bell (2000)
    V_d_m3: float = 40.0
    V_r_m3: float = 37.0
    V_dc_m3: float = 11.0
    m_t_kg: float = 300e3
    m_r_kg: float = 160e3
    m_d_kg: float = 40e3  # drum metal in the condensation flow (plausible default, unverified)
    C_p_J_kgK: float = 550.0
    A_d_m2: float = 20.0
    A_dc_m2: float = 0.38
    k_friction: float = 25.0
    beta: float = 0.3
    T_d_s: float = 12.0
    V_sd0_m3: float = 4.9
    V_wt_nom_m3: float = 57.2  # total water volume at the normal level, rated load
    # operating point
    p_drum_MPa: float = 8.5
    q_s_nom_kg_s: float = 50.0  # drum steam flow at rated load
    T_fw_nom_C: float = 242.0
    dT_fw_dload_K: float = 40.0  # feedwater temperature drop per unit load reduction
    p_fw_MPa: float = 9.5  # feedwater pressure for its properties
    T_out_C: float = 505.0  # main steam temperature setpoint
    T_primary_out_C: float = 440.0  # primary SH outlet at the rated design point
    spray_design_fraction: float = 0.05  # spray / main-steam flow at the rated design
    spray_max_fraction: float = 0.10  # spray / rated main-steam flow, valve fully open
    attemp_margin_K: float = 12.0  # protection: attemperator outlet >= Tsat(p_1) + margin
    dp_spray_MPa: float = 1.5  # pressure drop across the spray valve
    dp_sh_nom_MPa: float = 0.4  # drum to SH outlet at rated flow
    # superheaters
    n_segments: int = 5  # per superheater
    n_tubes_1: int = 96
    tube_length_1_m: float = 70.0
    tube_id_1_m: float = 0.034
    tube_od_1_m: float = 0.042
    n_tubes_2: int = 72
    tube_length_2_m: float = 60.0
    tube_id_2_m: float = 0.032
    tube_od_2_m: float = 0.042
    rho_metal_kg_m3: float = 7800.0
    c_metal_J_kgK: float = 550.0
    alpha_nom_W_m2K: float = 3500.0
    Tg1_nom_C: float = 750.0
    dTg1_dload_K: float = 200.0
    Tg2_nom_C: float = 1050.0
    dTg2_dload_K: float = 300.0
    gas_flow_exponent: float = 0.6
    # controls and actuators
    tau_steam_s: float = 10.0
    tau_mill_s: float = 60.0  # coal mill: grinding and pulverized-coal inventory lag
    tau_firing_s: float = 60.0  # furnace heat release behind the mills
    T_bir_s: float = 45.0  # boiler-input-rate feed-forward lead of the boiler master
    n_line: int = 3  # mixing cells of the outlet header and main-steam line
    line_volume_m3: float = 2.0  # their steam volume
    line_metal_t: float = 5.5  # their effective metal at steam temperature
    Kp_pressure: float = 1.5  # firing fraction per relative pressure error
    Ti_pressure_s: float = 500.0
    Kp_level_kg_s_m: float = 200.0
    Ti_level_s: float = 200.0
    tau_fw_s: float = 5.0
    tau_valve_s: float = 2.0
    valve_rate_per_s: float = 0.1
    tau_tc1_s: float = 5.0
    tau_tc2_s: float = 20.0
    dt_s: float = 2.0
    n_substeps: int = 1

    def __post_init__(self) -> None:
        validate_params(
            self,
            positive=tuple(
                n for n in self.__dataclass_fields__ if n not in ("dT_fw_dload_K", "T_bir_s")
            ),
            bounds={
                "n_segments": (1, 40),
                "p_drum_MPa": (2.0, 16.0),
                "p_fw_MPa": (2.0, 30.0),
                "beta": (0.0, 2.0),
                "T_fw_nom_C": (100.0, 300.0),
                "dT_fw_dload_K": (0.0, 100.0),
                "T_out_C": (400.0, 600.0),
                "spray_design_fraction": (0.005, 0.2),
                "spray_max_fraction": (0.01, 0.3),
                "gas_flow_exponent": (0.0, 1.0),
                "attemp_margin_K": (1.0, 50.0),
                "tau_mill_s": (1.0, 600.0),
                "tau_firing_s": (1.0, 900.0),
                "T_bir_s": (0.0, 600.0),
                "n_line": (1, 8),
                "line_volume_m3": (0.01, 50.0),
                "line_metal_t": (0.01, 100.0),
            },
        )
        for i in (1, 2):
            if getattr(self, f"tube_od_{i}_m") <= getattr(self, f"tube_id_{i}_m"):
                raise ValueError(f"DrumBoilerParams.tube_od_{i}_m must exceed tube_id_{i}_m")
        if self.V_wt_nom_m3 <= self.V_dc_m3 + 0.5 * self.V_r_m3:
            raise ValueError("DrumBoilerParams.V_wt_nom_m3 leaves the drum without water")
        if self.V_wt_nom_m3 >= self.V_d_m3 + self.V_r_m3 + self.V_dc_m3:
            raise ValueError("DrumBoilerParams.V_wt_nom_m3 exceeds the total volume")
        if self.p_fw_MPa <= self.p_drum_MPa:
            raise ValueError("DrumBoilerParams.p_fw_MPa must exceed p_drum_MPa")
        if self.dp_sh_nom_MPa >= 0.5 * self.p_drum_MPa:
            raise ValueError("DrumBoilerParams.dp_sh_nom_MPa is too large for p_drum_MPa")
        if self.spray_design_fraction >= self.spray_max_fraction:
            raise ValueError("DrumBoilerParams.spray_design_fraction must be below the max")
        if self.T_fw_nom_C - self.dT_fw_dload_K < 100.0:
            raise ValueError("DrumBoilerParams.dT_fw_dload_K: feedwater below 100 C at zero load")
        if self.T_fw_nom_C + 20.0 >= self.p_drum_tsat_C():
            raise ValueError("DrumBoilerParams.T_fw_nom_C must be subcooled at p_drum_MPa")
        if not self.p_drum_tsat_C() < self.T_primary_out_C < self.T_out_C:
            raise ValueError("DrumBoilerParams.T_primary_out_C must lie between Tsat and T_out_C")
        for i in (1, 2):
            tg = getattr(self, f"Tg{i}_nom_C") - 0.8 * getattr(self, f"dTg{i}_dload_K")
            if tg <= self.T_out_C:
                raise ValueError(f"DrumBoilerParams.dTg{i}_dload_K: gas at 20 % firing below T_out")

    def p_drum_tsat_C(self) -> float:
        """Saturation temperature at the drum pressure (C)."""
        return float(sat_p(self.p_drum_MPa * 1e6)[0] - K0)


# ---------------------------------------------------------------- packed parameters
(I_N, I_WNOM, I_PSP, I_QNOM, I_TFW, I_DTFW, I_CV, I_DPSP, I_DPSH,
 I_KA1, I_V1, I_CM1, I_UAG1, I_TG1, I_DTG1,
 I_KA2, I_V2, I_CM2, I_UAG2, I_TG2, I_DTG2, I_GEXP,
 I_TAUW, I_TAUF, I_KPP, I_TIP, I_KPL, I_TIL, I_TAUFW,
 I_TAUV, I_RATEV, I_TC1, I_TC2, I_QSN) = range(34)  # fmt: skip
I_TAUM, I_TBIR, I_NL, I_LV, I_MARG, I_LCM = 34, 35, 36, 37, 38, 39
I_DSP = 40  # design-spray function generator: spray (kg/s) at DSP_LOADS
DSP_LOADS = (0.4, 0.6, 0.8, 1.0)
I_DRUM = I_DSP + len(DSP_LOADS)  # drum parameter block (drum.drum_block)
I_FW = I_DRUM + dr.N_DRUM_P  # feedwater tables h(T), rho(T) at p_fw
FW_T0_K, FW_DT_K, N_FW = 273.15 + 80.0, 1.0, 261  # 80 .. 340 C
N_P = I_FW + 2 * N_FW
SHARE_1 = 0.4  # share of the SH pressure drop upstream of the primary SH's steam

# State indices
S_W, S_LF, S_IP, S_IL, S_QF, S_V = 0, 1, 2, 3, 4, 5
S_DRUM = 6  # V_wt, p, alpha_r, V_sd
S_P = S_DRUM + dr.PD
S_CHAIN1 = 10  # primary SH (2n states), then the final SH (2n states)
# then the coal mill (1), the outlet header / main-steam line (n_line cells), and the
# thermowells (their inputs are then lower couplings): offsets from
# sensors(n, n_line): main-steam thermocouple lags 1, 2, attemperator-outlet lags 1, 2
T_TC1, T_TC2, T_TA1, T_TA2 = 0, 1, 2, 3
DRUM_INPUT_COLS = (S_W, S_LF, S_QF, S_V)  # states the drum's inputs q_s, q_f, Q depend on
# Offsets in jl (order of pattern())
J_QF = 0
J_DRUM = 2
J_CHAIN1 = J_DRUM + 4 * len(DRUM_INPUT_COLS)


@njit(cache=True)
def s_mill(n):
    """State index of the coal-mill output (fraction of rated fuel) for n segments per SH."""
    return S_CHAIN1 + 4 * n


@njit(cache=True)
def s_line(n):
    """State index of the first outlet-header / main-steam-line cell (enthalpy, J/kg)."""
    return S_CHAIN1 + 4 * n + 1


@njit(cache=True)
def sensors(n, nl):
    """Index of the first thermowell state for n segments per SH and nl line lags."""
    return S_CHAIN1 + 4 * n + 1 + nl


# Output indices (order of DrumBoilerSH.outputs)
(Z_TOUT, Z_TOUTM, Z_TATT, Z_TATTM, Z_TPRI, Z_W, Z_PD, Z_LEVEL, Z_QF, Z_LF, Z_V, Z_WSP,
 Z_PMS, Z_QS, Z_QSH, Z_QEV, Z_TMMAX, Z_AR, Z_QDC, Z_DSP, Z_TSH2, Z_MILL) = range(22)  # fmt: skip


@njit(cache=True)
def _fw(P, T):
    """Feedwater (h J/kg, rho kg/m3, dh/dT J/(kg K)) at T (K): linear in the IF97 table at p_fw."""
    x = (min(max(T, FW_T0_K), FW_T0_K + FW_DT_K * (N_FW - 1)) - FW_T0_K) / FW_DT_K
    k = min(int(x), N_FW - 2)
    a = x - k
    o = I_FW + k
    h = (1.0 - a) * P[o] + a * P[o + 1]
    return h, (1.0 - a) * P[o + N_FW] + a * P[o + N_FW + 1], (P[o + 1] - P[o]) / FW_DT_K


@njit(cache=True)
def _boundary(x, d, P):
    """Algebraic quantities shared by rhs, outputs and the steady state.

    Returns (W, lw, dWok, q_s, w_sp, dw_dv, h_f, h_sp, p1, p2, dp1, dp2, L_f, UAg_mult)
    with dWok = 1 if W is inside its bounds (else 0), dw_dv = d(w_sp)/dv and dp1, dp2 the
    derivatives of the SH pressures by W.
    """
    Wn = P[I_WNOM]
    W = min(max(x[S_W], 0.05 * Wn), 1.3 * Wn)
    dWok = 1.0 if 0.05 * Wn < x[S_W] < 1.3 * Wn else 0.0
    lw = W / Wn
    T_fw = P[I_TFW] - P[I_DTFW] * (1.0 - lw)
    h_f, _, cp_f = _fw(P, T_fw)
    h_sp, rho_sp, _ = _fw(P, T_fw + d[D_SPRAY_T])
    v = min(max(x[S_V], 0.0), 1.0)
    cap = spray_flow(1.0, P[I_CV], rho_sp, P[I_DPSP])
    dpsh = P[I_DPSH] * lw * lw
    p = x[S_P]
    p1 = p - SHARE_1 * dpsh
    p2 = p - dpsh
    # attemperator protection (built-in interlock): outlet >= Tsat(p_1) + margin
    h_min = h_pT(p1, Tsat_p(p1) + P[I_MARG])
    w_max = protected_spray_out(0.5 * W, W, x[S_CHAIN1 + 2 * int(P[I_N]) - 1], h_sp, h_min)
    w_sp = min(v * cap, w_max)
    dw_dv = cap if v * cap < w_max else 0.0
    q_s = W - w_sp
    ddp = 2.0 * P[I_DPSH] * lw / Wn * dWok
    L_f = min(max(x[S_LF], 0.02), 1.3)
    mult = max(d[D_FOULING] * (1.0 + d[D_HEAT_BIAS]), 0.0) * L_f ** P[I_GEXP]
    dhf = cp_f * P[I_DTFW] / Wn * dWok
    return W, lw, dWok, q_s, w_sp, dw_dv, h_f, dhf, h_sp, p1, p2, -SHARE_1 * ddp, -ddp, L_f, mult


@njit(cache=True)
def _design_spray(P, lw):
    """Scheduled design spray (kg/s) at steam-flow fraction lw: the commissioning function
    generator, linear between the undisturbed steady sprays at DSP_LOADS (extrapolated
    linearly outside them, never below zero)."""
    k = 0
    while k < len(DSP_LOADS) - 2 and lw > DSP_LOADS[k + 1]:
        k += 1
    a = (lw - DSP_LOADS[k]) / (DSP_LOADS[k + 1] - DSP_LOADS[k])
    return max((1.0 - a) * P[I_DSP + k] + a * P[I_DSP + k + 1], 0.0)


@njit(cache=True)
def _firing_demand(x, d, P):
    """Boiler-master firing demand (fraction) and the pressure error (relative)."""
    e = (P[I_PSP] - x[S_P]) / P[I_PSP]
    return min(max(d[D_LOAD] + P[I_TBIR] * d[D_LOAD_RATE] + P[I_KPP] * e + x[S_IP], 0.02), 1.3), e


@njit(cache=True)
def _chain_fired(x, off, n, n_in, h0, dh0, W, dW, p, dp, kA, UAg, Tg, dUAg, dTg, Cm, V,
                 f, jd, ju, jl, joff, want_jac):  # fmt: skip
    """chain_rhs plus the firing column of every metal row (pattern: :func:`fired_pattern`).

    chain_rhs writes its own entries n places further on; they are then moved down to
    make room for d(metal_i)/d(L_f) = (dUA_g/dL_f (T_g - T_m,i) + UA_g dT_g/dL_f)/C_m
    before each metal row's entry (a forward in-place move: every destination index is
    at most its source).
    """
    _, T_out, _ = chain_rhs(x, off, n, h0, dh0, W, dW, p, dp, kA[0], kA[1], V, Cm, UAg, Tg,
                            0.0, f, jd, ju, jl, joff + n, want_jac, True)  # fmt: skip
    if want_jac:
        dst, src = joff, joff + n
        for i in range(n):
            jl[dst] = (dUAg * (Tg - x[off + 2 * i]) + UAg * dTg) / Cm
            jl[dst + 1] = jl[src]  # metal row, flow column
            dst += 2
            src += 1
            k = (n_in if i == 0 else 0) + (3 if i > 0 else 2)
            for _ in range(k):
                jl[dst] = jl[src]
                dst += 1
                src += 1
    return T_out


def fired_pattern(off: int, n: int, inlet_cols: tuple[int, ...]) -> list[tuple[int, int]]:
    """chain_pattern (flow column W) with the firing column before each metal row's entry."""
    out = []
    for r, c in chain_pattern(off, n, inlet_cols, S_W):
        if (r - off) % 2 == 0 and (not out or out[-1][0] != r):
            out.append((r, S_LF))
        out.append((r, c))
    return out


def pattern(n: int, nl: int) -> list[tuple[int, int]]:
    """Strictly-lower Jacobian pattern (row, col), sorted by row, in the order rhs fills jl.

    Feedwater on steam flow and the level integrator; the drum rows on the inputs' states
    (W, L_f, q_f, spray valve); the primary SH (inlet h_v(p): drum pressure) and the final
    SH (inlet from W, the valve and the primary outlet), each with the flow column W and
    the firing column L_f on the metal rows; the mill on the boiler master's integrator
    and the drum pressure; the line lags on the final SH's outlet enthalpy and on each
    other; the thermowells on the temperatures they measure (the main-steam line's outlet;
    W, valve and primary outlet for the attemperator).
    """
    c2 = S_CHAIN1 + 2 * n
    sl = S_CHAIN1 + 4 * n + 1
    st = sl + nl
    return (
        [(S_QF, S_W), (S_QF, S_IL)]
        + dr.input_pattern(S_DRUM, DRUM_INPUT_COLS)
        + fired_pattern(S_CHAIN1, n, (S_P,))
        + fired_pattern(c2, n, (S_W, S_V, c2 - 1))
        + [(sl - 1, S_IP), (sl - 1, S_P)]
        + pipe_pattern(sl, nl, (c2 + 2 * n - 1,))
        + [(st, st - 1), (st + 1, st), (st + 2, S_W), (st + 2, S_V), (st + 2, c2 - 1)]
        + [(st + 3, st + 2)]
    )


@njit(cache=True)
def rhs(x, u, d, P, f, jd, ju, jl, want_jac):
    """dx/dt of the drum boiler plant (see module docstring); pattern from :func:`pattern`."""
    n = int(P[I_N])
    c2 = S_CHAIN1 + 2 * n
    W, lw, dWok, q_s, w_sp, dw_dv, h_f, dhf, h_sp, p1, p2, dp1, dp2, L_f, mult = _boundary(x, d, P)
    # turbine load controller, boiler master, feedwater
    f[S_W] = (min(max(d[D_LOAD], 0.0), 1.3) * P[I_WNOM] - x[S_W]) / P[I_TAUW]
    u_f, e_p = _firing_demand(x, d, P)
    sm = s_mill(n)
    f[sm] = (u_f - x[sm]) / P[I_TAUM]
    f[S_LF] = (x[sm] - x[S_LF]) / P[I_TAUF]
    f[S_IP] = P[I_KPP] / P[I_TIP] * e_p
    dLf = 1.0 if 0.02 < x[S_LF] < 1.3 else 0.0
    Qn = P[I_QNOM]
    level, qdc, q_r, h_s, dh_s, sens = dr.drum_rhs(
        x, S_DRUM, P, I_DRUM, q_s, x[S_QF], h_f, L_f * Qn, f, jd, want_jac
    )
    if want_jac:
        # drum rows on (W, L_f, q_f, v) = DRUM_INPUT_COLS: q_s = W - w_sp(v), Q = L_f Q_nom
        for r in range(4):
            s_qs, s_qf, s_q, s_hf = sens[4 * r], sens[4 * r + 1], sens[4 * r + 2], sens[4 * r + 3]
            j = J_DRUM + 4 * r
            jl[j] = s_qs * dWok + s_hf * dhf
            jl[j + 1] = s_q * Qn * dLf
            jl[j + 2] = s_qf
            jl[j + 3] = -s_qs * dw_dv
    f[S_IL] = -P[I_KPL] / P[I_TIL] * level
    q_fd = q_s - P[I_KPL] * level + x[S_IL]
    f[S_QF] = (max(q_fd, 0.0) - x[S_QF]) / P[I_TAUFW]
    f[S_V], jv = u[0], 0.0  # exact chord velocity of the valve (plants/integrator.py)
    # primary superheater: saturated steam at q_s
    gex = P[I_GEXP] * dLf / L_f
    UAg1 = P[I_UAG1] * mult
    Tg1 = P[I_TG1] - P[I_DTG1] * (1.0 - L_f)
    # inlet derivatives (arrays only in the Jacobian call; chain_rhs reads them only then)
    dh0 = np.array([dh_s]) if want_jac else f[0:1]
    _chain_fired(
        x, S_CHAIN1, n, 1, h_s, dh0, q_s, dWok, p1, dp1,
        steam_side_kA(P[I_KA1], q_s, P[I_QSN]), UAg1, Tg1, gex * UAg1, P[I_DTG1] * dLf,
        P[I_CM1], P[I_V1], f, jd, ju, jl, J_CHAIN1, want_jac,
    )  # fmt: skip
    # attemperator and final superheater at W
    h1 = x[c2 - 1]
    _, h_att = mix(q_s, h1, w_sp, h_sp)
    if want_jac:
        dh_att = np.array([w_sp * (h1 - h_sp) / (W * W) * dWok, (h_sp - h1) * dw_dv / W, q_s / W])
    else:
        dh_att = f[0:3]
    UAg2 = P[I_UAG2] * mult
    Tg2 = P[I_TG2] - P[I_DTG2] * (1.0 - L_f)
    _chain_fired(
        x, c2, n, 3, h_att, dh_att, W, dWok, p2, dp2, steam_side_kA(P[I_KA2], W, P[I_WNOM]),
        UAg2, Tg2, gex * UAg2, P[I_DTG2] * dLf, P[I_CM2], P[I_V2], f, jd, ju, jl,
        J_CHAIN1 + 5 * n, want_jac,
    )  # fmt: skip
    # outlet header and main-steam line (superheater.pipe_rhs; module docstring)
    nl = int(P[I_NL])
    j_line = J_CHAIN1 + 10 * n + 4  # after the mill's two entries
    T_out, dT_out = pipe_rhs(x, s_line(n), nl, x[c2 + 2 * n - 1], (1.0,), W, 0.0, p2, P[I_LV],
                             P[I_LCM], f, jd, jl, j_line, want_jac, False)  # fmt: skip
    T_att, dT_att = T_dTdh_ph(p1, h_att)
    st = sensors(n, nl)
    tc1, tc2 = P[I_TC1], P[I_TC2]
    f[st], f[st + 1], j1, j2 = thermowell_rhs(T_out, x[st], x[st + 1], tc1, tc2)
    f[st + 2], f[st + 3], j3, j4 = thermowell_rhs(T_att, x[st + 2], x[st + 3], tc1, tc2)
    if want_jac:
        jd[S_W] = -1.0 / P[I_TAUW]
        jd[S_LF] = -1.0 / P[I_TAUF]
        jd[S_IP] = 0.0
        jd[S_IL] = 0.0
        jd[S_QF] = -1.0 / P[I_TAUFW]
        jd[S_V] = jv
        jd[st], jd[st + 1], jd[st + 2], jd[st + 3] = j1, j2, j3, j4
        jd[sm] = -1.0 / P[I_TAUM]
        # the mill on the boiler master's pressure integrator and pressure
        j = J_CHAIN1 + 10 * n + 2
        ok = 1.0 if 0.02 < u_f < 1.3 else 0.0
        jl[j] = ok / P[I_TAUM]
        jl[j + 1] = -ok * P[I_KPP] / P[I_PSP] / P[I_TAUM]
        # thermowells on the main-steam line outlet and on the attemperator's inputs
        j = j_line + nl
        jl[j] = dT_out / tc1
        jl[j + 1] = 1.0 / tc2
        for k in range(3):
            jl[j + 2 + k] = dT_att * dh_att[k] / tc1
        jl[j + 5] = 1.0 / tc2
        ok = 1.0 if q_fd > 0.0 else 0.0
        jl[J_QF] = ok * dWok / P[I_TAUFW]
        jl[J_QF + 1] = ok / P[I_TAUFW]


@njit(cache=True)
def outputs(x, u, d, P, z):
    """Physical outputs (order of DrumBoilerSH.outputs)."""
    n = int(P[I_N])
    c2 = S_CHAIN1 + 2 * n
    W, lw, dWok, q_s, w_sp, dw_dv, h_f, dhf, h_sp, p1, p2, dp1, dp2, L_f, mult = _boundary(x, d, P)
    h1 = x[c2 - 1]
    _, h_att = mix(q_s, h1, w_sp, h_sp)
    nl = int(P[I_NL])
    T_sh2, _ = T_dTdh_ph(p2, x[c2 + 2 * n - 1])
    T_out, _ = T_dTdh_ph(p2, x[s_line(n) + nl - 1])
    T_att, _ = T_dTdh_ph(p1, h_att)
    T_pri, _ = T_dTdh_ph(p1, h1)
    UAg1 = P[I_UAG1] * mult
    Tg1 = P[I_TG1] - P[I_DTG1] * (1.0 - L_f)
    UAg2 = P[I_UAG2] * mult
    Tg2 = P[I_TG2] - P[I_DTG2] * (1.0 - L_f)
    q = 0.0
    tm_max = 0.0
    for i in range(n):
        tm1 = x[S_CHAIN1 + 2 * i]
        tm2 = x[c2 + 2 * i]
        q += UAg1 * (Tg1 - tm1) + UAg2 * (Tg2 - tm2)
        tm_max = max(tm_max, tm1, tm2)
    Ts, rw, rs, hw, hs, dTs, drw, drs, dhw, dhs = sat_p(x[S_P])
    av, _, _ = dr.void_fraction(rw, rs, drw, drs, x[S_DRUM + dr.AR])
    z[Z_TOUT] = T_out - K0
    z[Z_TOUTM] = x[sensors(n, nl) + T_TC2] - K0
    z[Z_TATT] = T_att - K0
    z[Z_TATTM] = x[sensors(n, nl) + T_TA2] - K0
    z[Z_TPRI] = T_pri - K0
    z[Z_W] = W
    z[Z_PD] = x[S_P] * 1e-6
    z[Z_LEVEL] = dr.drum_level(x, S_DRUM, P, I_DRUM)
    z[Z_QF] = x[S_QF]
    z[Z_LF] = x[S_LF]
    z[Z_V] = min(max(x[S_V], 0.0), 1.0)
    z[Z_WSP] = w_sp
    z[Z_PMS] = p2 * 1e-6
    z[Z_QS] = q_s
    z[Z_QSH] = q * 1e-6
    z[Z_QEV] = L_f * P[I_QNOM] * 1e-6
    z[Z_TMMAX] = tm_max - K0
    z[Z_AR] = x[S_DRUM + dr.AR]
    z[Z_QDC] = dr.circulation(rw, rs, av, P, I_DRUM)
    z[Z_DSP] = _design_spray(P, lw)
    z[Z_TSH2] = T_sh2 - K0
    z[Z_MILL] = x[s_mill(n)]


@njit(cache=True)
def project(x, P):
    """Keep states inside their physical ranges after a step."""
    n = int(P[I_N])
    Wn = P[I_WNOM]
    x[S_W] = min(max(x[S_W], 0.0), 1.3 * Wn)
    x[S_LF] = min(max(x[S_LF], 0.02), 1.3)
    x[s_mill(n)] = min(max(x[s_mill(n)], 0.02), 1.3)
    for k in range(int(P[I_NL])):
        x[s_line(n) + k] = min(max(x[s_line(n) + k], 1.5e6), 4.2e6)
    x[S_IP] = min(max(x[S_IP], -0.6), 0.6)
    x[S_IL] = min(max(x[S_IL], -0.5 * Wn), 0.5 * Wn)
    x[S_QF] = min(max(x[S_QF], 0.0), 2.0 * Wn)
    x[S_V] = min(max(x[S_V], 0.0), 1.0)
    vt = P[I_DRUM + dr.D_VT]
    x[S_DRUM + dr.VWT] = min(max(x[S_DRUM + dr.VWT], 0.3 * vt), 0.97 * vt)
    x[S_P] = min(max(x[S_P], 1.0e6), 18.0e6)
    x[S_DRUM + dr.AR] = min(max(x[S_DRUM + dr.AR], 1e-4), 0.8)
    x[S_DRUM + dr.VSD] = min(max(x[S_DRUM + dr.VSD], 0.0), 0.5 * vt)
    for i in range(4 * n):
        j = S_CHAIN1 + i
        if i % 2 == 0:
            x[j] = min(max(x[j], 400.0), 1300.0)
        else:
            x[j] = min(max(x[j], 2.0e6), 4.2e6)


@njit(cache=True)
def _steady_at(x, v, d, P):
    """Steady plant state for valve opening v at x[S_W] (drum, firing, chains written into x).

    Returns the main-steam enthalpy (J/kg).
    """
    n = int(P[I_N])
    c2 = S_CHAIN1 + 2 * n
    x[S_V] = v
    w_prev = -1.0
    h_out = 0.0
    # fixed point on the spray: the protection cap depends on the primary SH outlet
    for _ in range(30):
        bd = _boundary(x, d, P)
        q_s, h_f = bd[3], bd[6]
        Q, _ = dr.drum_steady(P[I_PSP], q_s, h_f, 0.0, P, I_DRUM, x, S_DRUM)
        L_f = Q / P[I_QNOM]
        x[S_LF] = L_f
        x[s_mill(n)] = L_f
        x[S_QF] = q_s
        x[S_IL] = 0.0
        x[S_IP] = L_f - min(max(d[D_LOAD], 0.0), 1.3) - P[I_TBIR] * d[D_LOAD_RATE]
        W, lw, dWok, q_s, w_sp, dw_dv, h_f, dhf, h_sp, p1, p2, dp1, dp2, L_f, mult = _boundary(
            x, d, P
        )
        h_s = sat_p(P[I_PSP])[4]
        kA1 = steam_side_kA(P[I_KA1], q_s, P[I_QSN])[0]
        Tg1 = P[I_TG1] - P[I_DTG1] * (1.0 - L_f)
        h1 = chain_steady(x, S_CHAIN1, n, h_s, q_s, p1, kA1, P[I_UAG1] * mult, Tg1, 0.0)
        _, h_att = mix(q_s, h1, w_sp, h_sp)
        kA2 = steam_side_kA(P[I_KA2], W, P[I_WNOM])[0]
        Tg2 = P[I_TG2] - P[I_DTG2] * (1.0 - L_f)
        h_out = chain_steady(x, c2, n, h_att, W, p2, kA2, P[I_UAG2] * mult, Tg2, 0.0)
        if abs(w_sp - w_prev) < 1e-9:
            break
        w_prev = w_sp
    return h_out


@njit(cache=True)
def _outlet_T(x, v, d, P, p2):  # noqa: N803
    """Steady outlet temperature (K) at spray opening v and outlet pressure p2 (Pa)."""
    return T_dTdh_ph(p2, _steady_at(x, v, d, P))[0]


_opening_for = steady_opening("DrumBoilerSH", _outlet_T)


@njit(cache=True)
def steady(D, sp_K, P, X):
    """Steady state at each row's disturbances; spray valve set by bisection to hold sp_K."""
    for b in range(X.shape[0]):
        x = X[b]
        d = D[b]
        x[S_W] = min(max(d[D_LOAD], 0.05), 1.3) * P[I_WNOM]
        x[S_P] = P[I_PSP]
        p2 = P[I_PSP] - P[I_DPSH] * (x[S_W] / P[I_WNOM]) ** 2
        v = _opening_for(x, d, P, p2, sp_K[b])
        h_out = _steady_at(x, v, d, P)
        bd = _boundary(x, d, P)
        q_s, w_sp, h_sp, p1, p2 = bd[3], bd[4], bd[8], bd[9], bd[10]
        _, h_att = mix(q_s, x[S_CHAIN1 + 2 * int(P[I_N]) - 1], w_sp, h_sp)
        T_out, _ = T_dTdh_ph(p2, h_out)
        T_att, _ = T_dTdh_ph(p1, h_att)
        st = sensors(int(P[I_N]), int(P[I_NL]))
        pipe_steady(x, s_line(int(P[I_N])), int(P[I_NL]), h_out)
        x[st + T_TC1] = T_out
        x[st + T_TC2] = T_out
        x[st + T_TA1] = T_att
        x[st + T_TA2] = T_att


def _secant(fun, a: float, b: float, tol: float = 1e-6) -> float:
    """Root of fun by the secant method from a, b."""
    fa, fb = fun(a), fun(b)
    for _ in range(80):
        if fb == fa or abs(fb) < tol:
            break
        a, b, fa = b, b - fb * (b - a) / (fb - fa), fb
        fb = fun(b)
    return b


def _calibrate(params: DrumBoilerParams, P: np.ndarray, n_x: int) -> None:
    """Level reference, rated firing and SH gas-side conductances (writes P in place).

    Rated design: drum steam q_s,nom at p_drum and T_fw,nom, spray fraction s of the
    main steam W_nom = q_s,nom/(1 - s); UA_g1 gives T_primary_out after the primary SH,
    UA_g2 then gives T_out at the outlet.
    """
    x = np.zeros(n_x)
    n = params.n_segments
    c2 = S_CHAIN1 + 2 * n
    p = params.p_drum_MPa * 1e6
    q_s = params.q_s_nom_kg_s
    h_f, _, _ = _fw(P, P[I_TFW])
    # level reference: l = 0 at V_wt = V_wt,nom in the rated steady state
    P[I_DRUM + dr.D_L0] = 0.0
    Q, _ = dr.drum_steady(p, q_s, h_f, 0.0, P, I_DRUM, x, S_DRUM)
    P[I_QNOM] = Q
    dV = params.V_wt_nom_m3 - x[S_DRUM + dr.VWT]
    P[I_DRUM + dr.D_L0] = dV / params.A_d_m2
    # gas side at rated firing
    W = P[I_WNOM]
    w_sp = W - q_s
    dpsh = P[I_DPSH]
    p1, p2 = p - SHARE_1 * dpsh, p - dpsh
    h_s = float(sat_p(p)[4])
    h1_target = h_pT(p1, params.T_primary_out_C + K0)
    kA1 = steam_side_kA(P[I_KA1], q_s, q_s)[0]
    kA2 = steam_side_kA(P[I_KA2], W, W)[0]
    q1 = q_s * (h1_target - h_s) / n / 300.0
    P[I_UAG1] = _secant(
        lambda g: chain_steady(x, S_CHAIN1, n, h_s, q_s, p1, kA1, g, P[I_TG1], 0.0) - h1_target,
        q1, 1.2 * q1,
    )  # fmt: skip
    h_sp, rho_sp, _ = _fw(P, P[I_TFW])
    _, h_att = mix(q_s, h1_target, w_sp, h_sp)
    h_out = h_pT(p2, params.T_out_C + K0)
    q2 = W * (h_out - h_att) / n / 500.0
    P[I_UAG2] = _secant(
        lambda g: chain_steady(x, c2, n, h_att, W, p2, kA2, g, P[I_TG2], 0.0) - h_out,
        q2, 1.2 * q2,
    )  # fmt: skip
    P[I_CV] = params.spray_max_fraction * W / math.sqrt(rho_sp * P[I_DPSP])


@functools.lru_cache(maxsize=32)
def _pack(params: DrumBoilerParams) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    n = params.n_segments
    P = np.zeros(N_P)
    P[I_N] = n
    s = params.spray_design_fraction
    P[I_WNOM] = params.q_s_nom_kg_s / (1.0 - s)
    P[I_QSN] = params.q_s_nom_kg_s
    P[I_PSP] = params.p_drum_MPa * 1e6
    P[I_TFW] = params.T_fw_nom_C + K0
    P[I_DTFW] = params.dT_fw_dload_K
    P[I_DPSP] = params.dp_spray_MPa * 1e6
    P[I_DPSH] = params.dp_sh_nom_MPa * 1e6
    for i, (ika, iv, icm, itg, idtg) in enumerate(
        ((I_KA1, I_V1, I_CM1, I_TG1, I_DTG1), (I_KA2, I_V2, I_CM2, I_TG2, I_DTG2)), start=1
    ):
        nt = getattr(params, f"n_tubes_{i}")
        di, do = getattr(params, f"tube_id_{i}_m"), getattr(params, f"tube_od_{i}_m")
        seg = getattr(params, f"tube_length_{i}_m") / n
        P[ika] = params.alpha_nom_W_m2K * math.pi * di * seg * nt
        P[iv] = math.pi / 4.0 * di**2 * seg * nt
        P[icm] = (math.pi / 4.0 * (do**2 - di**2) * seg * nt * params.rho_metal_kg_m3
                  * params.c_metal_J_kgK)  # fmt: skip
        P[itg] = getattr(params, f"Tg{i}_nom_C") + K0
        P[idtg] = getattr(params, f"dTg{i}_dload_K")
    P[I_GEXP] = params.gas_flow_exponent
    P[I_TAUW] = params.tau_steam_s
    P[I_TAUF] = params.tau_firing_s
    P[I_KPP] = params.Kp_pressure
    P[I_TIP] = params.Ti_pressure_s
    P[I_KPL] = params.Kp_level_kg_s_m
    P[I_TIL] = params.Ti_level_s
    P[I_TAUFW] = params.tau_fw_s
    P[I_TAUV] = params.tau_valve_s
    P[I_RATEV] = params.valve_rate_per_s
    P[I_TC1] = params.tau_tc1_s
    P[I_TC2] = params.tau_tc2_s
    P[I_TAUM] = params.tau_mill_s
    P[I_TBIR] = params.T_bir_s
    P[I_NL] = params.n_line
    P[I_LV] = params.line_volume_m3 / params.n_line
    P[I_LCM] = params.line_metal_t * 1e3 * params.c_metal_J_kgK / params.n_line
    P[I_MARG] = params.attemp_margin_K
    P[I_DRUM : I_DRUM + dr.N_DRUM_P] = dr.drum_block(
        params.V_d_m3, params.V_r_m3, params.V_dc_m3, params.m_t_kg, params.m_r_kg,
        params.m_d_kg, params.C_p_J_kgK, params.A_d_m2, params.A_dc_m2, params.k_friction,
        params.beta, params.T_d_s, params.V_sd0_m3,
    )  # fmt: skip
    p_fw = params.p_fw_MPa * 1e6
    for k in range(N_FW):
        h = h_pT(p_fw, FW_T0_K + FW_DT_K * k)
        P[I_FW + k] = h
        P[I_FW + N_FW + k] = rho_ph(p_fw, h)
    n_x = S_CHAIN1 + 4 * n + 1 + params.n_line + 4
    _calibrate(params, P, n_x)
    # design-spray function generator: the undisturbed steady sprays at DSP_LOADS
    D = np.zeros((len(DSP_LOADS), 5))
    D[:, D_LOAD], D[:, D_FOULING] = DSP_LOADS, 1.0
    X = np.zeros((len(DSP_LOADS), n_x))
    steady(D, np.full(len(DSP_LOADS), params.T_out_C + K0), P, X)
    for k in range(len(DSP_LOADS)):
        P[I_DSP + k] = _boundary(X[k], D[k], P)[4]
    pat = pattern(n, params.n_line)
    jrow, jcol = pattern_arrays(pat)
    P.setflags(write=False)
    return P, jrow, jcol, n_x


#: compiled parts of the shared ROS2 kernel (bound here: in the class body
#: ``outputs`` names the Signal tuple)
KERNELS = (rhs, outputs, project)


class DrumBoilerSH(Plant):
    """Plant of ``steamtemp/DrumBoilerSH-v0`` (003_6ab8c34c4d0cb71f.txt with Astrom-Bell 2000)."""

    id = "steamtemp/DrumBoilerSH-v0"
    source = "003_6ab8c34c4d0cb71f.txt"
    Params = DrumBoilerParams
    actions = (Signal("spray_valve_cmd", "1", 0.5, 0.5, description="spray valve command"),)
    outputs = (
        Signal("outlet_temp_C", "C", 505.0, 20.0, observed=False, description="true main steam"),
        Signal("outlet_temp_meas_C", "C", 505.0, 20.0, noisy=True, description="thermocouple"),
        Signal("attemp_out_temp_C", "C", 390.0, 30.0, observed=False),
        Signal("attemp_out_temp_meas_C", "C", 390.0, 30.0, noisy=True),
        Signal("attemp_in_temp_C", "C", 440.0, 30.0, noisy=True, description="primary SH outlet"),
        Signal("steam_flow_kg_s", "kg/s", 39.0, 13.0, description="main steam flow"),
        Signal("drum_pressure_MPa", "MPa", 8.5, 0.5),
        Signal("drum_level_m", "m", 0.0, 0.2, description="above the normal water level"),
        Signal("feedwater_flow_kg_s", "kg/s", 37.5, 12.5),
        Signal("firing_rate", "1", 0.75, 0.3, description="firing, fraction of rated"),
        Signal("spray_valve", "1", 0.5, 0.5, description="valve position feedback"),
        Signal("spray_flow_kg_s", "kg/s", 2.5, 2.5),
        Signal("main_steam_pressure_MPa", "MPa", 8.2, 0.5),
        Signal("drum_steam_flow_kg_s", "kg/s", 37.5, 12.5, observed=False),
        Signal("heat_absorption_MW", "MW", 30.0, 10.0, observed=False, description="hidden, SH"),
        Signal("evaporator_heat_MW", "MW", 65.0, 21.0, observed=False),
        Signal("metal_temp_max_C", "C", 540.0, 40.0, observed=False),
        Signal("riser_exit_quality", "1", 0.05, 0.02, observed=False),
        Signal("downcomer_flow_kg_s", "kg/s", 1150.0, 100.0, observed=False),
        Signal(
            "design_spray_kg_s",
            "kg/s",
            2.0,
            2.0,
            observed=False,
            description="scheduled design spray (function generator over load)",
        ),
        Signal(
            "sh2_outlet_temp_C",
            "C",
            505.0,
            20.0,
            observed=False,
            description="final SH outlet, ahead of the outlet header and main-steam line",
        ),
        Signal("mill_output", "1", 0.75, 0.3, observed=False, description="coal to burners"),
    )
    design_spray = "design_spray_kg_s"
    setpoint_C = 505.0
    extra_info = (
        "attemp_out_temp_C", "heat_absorption_MW", "drum_pressure_MPa", "drum_level_m",
        "steam_flow_kg_s", "feedwater_flow_kg_s", "firing_rate",
    )  # fmt: skip

    pack = staticmethod(_pack)
    kernels = KERNELS
    actuators = ((S_V, I_TAUV, I_RATEV),)
    setpoint_param = "T_out_C"

    def steady_state(self, D: np.ndarray, setpoint_C: np.ndarray, X: np.ndarray) -> None:
        steady(D, setpoint_C + K0, self.P, X)
