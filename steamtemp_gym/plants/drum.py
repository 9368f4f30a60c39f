"""Natural-circulation drum, downcomers and risers: the Astrom-Bell four-state model.

Source: K.J. Astrom and R.D. Bell, "Drum-boiler dynamics", Automatica 36 (2000)
363-378, and the
water-tube boiler thesis of Kim (Inha Univ.), whose eq. (1)-(8)
and (16)-(22) are the same balances without the steam volume under the level. The
thesis's numbers lost digits in extraction, so all parameters are Astrom-Bell's.

States (SI): total water volume V_wt (m3), drum pressure p (Pa), riser-exit steam
mass fraction alpha_r (-), steam volume under the liquid level V_sd (m3). Inputs:
steam flow out of the drum q_s, feedwater flow q_f (kg/s), feedwater enthalpy h_f
(J/kg), heat to the risers Q (W). Saturation properties rho_s, rho_w, h_s, h_w,
t_s and their pressure derivatives (primes) are IAPWS-IF97 (steamtemp_gym.steam.sat_p),
h_c = h_s - h_w, V_st = V_t - V_wt, V_t = V_d + V_r + V_dc.

Balances (thesis eq. (1), (4), (5), (6), Astrom-Bell's drum steam balance):

- global mass:   d/dt(rho_s V_st + rho_w V_wt) = q_f - q_s
- global energy: d/dt(rho_s h_s V_st + rho_w h_w V_wt - p V_t + m_t C_p t_s)
  = Q + q_f h_f - q_s h_s
- riser mass and energy with the mean void fraction (thesis eq. (7))
  a_v = rho_w/(rho_w - rho_s) [1 - rho_s/((rho_w - rho_s) alpha_r)
  ln(1 + (rho_w - rho_s) alpha_r/rho_s)],
- circulation (momentum of the loop, thesis eq. (8) in Astrom-Bell's form):
  0.5 k q_dc^2 = rho_w A_dc (rho_w - rho_s) g a_v V_r,
- steam under the level: d/dt(rho_s V_sd) = alpha_r q_r - q_sd - q_cd with
  q_sd = (rho_s/T_d)(V_sd - V_sd0) + alpha_r q_dc + alpha_r beta (q_dc - q_r) and the
  condensation flow q_cd = [(h_w - h_f) q_f + (rho_s V_sd h_s' + rho_w V_wd h_w'
  - V_sd - V_wd + m_d C_p t_s') dp/dt] / h_c,
- level l = (V_wd + V_sd)/A_d with V_wd = V_wt - V_dc - (1 - a_v) V_r.

Eliminating q_r gives the descriptor form E(x) dx/dt = g(x, u) (thesis eq. (21),
Astrom-Bell's e_ij), solved here by block elimination (rows 1-2 give dV_wt/dt and
dp/dt, row 3 d alpha_r/dt, row 4 dV_sd/dt):

    e11 V_wt' + e12 p'            = q_f - q_s
    e21 V_wt' + e22 p'            = Q + q_f h_f - q_s h_s
                e32 p' + e33 a_r' = Q - alpha_r h_c q_dc
                e42 p' + e43 a_r' + e44 V_sd' = rho_s/T_d (V_sd0 - V_sd) + (h_f - h_w) q_f/h_c

    e11 = rho_w - rho_s,  e12 = V_wt rho_w' + V_st rho_s'
    e21 = rho_w h_w - rho_s h_s
    e22 = V_wt (h_w rho_w' + rho_w h_w') + V_st (h_s rho_s' + rho_s h_s') - V_t + m_t C_p t_s'
    e32 = (rho_w h_w' - alpha_r h_c rho_w')(1 - a_v) V_r + ((1 - alpha_r) h_c rho_s'
          + rho_s h_s') a_v V_r + (rho_s + (rho_w - rho_s) alpha_r) h_c V_r da_v/dp
          - V_r + m_r C_p t_s'
    e33 = ((1 - alpha_r) rho_s + alpha_r rho_w) h_c V_r da_v/dalpha_r
    e42 = V_sd rho_s' + (rho_s V_sd h_s' + rho_w V_wd h_w' - V_sd - V_wd + m_d C_p t_s')/h_c
          + alpha_r (1 + beta) V_r (a_v rho_s' + (1 - a_v) rho_w' + (rho_s - rho_w) da_v/dp)
    e43 = alpha_r (1 + beta) V_r (rho_s - rho_w) da_v/dalpha_r,   e44 = rho_s

Steady state (thesis eq. (22)): q_f = q_s, Q = q_s h_s - q_f h_f, Q = alpha_r h_c q_dc,
V_sd = V_sd0 + T_d (h_f - h_w) q_f/(rho_s h_c).

Parameters (Astrom and Bell 2000, docs/references.md): V_d 40 m3, V_r 37 m3, V_dc 11 m3,
m_t 300 t, m_r 160 t, C_p 550 J/(kg K), A_d 20 m2, A_dc 0.38 m2, k 25, beta 0.3,
T_d 12 s, V_sd0 4.9 m3. The drum metal mass m_d in the condensation flow is not in
the paper: 40 t is a plausible default, unverified (it only scales a small
storage term of q_cd).

The thesis's level, eq. (9)-(15), uses the wet surface of a horizontal cylinder and no
V_sd; here the level is Astrom-Bell's l = (V_wd + V_sd)/A_d (A_d the drum's water
surface), measured from a reference level.

Stiffness: the fastest drum modes are the riser quality (tau ~7-8 s) and the steam under
the level (T_d = 12 s); at the 2 s control interval they are not stiff (h |lambda| < 0.3).
drum_rhs gives the integrator their diagonal and the exact sensitivities of all four
rows to the inputs (q_s, q_f, Q, h_f), which the plant chains with the states those
inputs come from.

Validation: tests/test_drum_boiler.py (steady state against Astrom-Bell's nominal
values, the descriptor form against the balances it comes from along a transient,
shrink and swell, linearization at three loads, the Jacobian entries against finite
differences, ROS2 against Radau).
"""

from __future__ import annotations

import math

import numpy as np

from steamtemp_gym._jit import njit
from steamtemp_gym.steam import sat_p

G = 9.81  # m/s2

# Indices into a packed drum parameter block (drum_block).
D_VT, D_VR, D_VDC, D_MT, D_MR, D_MD, D_CP, D_AD, D_ADC, D_K, D_BETA, D_TD, D_VSD0, D_L0 = range(14)
N_DRUM_P = 14
# Offsets of the four states in the drum's state block.
VWT, PD, AR, VSD = 0, 1, 2, 3


def drum_block(
    V_d: float,
    V_r: float,
    V_dc: float,
    m_t: float,
    m_r: float,
    m_d: float,
    C_p: float,
    A_d: float,
    A_dc: float,
    k: float,
    beta: float,
    T_d: float,
    V_sd0: float,
) -> np.ndarray:
    """Packed drum parameters (SI) in the order of the D_* indices; level reference 0."""
    P = np.zeros(N_DRUM_P)
    P[D_VT] = V_d + V_r + V_dc
    P[D_VR], P[D_VDC], P[D_MT], P[D_MR], P[D_MD], P[D_CP] = V_r, V_dc, m_t, m_r, m_d, C_p
    P[D_AD], P[D_ADC], P[D_K], P[D_BETA], P[D_TD], P[D_VSD0] = A_d, A_dc, k, beta, T_d, V_sd0
    return P


@njit(cache=True)
def void_fraction(rho_w, rho_s, drho_w, drho_s, ar):
    """Mean riser void fraction a_v (thesis eq. (7)) and its derivatives.

    Returns:
        (a_v, da_v/dalpha_r, da_v/dp) for densities (kg/m3) and their pressure
        derivatives (kg/m3/Pa) at riser-exit quality ar.
    """
    d = rho_w - rho_s
    eta = ar * d / rho_s
    if eta < 1e-4:  # series of 1 - ln(1 + eta)/eta and its derivative
        phi = eta / 2.0 - eta * eta / 3.0
        dphi = 0.5 - 2.0 * eta / 3.0
    else:
        ln1 = math.log1p(eta)
        phi = 1.0 - ln1 / eta
        dphi = ln1 / (eta * eta) - 1.0 / (eta * (1.0 + eta))
    c = rho_w / d
    av = c * phi
    dav_dar = c * dphi * d / rho_s
    # a_v = r/(r-1) phi(alpha_r (r-1)), r = rho_w/rho_s
    r = rho_w / rho_s
    dr_dp = (rho_s * drho_w - rho_w * drho_s) / (rho_s * rho_s)
    dav_dr = -phi / ((r - 1.0) * (r - 1.0)) + c * dphi * ar
    return av, dav_dar, dav_dr * dr_dp


@njit(cache=True)
def circulation(rho_w, rho_s, av, P, o):
    """Downcomer flow q_dc (kg/s): 0.5 k q_dc^2 = rho_w A_dc (rho_w - rho_s) g a_v V_r."""
    return math.sqrt(
        max(2.0 * rho_w * P[o + D_ADC] * (rho_w - rho_s) * G * av * P[o + D_VR] / P[o + D_K], 0.0)
    )


@njit(cache=True)
def drum_rhs(x, s, P, o, q_s, q_f, h_f, Q, f, jd, want_jac):
    """Write d/dt of the drum states x[s:s+4] into f (their Jacobian diagonal into jd).

    Args:
        x: Plant state vector; the drum block starts at s (V_wt, p, alpha_r, V_sd).
        P: Packed parameters; the drum block (drum_block) starts at o.
        q_s: Steam flow out of the drum (kg/s). q_f: Feedwater flow (kg/s).
        h_f: Feedwater enthalpy (J/kg). Q: Heat to the risers (W).
        f, jd: Outputs (derivatives, Jacobian diagonal). want_jac: whether to fill jd
            (diagonal of the fast states alpha_r and V_sd; zero for V_wt and p) and to
            return the input sensitivities.

    Returns:
        (level above the reference (m), q_dc (kg/s), q_r (kg/s), h_s (J/kg), dh_s/dp,
        sens) with sens the 16 exact derivatives of (dV_wt/dt, dp/dt, dalpha_r/dt,
        dV_sd/dt) by (q_s, q_f, Q, h_f), row by row (zeros unless want_jac); the caller
        chains them with the inputs' dependence on its states (:func:`input_pattern`).
    """
    Vwt = x[s + VWT]
    p = x[s + PD]
    ar = x[s + AR]
    Vsd = x[s + VSD]
    Vt, Vr, Vdc = P[o + D_VT], P[o + D_VR], P[o + D_VDC]
    Cp = P[o + D_CP]
    Ts, rw, rs, hw, hs, dTs, drw, drs, dhw, dhs = sat_p(p)
    hc = hs - hw
    av, dav_dar, dav_dp = void_fraction(rw, rs, drw, drs, ar)
    qdc = circulation(rw, rs, av, P, o)
    Vst = Vt - Vwt
    Vwd = Vwt - Vdc - (1.0 - av) * Vr
    # global balances (rows 1-2)
    e11 = rw - rs
    e12 = Vwt * drw + Vst * drs
    e21 = rw * hw - rs * hs
    e22 = Vwt * (hw * drw + rw * dhw) + Vst * (hs * drs + rs * dhs) - Vt + P[o + D_MT] * Cp * dTs
    g1 = q_f - q_s
    g2 = Q + q_f * h_f - q_s * hs
    det = e11 * e22 - e12 * e21
    dVwt = (g1 * e22 - e12 * g2) / det
    dp = (e11 * g2 - e21 * g1) / det
    # riser (row 3)
    e32 = (
        (rw * dhw - ar * hc * drw) * (1.0 - av) * Vr
        + ((1.0 - ar) * hc * drs + rs * dhs) * av * Vr
        + (rs + (rw - rs) * ar) * hc * Vr * dav_dp
        - Vr
        + P[o + D_MR] * Cp * dTs
    )
    e33 = ((1.0 - ar) * rs + ar * rw) * hc * Vr * dav_dar
    dar = (Q - ar * hc * qdc - e32 * dp) / e33
    # steam under the level (row 4)
    ab = ar * (1.0 + P[o + D_BETA]) * Vr
    e42 = (
        Vsd * drs
        + (rs * Vsd * dhs + rw * Vwd * dhw - Vsd - Vwd + P[o + D_MD] * Cp * dTs) / hc
        + ab * (av * drs + (1.0 - av) * drw + (rs - rw) * dav_dp)
    )
    e43 = ab * (rs - rw) * dav_dar
    Td = P[o + D_TD]
    dVsd = (rs / Td * (P[o + D_VSD0] - Vsd) + (h_f - hw) * q_f / hc - e42 * dp - e43 * dar) / rs
    f[s + VWT] = dVwt
    f[s + PD] = dp
    f[s + AR] = dar
    f[s + VSD] = dVsd
    # riser outlet flow from the riser mass balance
    q_r = qdc - Vr * (
        (av * drs + (1.0 - av) * drw + (rs - rw) * dav_dp) * dp + (rs - rw) * dav_dar * dar
    )
    level = (Vwd + Vsd) / P[o + D_AD] - P[o + D_L0]
    if not want_jac:
        z = 0.0
        return level, qdc, q_r, hs, dhs, (z, z, z, z, z, z, z, z, z, z, z, z, z, z, z, z)
    jd[s + VWT] = 0.0
    jd[s + PD] = 0.0
    # d/d alpha_r of -alpha_r h_c q_dc / e33, q_dc ~ sqrt(a_v)
    jd[s + AR] = -hc * qdc * (1.0 + 0.5 * ar * dav_dar / av) / e33
    jd[s + VSD] = -1.0 / Td
    # by q_s: dg1 = -1, dg2 = -h_s; by q_f: dg1 = 1, dg2 = h_f, dg4 = (h_f - h_w)/h_c;
    # by Q: dg2 = 1, dg3 = 1; by h_f: dg2 = q_f, dg4 = q_f/h_c
    pw_s = (e21 - e11 * hs) / det
    pw_f = (e11 * h_f - e21) / det
    pw_q = e11 / det
    pw_h = e11 * q_f / det
    ar_s = -e32 * pw_s / e33
    ar_f = -e32 * pw_f / e33
    ar_q = (1.0 - e32 * pw_q) / e33
    ar_h = -e32 * pw_h / e33
    sens = (
        (e12 * hs - e22) / det,
        (e22 - e12 * h_f) / det,
        -e12 / det,
        -e12 * q_f / det,
        pw_s,
        pw_f,
        pw_q,
        pw_h,
        ar_s,
        ar_f,
        ar_q,
        ar_h,
        -(e42 * pw_s + e43 * ar_s) / rs,
        ((h_f - hw) / hc - e42 * pw_f - e43 * ar_f) / rs,
        -(e42 * pw_q + e43 * ar_q) / rs,
        (q_f / hc - e42 * pw_h - e43 * ar_h) / rs,
    )
    return level, qdc, q_r, hs, dhs, sens


def input_pattern(s: int, cols: tuple[int, ...]) -> list[tuple[int, int]]:
    """Lower Jacobian pattern (row, col): each drum row on the states the inputs depend on.

    The drum block starts at s; every col must be below s (strictly lower pattern). The
    values are drum_rhs's sensitivities chained with the inputs' derivatives.
    """
    if any(c >= s for c in cols):
        raise ValueError("drum input columns must precede the drum states")
    return [(s + r, c) for r in range(4) for c in cols]


@njit(cache=True)
def drum_level(x, s, P, o):
    """Level above the reference (m) of the drum state x[s:s+4]."""
    Ts, rw, rs, hw, hs, dTs, drw, drs, dhw, dhs = sat_p(x[s + PD])
    av, _, _ = void_fraction(rw, rs, drw, drs, x[s + AR])
    Vwd = x[s + VWT] - P[o + D_VDC] - (1.0 - av) * P[o + D_VR]
    return (Vwd + x[s + VSD]) / P[o + D_AD] - P[o + D_L0]


@njit(cache=True)
def drum_steady(p, q_s, h_f, level, P, o, x, s):
    """Write the steady drum state at pressure p, steam flow q_s = q_f, feed enthalpy h_f.

    The riser quality solves Q = alpha_r h_c q_dc(alpha_r) (bisection; the left side
    grows monotonically with alpha_r), V_sd follows from the drum steam balance and V_wt
    from the requested level (m above the reference).

    Returns:
        (Q in W, q_dc in kg/s).
    """
    Ts, rw, rs, hw, hs, dTs, drw, drs, dhw, dhs = sat_p(p)
    hc = hs - hw
    Q = q_s * (hs - h_f)
    lo, hi = 1e-6, 0.9
    for _ in range(80):
        ar = 0.5 * (lo + hi)
        av, _, _ = void_fraction(rw, rs, drw, drs, ar)
        if ar * hc * circulation(rw, rs, av, P, o) > Q:
            hi = ar
        else:
            lo = ar
    ar = 0.5 * (lo + hi)
    av, _, _ = void_fraction(rw, rs, drw, drs, ar)
    Vsd = P[o + D_VSD0] + P[o + D_TD] * (h_f - hw) * q_s / (rs * hc)
    Vwd = (level + P[o + D_L0]) * P[o + D_AD] - Vsd
    x[s + VWT] = Vwd + P[o + D_VDC] + (1.0 - av) * P[o + D_VR]
    x[s + PD] = p
    x[s + AR] = ar
    x[s + VSD] = Vsd
    return Q, circulation(rw, rs, av, P, o)
