"""Compiled physics of the supercritical final superheater: the rhs, outputs and
projection of the shared ROS2 kernel (plants/integrator.py), and the boundary conditions
they share (see the package docstring for the model)."""

from __future__ import annotations

import numpy as np

from steamtemp_gym._jit import njit
from steamtemp_gym.plants.attemperator import mix, protected_spray_out, spray_flow
from steamtemp_gym.plants.base import (
    D_FOULING,
    D_HEAT_BIAS,
    D_LOAD,
    D_LOAD_RATE,
    D_SPRAY_T,
    K0,
)
from steamtemp_gym.plants.sensors import thermowell_rhs
from steamtemp_gym.plants.supercritical_fsh.layout import IP, IX, IZ, N_TAB, s_line, s_mill
from steamtemp_gym.plants.supercritical_fsh.params import P_CRIT_PA
from steamtemp_gym.plants.superheater import (
    chain_rhs,
    pipe_rhs,
    steam_side_kA,
)
from steamtemp_gym.steam import T_dTdh_ph, Tsat_p, h_pT


@njit(cache=True, error_model="numpy")
def pressure(P, lw):
    """Sliding pressure (Pa) at steam-flow fraction lw."""
    lo, hi = P[IP.SLL], P[IP.SLH]
    r = min(max((lw - lo) / (hi - lo), 0.0), 1.0)
    return P[IP.PMIN] + r * (P[IP.PNOM] - P[IP.PMIN])


@njit(cache=True, error_model="numpy")
def table(P, off, load):
    """Linear interpolation of a schedule table stored in P over TAB_LOADS."""
    x = (min(max(load, 0.2), 1.2) - 0.2) / 0.05
    k = min(int(x), N_TAB - 2)
    a = x - k
    return (1.0 - a) * P[off + k] + a * P[off + k + 1]


@njit(cache=True, error_model="numpy")
def spray_water(P, lw, dT):
    """Spray water (h J/kg, rho kg/m3, valve dp Pa) at steam-flow fraction lw and offset dT (K).

    Feed-pump discharge water, tabulated over load from IF97 at pack time; the
    temperature offset enters by a second-order Taylor step in T
    (h + cp dT + dcp/dT dT^2 / 2; error < 0.05 kJ/kg at +-15 K).
    """
    cp = table(P, IP.CPFW, lw)
    h = table(P, IP.HFW, lw) + dT * (cp + 0.5 * dT * table(P, IP.DCPFW, lw))
    return h, table(P, IP.RHOFW, lw), P[IP.DPB] * lw * lw


@njit(cache=True, error_model="numpy")
def spray_enthalpies(P, flow_fraction):
    """Spray-water enthalpy (J/kg, no temperature offset) at each steam-flow fraction,
    clipped to the tables' 0.05-1.3 as the plant clips its own."""
    out = np.empty(flow_fraction.shape[0])
    for b in range(out.shape[0]):
        out[b] = spray_water(P, min(max(flow_fraction[b], 0.05), 1.3), 0.0)[0]
    return out


@njit(cache=True, error_model="numpy")
def boundary(x, u, d, P):
    """Algebraic part shared by rhs and outputs.

    Returns (W, p, w_sp, h0, h_sp, kA_seg, UAg_seg, Tg, capped) for state x, command u,
    disturbance d. kA_seg is the pair (kA, dkA/dW); capped: the spray is limited below the
    valve's flow (attemperator protection or the 0.5 W bound), so the valve has no effect.
    """
    lw = min(max(x[IX.LW], 0.05), 1.3)
    lf = min(max(x[IX.LF], 0.05), 1.3)
    W = lw * P[IP.WNOM]
    p = pressure(P, lw)
    h_sp, rho_sp, dp = spray_water(P, lw, d[D_SPRAY_T])
    w_valve = spray_flow(x[IX.V], P[IP.CV], rho_sp, dp)
    w_sp = min(w_valve, 0.5 * W)
    if p < P_CRIT_PA - 0.5e6:  # subcritical: the attemperator protection (module docstring)
        h_min = h_pT(p, Tsat_p(p) + P[IP.MARG])
        w_sp = protected_spray_out(w_sp, W, x[IX.HUP], h_sp, h_min)
    capped = w_sp < w_valve
    _, h0 = mix(W - w_sp, x[IX.HUP], w_sp, h_sp)
    kA = steam_side_kA(P[IP.KA], W, P[IP.WNOM])
    gas = max(d[D_FOULING] * (1.0 + d[D_HEAT_BIAS]), 0.0)
    UAg = P[IP.UAG] * lf ** P[IP.GEXP] * gas
    Tg = P[IP.TGN] - P[IP.DTG] * (1.0 - lf)
    return W, p, w_sp, h0, h_sp, kA, UAg, Tg, capped


@njit(cache=True, error_model="numpy")
def h_up_target(P, lf, lw, bias):
    """Upstream SH outlet enthalpy: fuel/water-ratio schedule, its error and ratio error.

    ``bias`` is the relative heat-absorption error (D[2]); its share bias_upstream_share
    of the enthalpy rise from the feedwater reaches the upstream superheaters' outlet.
    """
    lw = min(max(lw, 0.05), 1.3)
    lf = min(max(lf, 0.05), 1.3)
    h_up = table(P, IP.HUP, lw)
    dh_rise = table(P, IP.DHUP, lw)
    mis = P[IP.MIS] * 4.0 * lw * (1.0 - lw)  # FWR schedule error, zero at rated load
    return h_up + (P[IP.FWR] * (lf / lw - 1.0) + mis + P[IP.BUP] * bias) * dh_rise


@njit(cache=True, error_model="numpy")
def _dpressure(P, lw):
    """d(sliding pressure)/d(steam-flow fraction) (Pa)."""
    if P[IP.SLL] < lw < P[IP.SLH]:
        return (P[IP.PNOM] - P[IP.PMIN]) / (P[IP.SLH] - P[IP.SLL])
    return 0.0


@njit(cache=True, error_model="numpy")
def rhs(x, u, d, P, f, jd, ju, jl, want_jac):
    """dx/dt of the FSH plant (see module docstring); Jacobian pattern from FSHPlant.pack."""
    n = int(P[IP.N])
    sm = s_mill(n)
    fd = min(max(d[D_LOAD] + P[IP.TBIR] * d[D_LOAD_RATE], 0.05), 1.3)
    f[sm] = (fd - x[sm]) / P[IP.TAUM]
    f[IX.LF] = (x[sm] - x[IX.LF]) / P[IP.TAUF]
    f[IX.LW] = (d[D_LOAD] - x[IX.LW]) / P[IP.TAUW]
    f[IX.HUP] = (h_up_target(P, x[IX.LF], x[IX.LW], d[D_HEAT_BIAS]) - x[IX.HUP]) / P[IP.TAUUP]
    f[IX.V] = u[0]  # exact chord velocity of the valve (plants/integrator.py)
    W, p, w_sp, h0, h_sp, kA, UAg, Tg, capped = boundary(x, u, d, P)
    # dh0/d(h_up) and dh0/dv (attemperator balance, linear valve), order of INLET_COLS
    v = min(max(x[IX.V], 1e-6), 1.0)
    dh0 = ((W - w_sp) / W, (h_sp - x[IX.HUP]) * w_sp / v / W)
    if capped:
        dh0 = (dh0[0], 0.0)
    dW = P[IP.WNOM] if 0.05 < x[IX.LW] < 1.3 else 0.0
    dp = _dpressure(P, x[IX.LW])
    _, _, _ = chain_rhs(
        x,
        IX.CHAIN,
        n,
        h0,
        dh0,
        W,
        dW,
        p,
        dp,
        kA[0],
        kA[1],
        P[IP.V],
        P[IP.CM],
        UAg,
        Tg,
        0.0,
        f,
        jd,
        ju,
        jl,
        0,
        want_jac,
        True,
    )
    # outlet header and main-steam line (superheater.pipe_rhs; module docstring)
    T_out, _ = pipe_rhs(
        x,
        s_line(n),
        int(P[IP.NL]),
        x[IX.CHAIN + 2 * n - 1],
        (1.0,),
        W,
        0.0,
        p,
        P[IP.LV],
        P[IP.LCM],
        f,
        jd,
        jl,
        4 * n + 1,
        want_jac,
        False,
    )
    T_att, _ = T_dTdh_ph(p, h0)
    f[IX.TC1], f[IX.TC2], j1, j2 = thermowell_rhs(T_out, x[IX.TC1], x[IX.TC2], P[IP.TC1], P[IP.TC2])
    f[IX.TA1], f[IX.TA2], j3, j4 = thermowell_rhs(T_att, x[IX.TA1], x[IX.TA2], P[IP.TC1], P[IP.TC2])
    if want_jac:
        jd[IX.LF] = -1.0 / P[IP.TAUF]
        jd[IX.LW] = -1.0 / P[IP.TAUW]
        jd[IX.HUP] = -1.0 / P[IP.TAUUP]
        jd[IX.V] = 0.0
        jd[IX.TC1], jd[IX.TC2], jd[IX.TA1], jd[IX.TA2] = j1, j2, j3, j4
        jd[sm] = -1.0 / P[IP.TAUM]


@njit(cache=True, error_model="numpy")
def outputs(x, u, d, P, z):
    """Physical outputs (order of FSHPlant.outputs)."""
    n = int(P[IP.N])
    W, p, w_sp, h0, h_sp, kA, UAg, Tg, capped = boundary(x, u, d, P)
    T_fsh, _ = T_dTdh_ph(p, x[IX.CHAIN + 2 * n - 1])
    T_out, _ = T_dTdh_ph(p, x[s_line(n) + int(P[IP.NL]) - 1])
    T_att, _ = T_dTdh_ph(p, h0)
    T_up, _ = T_dTdh_ph(p, x[IX.HUP])
    q = 0.0
    tm_max = 0.0
    for i in range(n):
        tm = x[IX.CHAIN + 2 * i]
        q += UAg * (Tg - tm)
        tm_max = max(tm_max, tm)
    z[IZ.outlet_temp_C] = T_out - K0
    z[IZ.outlet_temp_meas_C] = x[IX.TC2] - K0
    z[IZ.attemp_out_temp_C] = T_att - K0
    z[IZ.attemp_out_temp_meas_C] = x[IX.TA2] - K0
    z[IZ.attemp_in_temp_C] = T_up - K0
    z[IZ.steam_flow_kg_s] = W
    z[IZ.pressure_MPa] = p * 1e-6
    z[IZ.spray_valve] = x[IX.V]
    z[IZ.spray_flow_kg_s] = w_sp
    z[IZ.firing_rate] = x[IX.LF]
    z[IZ.heat_absorption_MW] = q * 1e-6
    z[IZ.metal_temp_max_C] = tm_max - K0
    z[IZ.design_spray_kg_s] = P[IP.SPD] * W
    z[IZ.fsh_outlet_temp_C] = T_fsh - K0
    z[IZ.mill_output] = x[s_mill(n)]


@njit(cache=True, error_model="numpy")
def project(x, P):
    """Keep states inside their physical ranges after a step."""
    n = int(P[IP.N])
    x[IX.V] = min(max(x[IX.V], 0.0), 1.0)
    x[IX.LF] = min(max(x[IX.LF], 0.05), 1.3)
    x[IX.LW] = min(max(x[IX.LW], 0.05), 1.3)
    x[IX.HUP] = min(max(x[IX.HUP], 2.0e6), 4.0e6)
    x[s_mill(n)] = min(max(x[s_mill(n)], 0.05), 1.3)
    for k in range(int(P[IP.NL])):
        x[s_line(n) + k] = min(max(x[s_line(n) + k], 1.5e6), 4.2e6)
    for i in range(n):
        x[IX.CHAIN + 2 * i] = min(max(x[IX.CHAIN + 2 * i], 400.0), 1300.0)
        x[IX.CHAIN + 2 * i + 1] = min(max(x[IX.CHAIN + 2 * i + 1], 1.5e6), 4.2e6)


#: compiled parts of the shared ROS2 kernel (bound here: in the class body
#: ``outputs`` names the Signal tuple)
KERNELS = (rhs, outputs, project)
