"""Lookups on the patch tables (any (p, h), clamped to the table domain): locating a point
in its segment, q-cell and patch, the Hermite-bicubic T and rho, the exact inverse h(p, T)
and the saturation curves. Internal units: MPa, kJ/kg, K."""

from __future__ import annotations

import math

import numpy as np
from numba import carray

from steamtemp_gym._jit import njit
from steamtemp_gym.steam.cubic import cell_root, hermite_cell, hermite_slope
from steamtemp_gym.steam.tables import (
    AX_DX,
    AX_INV,
    AX_NZ,
    AX_OFF,
    AX_X0,
    B23_N3,
    B23_N4,
    B23_N5,
    CDAT_PTR,
    COFF,
    M13,
    M23,
    MARG,
    NCDAT,
    NCURVE,
    NTDAT,
    NXI,
    P13,
    PC,
    PMIN,
    POFF,
    RDAT_PTR,
    S0_L1,
    S0_V2,
    S1_L1,
    S1_L3,
    S1_V2,
    S1_V3,
    S2_L1,
    S2_S3,
    S2_V2,
    SMIN,
    T13,
    TDAT_PTR,
)


@njit(cache=True, error_model="numpy")
def _locate(ax: int, x: float) -> tuple[int, float, float]:
    """Cell index, local coordinate t in [0, 1] and cell width of x on axis ``ax``.

    x is clamped to the axis range (NaN maps to the lower edge), so the returned cell
    index is always valid.
    """
    nz = AX_NZ[ax]
    if not x >= AX_X0[ax, 0]:
        x = AX_X0[ax, 0]
    elif x > AX_X0[ax, nz]:
        x = AX_X0[ax, nz]
    k = 0
    while k < nz - 1 and x >= AX_X0[ax, k + 1]:
        k += 1
    r = (x - AX_X0[ax, k]) * AX_INV[ax, k]
    m = int(r)
    ncell = AX_OFF[ax, k + 1] - AX_OFF[ax, k]
    if m > ncell - 1:
        m = ncell - 1
    elif m < 0:
        m = 0
    return AX_OFF[ax, k] + m, r - m, AX_DX[ax, k]


@njit(cache=True, error_model="numpy", inline="always")
def qcell(pm: float) -> tuple[int, int, float, float, float, float, float, float]:
    """Segment, q-cell, cubic Hermite basis in q (a1, a3 times the cell width), t, dq."""
    if not pm >= PMIN:  # also NaN
        pm = PMIN
    if pm < P13:
        seg = 0
        q = pm
    elif pm < PC:
        seg = 1
        q = math.sqrt(PC - pm)
    else:
        seg = 2
        q = pm
    i, t, dq = _locate(seg, q)
    a0, a1, a2, a3 = hermite_cell(t, dq)
    return seg, i, a0, a1, a2, a3, t, dq


@njit(cache=True, error_model="numpy")
def curve(seg: int, i: int, c: int, a0: float, a1: float, a2: float, a3: float) -> float:
    """Curve c of segment seg in q-cell i (cubic Hermite; a1, a3 include the width)."""
    nc = NCURVE[seg]
    k = COFF[seg] + (i * nc + c) * 2
    k1 = k + nc * 2
    cdat = carray(CDAT_PTR(), NCDAT)
    return (a0 * cdat[k] + a1 * cdat[k + 1]) + (a2 * cdat[k1] + a3 * cdat[k1 + 1])


@njit(cache=True, error_model="numpy")
def _column(
    dat: np.ndarray, b: int, i: int, j: int, a0: float, a1: float, a2: float, a3: float
) -> tuple[float, float]:
    """Value and d/dxi at xi-node j of patch b, Hermite-interpolated in q within q-cell i."""
    nxi = NXI[b]
    k0 = POFF[b] + (i * nxi + j) * 4
    k1 = k0 + nxi * 4
    # pairwise sums (shorter dependency chains than left-to-right accumulation)
    g = (a0 * dat[k0] + a1 * dat[k0 + 1]) + (a2 * dat[k1] + a3 * dat[k1 + 1])
    gx = (a0 * dat[k0 + 2] + a1 * dat[k0 + 3]) + (a2 * dat[k1 + 2] + a3 * dat[k1 + 3])
    return g, gx


@njit(cache=True, error_model="numpy", inline="always")
def _where(pm: float, hk: float) -> tuple[int, int, float, float, float, float, int, float, float]:
    """Locate (p, h): segment, q-cell, q basis, patch and its h bounds (lo, hi).

    Patch -1 is the two-phase dome (then lo = h_l, hi = h_v). Region boundaries as
    IAPWS97(P, h): region 1 for h <= h13(p), region 2 for h >= h23(p), region 3 between,
    two-phase for h_l(p) < h < h_v(p).
    """
    seg, i, a0, a1, a2, a3, _, _ = qcell(pm)
    b = -1  # two-phase unless a single-phase patch is found below
    if seg == 0:
        lo = curve(0, i, 1, a0, a1, a2, a3)  # hl
        hi = curve(0, i, 2, a0, a1, a2, a3)  # hv
        if hk <= lo:
            b, hi, lo = S0_L1, lo, curve(0, i, 0, a0, a1, a2, a3)
        elif hk >= hi:
            b, lo, hi = S0_V2, hi, curve(0, i, 3, a0, a1, a2, a3)
    elif seg == 1:
        h13 = curve(1, i, 1, a0, a1, a2, a3)
        h23 = curve(1, i, 4, a0, a1, a2, a3)
        lo = curve(1, i, 2, a0, a1, a2, a3)  # hl
        hi = curve(1, i, 3, a0, a1, a2, a3)  # hv
        if hk >= h23:
            b, lo, hi = S1_V2, h23, curve(1, i, 5, a0, a1, a2, a3)
        elif hk <= h13:
            b, lo, hi = S1_L1, curve(1, i, 0, a0, a1, a2, a3), h13
        elif hk <= lo:
            b, hi, lo = S1_L3, lo, h13 - M13
        elif hk >= hi:
            b, lo, hi = S1_V3, hi, h23 + M23
    else:
        h13 = curve(2, i, 1, a0, a1, a2, a3)
        h23 = curve(2, i, 2, a0, a1, a2, a3)
        if hk <= h13:
            b, lo, hi = S2_L1, curve(2, i, 0, a0, a1, a2, a3), h13
        elif hk < h23:
            b, lo, hi = S2_S3, h13 - M13, h23 + M23
        else:
            b, lo, hi = S2_V2, h23, curve(2, i, 3, a0, a1, a2, a3)
    return seg, i, a0, a1, a2, a3, b, lo, hi


@njit(cache=True, error_model="numpy")
def patch_lookup(pm: float, hk: float, want: int) -> tuple[float, float, float, float]:
    """``_lookup`` on the patch tables (any (p, h); clamped to the table domain)."""
    tdat = carray(TDAT_PTR(), NTDAT)
    rdat = carray(RDAT_PTR(), NTDAT)
    if hk != hk:  # NaN enthalpy: lower table edge
        hk = -math.inf
    seg, i, a0, a1, a2, a3, b, lo, hi = _where(pm, hk)
    T = 0.0
    dT = 0.0
    rho = 0.0
    drho = 0.0
    if b < 0:  # two-phase dome: lo = hl, hi = hv
        c = 4 if seg == 0 else 6
        if want != 1:
            T = curve(seg, i, c, a0, a1, a2, a3)
        if want != 0:
            vl = 1.0 / curve(seg, i, c + 1, a0, a1, a2, a3)
            vv = 1.0 / curve(seg, i, c + 2, a0, a1, a2, a3)
            dvdh = (vv - vl) / (hi - lo)
            rho = 1.0 / (vl + (hk - lo) * dvdh)
            drho = -rho * rho * dvdh
        return T, dT, rho, drho
    iw = 1.0 / (hi - lo)
    j, u, dxi = _locate(3 + b, (hk - lo) * iw)
    b0, b1, b2, b3 = hermite_cell(u, dxi)
    d0, d1, _, d3 = hermite_slope(u, dxi)
    e0 = d0 * iw  # d/dh of the basis (e2 = -e0)
    e1 = d1 * iw
    e3 = d3 * iw
    if want != 1:
        g0, gx0 = _column(tdat, b, i, j, a0, a1, a2, a3)
        g1, gx1 = _column(tdat, b, i, j + 1, a0, a1, a2, a3)
        T = (b0 * g0 + b1 * gx0) + (b2 * g1 + b3 * gx1)
        dT = e0 * (g0 - g1) + (e1 * gx0 + e3 * gx1)
    if want != 0:
        g0, gx0 = _column(rdat, b, i, j, a0, a1, a2, a3)
        g1, gx1 = _column(rdat, b, i, j + 1, a0, a1, a2, a3)
        rho = (b0 * g0 + b1 * gx0) + (b2 * g1 + b3 * gx1)
        drho = e0 * (g0 - g1) + (e1 * gx0 + e3 * gx1)
    return T, dT, rho, drho


@njit(cache=True, error_model="numpy", inline="always")
def _select_T(
    pm: float, T: float
) -> tuple[int, int, float, float, float, float, int, float, float]:
    """Locate (p, T): like ``_where`` but with the (p, T) region logic of IAPWS97(P, T).

    Liquid for T < Tsat(p), vapour for T >= Tsat(p) (subcritical); region 1 for
    T <= 623.15 K, region 2 for T >= T_B23(p), region 3 between (p > 16.529 MPa).
    """
    seg, i, a0, a1, a2, a3, _, _ = qcell(pm)
    t_b23 = B23_N4 + math.sqrt(max(pm - B23_N5, 0.0) / B23_N3)
    if seg == 0:
        if T < curve(0, i, 4, a0, a1, a2, a3):
            b, c_lo, c_hi = S0_L1, 0, 1
        else:
            b, c_lo, c_hi = S0_V2, 2, 3
    elif T <= T13:
        b, c_lo, c_hi = (S1_L1 if seg == 1 else S2_L1), 0, 1
    elif seg == 1:
        if T < curve(1, i, 6, a0, a1, a2, a3):
            b, c_lo, c_hi = S1_L3, 1, 2
        elif T < t_b23:
            b, c_lo, c_hi = S1_V3, 3, 4
        else:
            b, c_lo, c_hi = S1_V2, 4, 5
    elif T < t_b23:
        b, c_lo, c_hi = S2_S3, 1, 2
    else:
        b, c_lo, c_hi = S2_V2, 2, 3
    m_lo, m_hi = MARG[b, 0], MARG[b, 1]
    lo = curve(seg, i, c_lo, a0, a1, a2, a3) - m_lo
    hi = curve(seg, i, c_hi, a0, a1, a2, a3) + m_hi
    return seg, i, a0, a1, a2, a3, b, lo, hi


@njit(cache=True, error_model="numpy")
def patch_h_of_T(pm: float, T: float) -> float:
    """h (kJ/kg) at (MPa, K): exact inverse of the T table on the patch holding (p, T).

    Binary search for the xi-cell over the q-interpolated node temperatures (monotone in
    xi), then a safeguarded Halley solve of that cell's Hermite cubic. T outside the
    patch range is clamped to its edge.
    """
    tdat = carray(TDAT_PTR(), NTDAT)
    _, i, a0, a1, a2, a3, b, lo, hi = _select_T(pm, T)
    nxi = NXI[b]
    g_lo, gx_lo = _column(tdat, b, i, 0, a0, a1, a2, a3)
    if not T > g_lo:
        return lo
    g_hi, gx_hi = _column(tdat, b, i, nxi - 1, a0, a1, a2, a3)
    if T >= g_hi:
        return hi
    jl = 0
    jh = nxi - 1
    while jh - jl > 1:
        jm = (jl + jh) >> 1
        g, gx = _column(tdat, b, i, jm, a0, a1, a2, a3)
        if g <= T:
            jl, g_lo, gx_lo = jm, g, gx
        else:
            jh, g_hi, gx_hi = jm, g, gx
    # node coordinate and width of xi-cell jl
    ax = 3 + b
    k = 0
    while k < AX_NZ[ax] - 1 and jl >= AX_OFF[ax, k + 1]:
        k += 1
    dxi = AX_DX[ax, k]
    x0 = AX_X0[ax, k] + (jl - AX_OFF[ax, k]) * dxi
    # cubic F(u) - T on the cell, started from the secant root
    f0 = g_lo - T
    f1 = g_hi - T
    u = cell_root(f0, f1, dxi * gx_lo, dxi * gx_hi, f0 / (f0 - f1))
    return lo + (x0 + u * dxi) * (hi - lo)


@njit(cache=True, error_model="numpy")
def saturation(
    pm: float,
) -> tuple[float, float, float, float, float, float, float, float, float, float]:
    """Tsat, rho_l, rho_v, h_l, h_v and their d/dp (MPa, kJ/kg units), pm in [PMIN, pc)."""
    if not pm >= PMIN:
        pm = PMIN
    if pm < P13:
        seg, q, dpdq = 0, pm, 1.0
        cs = (4, 5, 6, 1, 2)  # Tsat, rhol, rhov, hl, hv
    else:
        seg, q = 1, math.sqrt(max(PC - pm, 0.0))
        dpdq = -2.0 * max(q, SMIN)  # dp/dq at the (clamped) point
        cs = (6, 7, 8, 2, 3)
    i, t, dq = _locate(seg, q)
    a0, a1, a2, a3 = hermite_cell(t, dq)
    d0, d1, d2, d3 = hermite_slope(t, dq)
    v0 = curve(seg, i, cs[0], a0, a1, a2, a3)
    v1 = curve(seg, i, cs[1], a0, a1, a2, a3)
    v2 = curve(seg, i, cs[2], a0, a1, a2, a3)
    v3 = curve(seg, i, cs[3], a0, a1, a2, a3)
    v4 = curve(seg, i, cs[4], a0, a1, a2, a3)
    e0 = curve(seg, i, cs[0], d0, d1, d2, d3) / dpdq
    e1 = curve(seg, i, cs[1], d0, d1, d2, d3) / dpdq
    e2 = curve(seg, i, cs[2], d0, d1, d2, d3) / dpdq
    e3 = curve(seg, i, cs[3], d0, d1, d2, d3) / dpdq
    e4 = curve(seg, i, cs[4], d0, d1, d2, d3) / dpdq
    return v0, v1, v2, v3, v4, e0, e1, e2, e3, e4
