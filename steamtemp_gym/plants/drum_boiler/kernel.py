"""Compiled physics of the drum boiler plant: the rhs, outputs and projection (see the
package docstring for the model).

Integration: ROS2 (integrator.py), one step per 2 s control interval. The matrix A
holds the stiff superheater couplings (chain_pattern, plus the firing column of every
metal row), the feedwater lag on steam flow and level integrator, the drum rows on the
states their inputs come from (exact sensitivities of the descriptor form by q_s, q_f,
Q and h_f) and the thermowells on what they measure (they come last in the state
vector so that these couplings are lower), the mill on the pressure loop, the line
lags on the final SH's outlet. Without the drum and firing columns the outlet error
against Radau over the 100 -> 50 % ramp was 0.22 K; with them 0.03 K (0.045 K with the
mill and line).
"""

from __future__ import annotations

import numpy as np

from steamtemp_gym._jit import njit
from steamtemp_gym.plants import drum as dr
from steamtemp_gym.plants.attemperator import mix, protected_spray_out, spray_flow
from steamtemp_gym.plants.base import D_FOULING, D_HEAT_BIAS, D_LOAD, D_LOAD_RATE, D_SPRAY_T, K0
from steamtemp_gym.plants.drum_boiler.layout import (
    DSP_LOADS,
    FW_DT_K,
    FW_T0_K,
    IJ,
    IP,
    IW,
    IX,
    IZ,
    N_FW,
    S_P,
    SHARE_1,
    s_line,
    s_mill,
    sensors,
)
from steamtemp_gym.plants.sensors import thermowell_rhs
from steamtemp_gym.plants.superheater import chain_rhs, pipe_rhs, steam_side_kA
from steamtemp_gym.steam import T_dTdh_ph, Tsat_p, h_pT, sat_p


@njit(cache=True)
def feedwater(P, T):
    """Feedwater (h J/kg, rho kg/m3, dh/dT J/(kg K)) at T (K): linear in the IF97 table at p_fw."""
    x = (min(max(T, FW_T0_K), FW_T0_K + FW_DT_K * (N_FW - 1)) - FW_T0_K) / FW_DT_K
    k = min(int(x), N_FW - 2)
    a = x - k
    o = IP.FW + k
    h = (1.0 - a) * P[o] + a * P[o + 1]
    return h, (1.0 - a) * P[o + N_FW] + a * P[o + N_FW + 1], (P[o + 1] - P[o]) / FW_DT_K


@njit(cache=True)
def boundary(x, d, P):
    """Algebraic quantities shared by rhs, outputs and the steady state.

    Returns (W, lw, dWok, q_s, w_sp, dw_dv, h_f, h_sp, p1, p2, dp1, dp2, L_f, UAg_mult)
    with dWok = 1 if W is inside its bounds (else 0), dw_dv = d(w_sp)/dv and dp1, dp2 the
    derivatives of the SH pressures by W.
    """
    Wn = P[IP.WNOM]
    W = min(max(x[IX.W], 0.05 * Wn), 1.3 * Wn)
    dWok = 1.0 if 0.05 * Wn < x[IX.W] < 1.3 * Wn else 0.0
    lw = W / Wn
    T_fw = P[IP.TFW] - P[IP.DTFW] * (1.0 - lw)
    h_f, _, cp_f = feedwater(P, T_fw)
    h_sp, rho_sp, _ = feedwater(P, T_fw + d[D_SPRAY_T])
    v = min(max(x[IX.V], 0.0), 1.0)
    cap = spray_flow(1.0, P[IP.CV], rho_sp, P[IP.DPSP])
    dpsh = P[IP.DPSH] * lw * lw
    p = x[S_P]
    p1 = p - SHARE_1 * dpsh
    p2 = p - dpsh
    # attemperator protection (built-in interlock): outlet >= Tsat(p_1) + margin
    h_min = h_pT(p1, Tsat_p(p1) + P[IP.MARG])
    w_max = protected_spray_out(0.5 * W, W, x[IX.CHAIN1 + 2 * int(P[IP.N]) - 1], h_sp, h_min)
    w_sp = min(v * cap, w_max)
    dw_dv = cap if v * cap < w_max else 0.0
    q_s = W - w_sp
    ddp = 2.0 * P[IP.DPSH] * lw / Wn * dWok
    L_f = min(max(x[IX.LF], 0.02), 1.3)
    mult = max(d[D_FOULING] * (1.0 + d[D_HEAT_BIAS]), 0.0) * L_f ** P[IP.GEXP]
    dhf = cp_f * P[IP.DTFW] / Wn * dWok
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
    return max((1.0 - a) * P[IP.DSP + k] + a * P[IP.DSP + k + 1], 0.0)


@njit(cache=True)
def _firing_demand(x, d, P):
    """Boiler-master firing demand (fraction) and the pressure error (relative)."""
    e = (P[IP.PSP] - x[S_P]) / P[IP.PSP]
    demand = d[D_LOAD] + P[IP.TBIR] * d[D_LOAD_RATE] + P[IP.KPP] * e + x[IX.IP]
    return min(max(demand, 0.02), 1.3), e


@njit(cache=True)
def _chain_fired(
    x,
    off,
    n,
    n_in,
    h0,
    dh0,
    W,
    dW,
    p,
    dp,
    kA,
    UAg,
    Tg,
    dUAg,
    dTg,
    Cm,
    V,
    f,
    jd,
    ju,
    jl,
    joff,
    want_jac,
):
    """chain_rhs plus the firing column of every metal row (pattern: :func:`fired_pattern`).

    chain_rhs writes its own entries n places further on; they are then moved down to
    make room for d(metal_i)/d(L_f) = (dUA_g/dL_f (T_g - T_m,i) + UA_g dT_g/dL_f)/C_m
    before each metal row's entry (a forward in-place move: every destination index is
    at most its source).
    """
    _, T_out, _ = chain_rhs(
        x,
        off,
        n,
        h0,
        dh0,
        W,
        dW,
        p,
        dp,
        kA[0],
        kA[1],
        V,
        Cm,
        UAg,
        Tg,
        0.0,
        f,
        jd,
        ju,
        jl,
        joff + n,
        want_jac,
        True,
    )
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


@njit(cache=True)
def rhs(x, u, d, P, f, jd, ju, jl, want_jac):
    """dx/dt of the drum boiler plant (see package docstring); pattern from :func:`pattern`."""
    n = int(P[IP.N])
    c2 = IX.CHAIN1 + 2 * n
    W, lw, dWok, q_s, w_sp, dw_dv, h_f, dhf, h_sp, p1, p2, dp1, dp2, L_f, mult = boundary(x, d, P)
    # turbine load controller, boiler master, feedwater
    f[IX.W] = (min(max(d[D_LOAD], 0.0), 1.3) * P[IP.WNOM] - x[IX.W]) / P[IP.TAUW]
    u_f, e_p = _firing_demand(x, d, P)
    sm = s_mill(n)
    f[sm] = (u_f - x[sm]) / P[IP.TAUM]
    f[IX.LF] = (x[sm] - x[IX.LF]) / P[IP.TAUF]
    f[IX.IP] = P[IP.KPP] / P[IP.TIP] * e_p
    dLf = 1.0 if 0.02 < x[IX.LF] < 1.3 else 0.0
    Qn = P[IP.QNOM]
    level, qdc, q_r, h_s, dh_s, sens = dr.drum_rhs(
        x, IX.DRUM, P, IP.DRUM, q_s, x[IX.QF], h_f, L_f * Qn, f, jd, want_jac
    )
    if want_jac:
        # drum rows on (W, L_f, q_f, v) = DRUM_INPUT_COLS: q_s = W - w_sp(v), Q = L_f Q_nom
        for r in range(4):
            s_qs, s_qf, s_q, s_hf = sens[4 * r], sens[4 * r + 1], sens[4 * r + 2], sens[4 * r + 3]
            j = IJ.DRUM + 4 * r
            jl[j] = s_qs * dWok + s_hf * dhf
            jl[j + 1] = s_q * Qn * dLf
            jl[j + 2] = s_qf
            jl[j + 3] = -s_qs * dw_dv
    f[IX.IL] = -P[IP.KPL] / P[IP.TIL] * level
    q_fd = q_s - P[IP.KPL] * level + x[IX.IL]
    f[IX.QF] = (max(q_fd, 0.0) - x[IX.QF]) / P[IP.TAUFW]
    f[IX.V], jv = u[0], 0.0  # exact chord velocity of the valve (plants/integrator.py)
    # primary superheater: saturated steam at q_s
    gex = P[IP.GEXP] * dLf / L_f
    UAg1 = P[IP.UAG1] * mult
    Tg1 = P[IP.TG1] - P[IP.DTG1] * (1.0 - L_f)
    # inlet derivatives (arrays only in the Jacobian call; chain_rhs reads them only then)
    dh0 = np.array([dh_s]) if want_jac else f[0:1]
    _chain_fired(
        x,
        IX.CHAIN1,
        n,
        1,
        h_s,
        dh0,
        q_s,
        dWok,
        p1,
        dp1,
        steam_side_kA(P[IP.KA1], q_s, P[IP.QSN]),
        UAg1,
        Tg1,
        gex * UAg1,
        P[IP.DTG1] * dLf,
        P[IP.CM1],
        P[IP.V1],
        f,
        jd,
        ju,
        jl,
        IJ.CHAIN1,
        want_jac,
    )
    # attemperator and final superheater at W
    h1 = x[c2 - 1]
    _, h_att = mix(q_s, h1, w_sp, h_sp)
    if want_jac:
        dh_att = np.array([w_sp * (h1 - h_sp) / (W * W) * dWok, (h_sp - h1) * dw_dv / W, q_s / W])
    else:
        dh_att = f[0:3]
    UAg2 = P[IP.UAG2] * mult
    Tg2 = P[IP.TG2] - P[IP.DTG2] * (1.0 - L_f)
    _chain_fired(
        x,
        c2,
        n,
        3,
        h_att,
        dh_att,
        W,
        dWok,
        p2,
        dp2,
        steam_side_kA(P[IP.KA2], W, P[IP.WNOM]),
        UAg2,
        Tg2,
        gex * UAg2,
        P[IP.DTG2] * dLf,
        P[IP.CM2],
        P[IP.V2],
        f,
        jd,
        ju,
        jl,
        IJ.CHAIN1 + 5 * n,
        want_jac,
    )
    # outlet header and main-steam line (superheater.pipe_rhs; package docstring)
    nl = int(P[IP.NL])
    j_line = IJ.CHAIN1 + 10 * n + 4  # after the mill's two entries
    T_out, dT_out = pipe_rhs(
        x,
        s_line(n),
        nl,
        x[c2 + 2 * n - 1],
        (1.0,),
        W,
        0.0,
        p2,
        P[IP.LV],
        P[IP.LCM],
        f,
        jd,
        jl,
        j_line,
        want_jac,
        False,
    )
    T_att, dT_att = T_dTdh_ph(p1, h_att)
    st = sensors(n, nl)
    tc1, tc2 = P[IP.TC1], P[IP.TC2]
    f[st], f[st + 1], j1, j2 = thermowell_rhs(T_out, x[st], x[st + 1], tc1, tc2)
    f[st + 2], f[st + 3], j3, j4 = thermowell_rhs(T_att, x[st + 2], x[st + 3], tc1, tc2)
    if want_jac:
        jd[IX.W] = -1.0 / P[IP.TAUW]
        jd[IX.LF] = -1.0 / P[IP.TAUF]
        jd[IX.IP] = 0.0
        jd[IX.IL] = 0.0
        jd[IX.QF] = -1.0 / P[IP.TAUFW]
        jd[IX.V] = jv
        jd[st], jd[st + 1], jd[st + 2], jd[st + 3] = j1, j2, j3, j4
        jd[sm] = -1.0 / P[IP.TAUM]
        # the mill on the boiler master's pressure integrator and pressure
        j = IJ.CHAIN1 + 10 * n + 2
        ok = 1.0 if 0.02 < u_f < 1.3 else 0.0
        jl[j] = ok / P[IP.TAUM]
        jl[j + 1] = -ok * P[IP.KPP] / P[IP.PSP] / P[IP.TAUM]
        # thermowells on the main-steam line outlet and on the attemperator's inputs
        j = j_line + nl
        jl[j] = dT_out / tc1
        jl[j + 1] = 1.0 / tc2
        for k in range(3):
            jl[j + 2 + k] = dT_att * dh_att[k] / tc1
        jl[j + 5] = 1.0 / tc2
        ok = 1.0 if q_fd > 0.0 else 0.0
        jl[IJ.QF] = ok * dWok / P[IP.TAUFW]
        jl[IJ.QF + 1] = ok / P[IP.TAUFW]


@njit(cache=True)
def outputs(x, u, d, P, z):
    """Physical outputs (order of DrumBoilerSH.outputs)."""
    n = int(P[IP.N])
    c2 = IX.CHAIN1 + 2 * n
    W, lw, dWok, q_s, w_sp, dw_dv, h_f, dhf, h_sp, p1, p2, dp1, dp2, L_f, mult = boundary(x, d, P)
    h1 = x[c2 - 1]
    _, h_att = mix(q_s, h1, w_sp, h_sp)
    nl = int(P[IP.NL])
    T_sh2, _ = T_dTdh_ph(p2, x[c2 + 2 * n - 1])
    T_out, _ = T_dTdh_ph(p2, x[s_line(n) + nl - 1])
    T_att, _ = T_dTdh_ph(p1, h_att)
    T_pri, _ = T_dTdh_ph(p1, h1)
    UAg1 = P[IP.UAG1] * mult
    Tg1 = P[IP.TG1] - P[IP.DTG1] * (1.0 - L_f)
    UAg2 = P[IP.UAG2] * mult
    Tg2 = P[IP.TG2] - P[IP.DTG2] * (1.0 - L_f)
    q = 0.0
    tm_max = 0.0
    for i in range(n):
        tm1 = x[IX.CHAIN1 + 2 * i]
        tm2 = x[c2 + 2 * i]
        q += UAg1 * (Tg1 - tm1) + UAg2 * (Tg2 - tm2)
        tm_max = max(tm_max, tm1, tm2)
    Ts, rw, rs, hw, hs, dTs, drw, drs, dhw, dhs = sat_p(x[S_P])
    av, _, _ = dr.void_fraction(rw, rs, drw, drs, x[IX.DRUM + dr.AR])
    z[IZ.outlet_temp_C] = T_out - K0
    z[IZ.outlet_temp_meas_C] = x[sensors(n, nl) + IW.TC2] - K0
    z[IZ.attemp_out_temp_C] = T_att - K0
    z[IZ.attemp_out_temp_meas_C] = x[sensors(n, nl) + IW.TA2] - K0
    z[IZ.attemp_in_temp_C] = T_pri - K0
    z[IZ.steam_flow_kg_s] = W
    z[IZ.drum_pressure_MPa] = x[S_P] * 1e-6
    z[IZ.drum_level_m] = dr.drum_level(x, IX.DRUM, P, IP.DRUM)
    z[IZ.feedwater_flow_kg_s] = x[IX.QF]
    z[IZ.firing_rate] = x[IX.LF]
    z[IZ.spray_valve] = min(max(x[IX.V], 0.0), 1.0)
    z[IZ.spray_flow_kg_s] = w_sp
    z[IZ.main_steam_pressure_MPa] = p2 * 1e-6
    z[IZ.drum_steam_flow_kg_s] = q_s
    z[IZ.heat_absorption_MW] = q * 1e-6
    z[IZ.evaporator_heat_MW] = L_f * P[IP.QNOM] * 1e-6
    z[IZ.metal_temp_max_C] = tm_max - K0
    z[IZ.riser_exit_quality] = x[IX.DRUM + dr.AR]
    z[IZ.downcomer_flow_kg_s] = dr.circulation(rw, rs, av, P, IP.DRUM)
    z[IZ.design_spray_kg_s] = _design_spray(P, lw)
    z[IZ.sh2_outlet_temp_C] = T_sh2 - K0
    z[IZ.mill_output] = x[s_mill(n)]


@njit(cache=True)
def project(x, P):
    """Keep states inside their physical ranges after a step."""
    n = int(P[IP.N])
    Wn = P[IP.WNOM]
    x[IX.W] = min(max(x[IX.W], 0.0), 1.3 * Wn)
    x[IX.LF] = min(max(x[IX.LF], 0.02), 1.3)
    x[s_mill(n)] = min(max(x[s_mill(n)], 0.02), 1.3)
    for k in range(int(P[IP.NL])):
        x[s_line(n) + k] = min(max(x[s_line(n) + k], 1.5e6), 4.2e6)
    x[IX.IP] = min(max(x[IX.IP], -0.6), 0.6)
    x[IX.IL] = min(max(x[IX.IL], -0.5 * Wn), 0.5 * Wn)
    x[IX.QF] = min(max(x[IX.QF], 0.0), 2.0 * Wn)
    x[IX.V] = min(max(x[IX.V], 0.0), 1.0)
    vt = P[IP.DRUM + dr.D_VT]
    x[IX.DRUM + dr.VWT] = min(max(x[IX.DRUM + dr.VWT], 0.3 * vt), 0.97 * vt)
    x[S_P] = min(max(x[S_P], 1.0e6), 18.0e6)
    x[IX.DRUM + dr.AR] = min(max(x[IX.DRUM + dr.AR], 1e-4), 0.8)
    x[IX.DRUM + dr.VSD] = min(max(x[IX.DRUM + dr.VSD], 0.0), 0.5 * vt)
    for i in range(4 * n):
        j = IX.CHAIN1 + i
        if i % 2 == 0:
            x[j] = min(max(x[j], 400.0), 1300.0)
        else:
            x[j] = min(max(x[j], 2.0e6), 4.2e6)


#: compiled parts of the shared ROS2 kernel (bound here: in the class body
#: ``outputs`` names the Signal tuple)
KERNELS = (rhs, outputs, project)
