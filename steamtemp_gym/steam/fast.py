"""The fast path: plain Hermite bicubics of T and rho on the uniform (p, h) rectangle in
region 2 (``FAST_RECT``), and the exact inverse h(p, T) there. Internal units: MPa, kJ/kg, K."""

from __future__ import annotations

import math

import numpy as np
from numba import carray

from steamtemp_gym._jit import njit
from steamtemp_gym.steam.cubic import cell_root, hermite, hermite_slope
from steamtemp_gym.steam.tables import (
    FDH,
    FG_PTR,
    FG_SHAPE,
    FH0,
    FHINV,
    FNG,
    FNH,
    FNP,
    FP0,
    FPINV,
    FR_PTR,
    FT_PTR,
    FT_SHAPE,
)


@njit(cache=True, error_model="numpy")
def _ucell(x: float, n: int) -> tuple[int, float]:
    """Cell index in [0, n - 1] and local coordinate of x (in cell units) on a uniform axis.

    x is clamped to [0, n] (NaN to 0).
    """
    if not x > 0.0:
        x = 0.0
    elif x > n:
        x = float(n)
    i = int(x)
    if i > n - 1:
        i = n - 1
    return i, x - i


@njit(cache=True, error_model="numpy")
def _fcol(
    tab: np.ndarray, i: int, j: int, a0: float, a1: float, a2: float, a3: float
) -> tuple[float, float]:
    """Value and d/(cell coordinate) at node j of a fast table, Hermite in p in p-cell i."""
    g = (a0 * tab[i, j, 0] + a1 * tab[i, j, 1]) + (a2 * tab[i + 1, j, 0] + a3 * tab[i + 1, j, 1])
    gu = (a0 * tab[i, j, 2] + a1 * tab[i, j, 3]) + (a2 * tab[i + 1, j, 2] + a3 * tab[i + 1, j, 3])
    return g, gu


@njit(cache=True, error_model="numpy")
def fast_basis_h(u: float) -> tuple[tuple[float, float, float, float], tuple[float, float, float]]:
    """Hermite weights in h at local coordinate u of a fast-table cell: those of the value
    (:func:`hermite`) and those of d/dh per kJ/kg, for f(0), f'(0), f'(1) (that of f(1) is
    minus the first)."""
    d0, d1, _, d3 = hermite_slope(u, 1.0)
    return hermite(u), (d0 * FHINV, d1 * FHINV, d3 * FHINV)


@njit(cache=True, error_model="numpy")
def fast_value(
    tab: np.ndarray,
    i: int,
    j: int,
    a: tuple[float, float, float, float],
    b: tuple[float, float, float, float],
    e: tuple[float, float, float],
) -> tuple[float, float]:
    """Value and d/dh of a fast table in cell (i, j): Hermite weights a in p, b and e in h
    (:func:`fast_basis_h`)."""
    g0, gu0 = _fcol(tab, i, j, a[0], a[1], a[2], a[3])
    g1, gu1 = _fcol(tab, i, j + 1, a[0], a[1], a[2], a[3])
    value = (b[0] * g0 + b[1] * gu0) + (b[2] * g1 + b[3] * gu1)
    slope = e[0] * (g0 - g1) + (e[1] * gu0 + e[2] * gu1)
    return value, slope


@njit(cache=True, error_model="numpy")
def fast_lookup(pm: float, hk: float, want: int) -> tuple[float, float, float, float]:
    """``_lookup`` on the fast rectangle: plain Hermite bicubic on the uniform (p, h) grid.

    The caller ensures FP0 <= pm <= _FP1 and FH0 <= hk <= _FH1.
    """
    ft = carray(FT_PTR(), FT_SHAPE)
    fr = carray(FR_PTR(), FT_SHAPE)
    i, t = _ucell((pm - FP0) * FPINV, FNP)
    j, u = _ucell((hk - FH0) * FHINV, FNH)
    a = hermite(t)
    b, e = fast_basis_h(u)
    T = dT = rho = drho = 0.0
    if want != 1:
        T, dT = fast_value(ft, i, j, a, b, e)
    if want != 0:
        rho, drho = fast_value(fr, i, j, a, b, e)
    return T, dT, rho, drho


@njit(cache=True, error_model="numpy")
def fast_h_of_T(pm: float, T: float) -> float:
    """h (kJ/kg) inverting the fast T table at (MPa, K), NaN if T lies outside its range.

    Start value from the h(p, tau) table, tau = (T - T_lo(p)) / (T_hi(p) - T_lo(p)) with
    T_lo, T_hi the T table at the rectangle's h edges; then a walk to the h-cell whose
    node temperatures bracket T and a safeguarded Halley solve of its cubic. The caller
    ensures FP0 <= pm <= _FP1.
    """
    ft = carray(FT_PTR(), FT_SHAPE)
    fg = carray(FG_PTR(), FG_SHAPE)
    i, t = _ucell((pm - FP0) * FPINV, FNP)
    a0, a1, a2, a3 = hermite(t)
    t_lo = _fcol(ft, i, 0, a0, a1, a2, a3)[0]
    t_hi = _fcol(ft, i, FNH, a0, a1, a2, a3)[0]
    if not t_lo <= T <= t_hi:
        return math.nan
    k, w = _ucell((T - t_lo) / (t_hi - t_lo) * FNG, FNG)
    g0, gw0 = _fcol(fg, i, k, a0, a1, a2, a3)
    g1, gw1 = _fcol(fg, i, k + 1, a0, a1, a2, a3)
    c0, c1, c2, c3 = hermite(w)
    j, u = _ucell(((c0 * g0 + c1 * gw0) + (c2 * g1 + c3 * gw1) - FH0) * FHINV, FNH)
    g0, gu0 = _fcol(ft, i, j, a0, a1, a2, a3)
    g1, gu1 = _fcol(ft, i, j + 1, a0, a1, a2, a3)
    while T < g0 and j > 0:  # rarely taken: the start value is within ~0.01 kJ/kg
        j -= 1
        u = 1.0
        g1, gu1 = g0, gu0
        g0, gu0 = _fcol(ft, i, j, a0, a1, a2, a3)
    while T > g1 and j < FNH - 1:
        j += 1
        u = 0.0
        g0, gu0 = g1, gu1
        g1, gu1 = _fcol(ft, i, j + 1, a0, a1, a2, a3)
    return FH0 + (j + cell_root(g0 - T, g1 - T, gu0, gu1, u)) * FDH
