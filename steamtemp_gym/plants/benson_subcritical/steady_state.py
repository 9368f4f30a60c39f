"""Steady state of the Benson boiler under the unit controllers, and the section
enthalpies and temperatures of a state."""

from __future__ import annotations

import numpy as np

from steamtemp_gym._jit import njit
from steamtemp_gym.plants.attemperator import mix
from steamtemp_gym.plants.base import D_LOAD, D_LOAD_RATE, K0
from steamtemp_gym.plants.benson_subcritical.kernel import (
    boundary,
    cold_reheat,
    firing,
    gas_side,
    h_ev_setpoint,
    last_h,
    p_setpoint,
    reheat,
    section_param,
    table,
)
from steamtemp_gym.plants.benson_subcritical.layout import IF, IP, ITB, IX
from steamtemp_gym.plants.benson_subcritical.params import P_SHARE, SEC
from steamtemp_gym.plants.superheater import chain_steady, pipe_steady, steam_side_kA
from steamtemp_gym.plants.valve import steady_opening
from steamtemp_gym.steam import T_ph, h_pT


@njit(cache=True)
def section_steady(x, P, k, h0, W, p, lf, d):
    """Steady state of section k written into x; returns its outlet enthalpy."""
    kA = steam_side_kA(section_param(P, k, IF.KA), W, section_param(P, k, IF.WN))[0]
    UAg, Tg, Qrad = gas_side(P, k, lf, d)
    return chain_steady(
        x,
        int(section_param(P, k, IF.OFF)),
        int(section_param(P, k, IF.N)),
        h0,
        W,
        p,
        kA,
        UAg,
        Tg,
        Qrad,
    )


@njit(cache=True)
def upstream_steady(x, d, P, lf, p):
    """Economizer and evaporator steady at firing lf, pressure p; returns evaporator outlet h."""
    L, r2, W_eco, _, _, h_fw, _, _, _ = boundary(x, d, P)
    dpb = P[IP.DPB] * r2
    h = section_steady(x, P, SEC.ECO, h_fw, W_eco, p + P_SHARE[SEC.ECO] * dpb, lf, d)
    return section_steady(x, P, SEC.EV, h, W_eco, p + P_SHARE[SEC.EV] * dpb, lf, d)


@njit(cache=True)
def sh_steady(x, d, P, lf, p, upto):
    """SH1..SH4 steady (x holds the evaporator and valves); SH3 outlet h (upto=3) or main h."""
    L, r2, W_eco, w1, w2, _, h_sp, p_a1, p_a2 = boundary(x, d, P)
    dpb = P[IP.DPB] * r2
    h_ev = last_h(x, P, SEC.EV)
    h = section_steady(x, P, SEC.SH1, h_ev, W_eco, p + P_SHARE[SEC.SH1] * dpb, lf, d)
    h = section_steady(x, P, SEC.SH2, h, W_eco, p_a1, lf, d)
    W3, h = mix(W_eco, h, w1, h_sp)
    h = section_steady(x, P, SEC.SH3, h, W3, p_a2, lf, d)
    if upto == 3:
        return h
    W4, h = mix(W3, h, w2, h_sp)
    return section_steady(x, P, SEC.SH4, h, W4, p, lf, d)


@njit(cache=True)
def _fuel_for_evap(x, d, P, p, h_target, lf0):
    """Firing fraction that makes the evaporator outlet enthalpy h_target (secant)."""
    a, b = lf0, lf0 * 1.02
    fa = upstream_steady(x, d, P, a, p) - h_target
    fb = upstream_steady(x, d, P, b, p) - h_target
    for _ in range(40):
        if fb == fa or abs(fb) < 1e-3:
            break
        c = min(max(b - fb * (b - a) / (fb - fa), 0.02), 1.5)
        a, fa = b, fb
        b = c
        fb = upstream_steady(x, d, P, b, p) - h_target
    return b


@njit(cache=True)
def _outlet_h(x, v, d, P, aux):  # noqa: N803
    """Steady SH3 (upto=3) or SH4 outlet enthalpy with valve state s_v at opening v;
    aux = (firing fraction, pressure Pa, s_v, upto)."""
    lf, p, s_v, upto = aux
    x[s_v] = v
    return sh_steady(x, d, P, lf, p, upto)


#: opening (state s_v) that brings the SH3 (upto=3) or SH4 outlet enthalpy to a target
_opening_for = steady_opening("BensonSubcritical", _outlet_h)


@njit(cache=True)
def steady(D, sp_K, P, X):
    """Steady state of each row at its disturbances, holding the main-steam setpoint sp_K.

    The unit controllers' steady conditions: fuel such that the evaporator outlet enthalpy
    meets its schedule; spray 1 holds the SH3 outlet at its schedule (the DCS's
    intermediate temperature), spray 2 the main steam at sp_K; pressure from eq. (13) at
    equilibrium (pumped water = turbine flow).
    """
    for b in range(X.shape[0]):
        x = X[b]
        d = D[b]
        L = min(max(d[D_LOAD], 0.05), 1.3)
        p = p_setpoint(P, L)
        lf = table(P, ITB.FUEL, L)
        x[IX.V1] = P[IP.V1D]
        x[IX.V2] = P[IP.V2D]
        for _ in range(4):
            x[IX.P] = p
            lf = _fuel_for_evap(x, d, P, p, h_ev_setpoint(P, L), lf)
            upstream_steady(x, d, P, lf, p)
            x[IX.V1] = _opening_for(x, d, P, (lf, p, IX.V1, 3), table(P, ITB.H3, L))
            x[IX.V2] = _opening_for(x, d, P, (lf, p, IX.V2, 4), h_pT(p, sp_K[b]))
            _, _, W_eco, w1, w2, _, _, _, _ = boundary(x, d, P)
            p = p_setpoint(P, L) * (W_eco + w1 + w2) / (P[IP.WNOM] * L)
        x[IX.P] = p
        upstream_steady(x, d, P, lf, p)
        h_ms = sh_steady(x, d, P, lf, p, 4)
        pipe_steady(x, int(P[IP.LOFF]), int(P[IP.NL]), h_ms)
        x[IX.F] = lf
        W_t, W_rh, p_rh, p_crh, _ = reheat(P, p, L)
        T_ms = T_ph(p, h_ms)
        h_crh = cold_reheat(P, L, p_crh, T_ms * (p_crh / p) ** P[IP.KE])[0]
        section_steady(x, P, SEC.RH, h_crh, W_rh, p_rh, lf, d)
        L_ff = min(max(L + P[IP.TBIR] * d[D_LOAD_RATE], 0.05), 1.3)
        x[int(P[IP.STRIM])] = lf / table(P, ITB.FUEL, L_ff) - 1.0
        temps = section_temperatures(x, d, P)
        s0 = int(P[IP.S0])
        for j, T in enumerate(
            (temps[2], temps[3], temps[4], temps[5], temps[6], temps[7], temps[8], temps[10])
        ):
            x[s0 + 2 * j] = T + K0
            x[s0 + 2 * j + 1] = T + K0


@njit(cache=True)
def section_enthalpies(x, d, P):
    """Enthalpies (J/kg) at the points of section_temperatures (feedwater ... hot reheat)."""
    L, r2, W_eco, w1, w2, h_fw, h_sp, p_a1, p_a2 = boundary(x, d, P)
    p = x[IX.P]
    out = np.empty(11)
    out[0] = h_fw
    for i, k in (
        (1, SEC.ECO),
        (2, SEC.EV),
        (3, SEC.SH1),
        (4, SEC.SH2),
        (6, SEC.SH3),
        (8, SEC.SH4),
        (10, SEC.RH),
    ):
        out[i] = last_h(x, P, k)
    W3, out[5] = mix(W_eco, out[4], w1, h_sp)
    _, out[7] = mix(W3, out[6], w2, h_sp)
    _, _, _, p_crh, _ = reheat(P, p, L)
    h_t = x[int(P[IP.LOFF]) + int(P[IP.NL]) - 1]  # turbine inlet
    out[9] = cold_reheat(P, L, p_crh, T_ph(p, h_t) * (p_crh / p) ** P[IP.KE])[0]
    return out


@njit(cache=True)
def section_temperatures(x, d, P):
    """True temperatures (C) and flows (kg/s) of every section of state x.

    Returns an array: [T_fw, T_eco, T_evap, T_sh1, T_sh2, T_att1, T_sh3, T_att2, T_sh4,
    T_crh, T_rh, W_eco, W_sh3, W_sh4, W_rh, firing fraction, T_ms] (temperatures at each
    section's outlet pressure; T_fw at the economizer, T_sh4 the SH4 outlet, T_ms the
    turbine inlet after the main-steam line, T_crh the HP exhaust by eq. (14)).
    """
    L, r2, W_eco, w1, w2, h_fw, h_sp, p_a1, p_a2 = boundary(x, d, P)
    p = x[IX.P]
    dpb = P[IP.DPB] * r2
    out = np.empty(17)
    out[0] = T_ph(p + P_SHARE[SEC.ECO] * dpb, h_fw)
    out[1] = T_ph(p + P_SHARE[SEC.ECO] * dpb, last_h(x, P, SEC.ECO))
    out[2] = T_ph(p + P_SHARE[SEC.EV] * dpb, last_h(x, P, SEC.EV))
    out[3] = T_ph(p + P_SHARE[SEC.SH1] * dpb, last_h(x, P, SEC.SH1))
    out[4] = T_ph(p_a1, last_h(x, P, SEC.SH2))
    W3, h_a1 = mix(W_eco, last_h(x, P, SEC.SH2), w1, h_sp)
    out[5] = T_ph(p_a1, h_a1)
    out[6] = T_ph(p_a2, last_h(x, P, SEC.SH3))
    W4, h_a2 = mix(W3, last_h(x, P, SEC.SH3), w2, h_sp)
    out[7] = T_ph(p_a2, h_a2)
    out[8] = T_ph(p, last_h(x, P, SEC.SH4))
    W_t, W_rh, p_rh, p_crh, _ = reheat(P, p, L)
    out[16] = T_ph(p, x[int(P[IP.LOFF]) + int(P[IP.NL]) - 1])
    out[9] = out[16] * (p_crh / p) ** P[IP.KE]  # eq. (14), in K
    out[10] = T_ph(p_rh, last_h(x, P, SEC.RH))
    for i in range(11):
        out[i] -= K0
    out[16] -= K0
    out[11] = W_eco
    out[12] = W3
    out[13] = W4
    out[14] = W_rh
    out[15] = firing(x, d, P)
    return out
