"""The fast-path tables: uniform Hermite-bicubic tables of T and rho (and the start table of
h(p, T)) on the (p, h) rectangle ``FAST_P`` x ``FAST_H`` inside IF97 region 2."""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor

import numpy as np
from iapws import iapws97 as if97

from steam_tables.if97 import (
    FD_STEP,
    P13,
    PMAX,
    PMIN,
    curve_state,
    region12_pT,
    sat_state,
    state_ph,
)

# Fast path: uniform (p, h) rectangle inside IF97 region 2, as (start, end, n_cells).
# max_p h_v(p) = 2803 kJ/kg, h23(p) <= 2623 kJ/kg and h(35 MPa, 800 C) = 3996 kJ/kg, so no
# saturation or region boundary and no table edge crosses it (``build_fast`` checks).
FAST_P = (2.0, 35.0, 66)  # MPa
FAST_H = (2850.0, 3950.0, 55)  # kJ/kg
FAST_TAU = 32  # cells of the h(p, tau) start table of h_pT on the fast rectangle


def fast_row(p: float) -> dict[str, np.ndarray]:
    """Fast-path node data along one pressure (no cross derivatives yet).

    Returns (n, 3) arrays of value, d/dp and d/dh (d/dtau for "h"): "T" and "rho" at the
    h nodes of ``FAST_H``, and "h" at the tau nodes of the h_pT start table, where
    T = T(p, h_0) + tau (T(p, h_n) - T(p, h_0)) spans the rectangle's h range at p.
    The p-derivatives (at constant h, resp. tau) are analytic:
    (dT/dp)_h = v (T alpha_v - 1) / cp, (drho/dp)_h = rho (kappa_T - alpha_v (dT/dp)_h),
    (dh/dp)_T = v (1 - T alpha_v); the factor 1e3 converts MPa m3/kg to kJ/kg.
    """
    hn = np.linspace(*FAST_H[:2], FAST_H[2] + 1)
    T = np.empty((hn.size, 3))
    rho = np.empty((hn.size, 3))
    guess = region12_pT(2, p, float(if97._Backward2_T_Ph(p, hn[0])))
    for j, h in enumerate(hn):
        st = state_ph(2, p, h, guess)
        guess = st
        dTdp = 1e3 * (st.T * st.alpha - 1.0) / (st.rho * st.cp)
        T[j] = st.T, dTdp, 1.0 / st.cp
        rho[j] = st.rho, st.rho * (st.kt - st.alpha * dTdp), -st.rho * st.alpha / st.cp
    tau = np.linspace(0.0, 1.0, FAST_TAU + 1)
    hg = np.empty((tau.size, 3))
    span = T[-1, 0] - T[0, 0]
    dspan = T[-1, 1] - T[0, 1]
    for k, x in enumerate(tau):
        st = region12_pT(2, p, T[0, 0] + x * span)
        hg[k] = (
            st.h,
            1e3 * (1.0 - st.T * st.alpha) / st.rho + st.cp * (T[0, 1] + x * dspan),
            st.cp * span,
        )
    return {"T": T, "rho": rho, "h": hg}


def check_fast_rectangle() -> None:
    """Raise unless the fast rectangle lies strictly inside region 2 and the table domain."""
    p0, p1 = FAST_P[:2]
    h0, h1 = FAST_H[:2]
    ps = np.linspace(p0, p1, 331)
    h_v = max(sat_state(p, 1, False).h for p in ps if p <= P13)
    h_23 = max(curve_state("h23", p, 2).h for p in ps if p >= P13)
    h_max = min(curve_state("hmax", p, 2).h for p in ps)
    if not (p0 >= PMIN and p1 <= PMAX and h_v < h0 and h_23 < h0 and h1 < h_max):
        raise RuntimeError(
            f"fast rectangle {FAST_P[:2]} MPa x {FAST_H[:2]} kJ/kg leaves region 2 or the "
            f"table domain (max h_v {h_v:.1f}, max h23 {h_23:.1f}, min hmax {h_max:.1f})"
        )


def build_fast(pool: ProcessPoolExecutor) -> dict[str, np.ndarray]:
    """Fast-path Hermite tables: (n_p, n, 4) of value, d/dp, d/dx and d2/(dp dx).

    x is h for "fast_T" and "fast_rho", tau for "fast_h". The cross derivative is the
    central difference (step ``FD_STEP`` MPa, at constant h or tau) of the analytic d/dx;
    the same stencil checks the analytic d/dp against a difference of the values.
    """
    check_fast_rectangle()
    pn = np.linspace(*FAST_P[:2], FAST_P[2] + 1)
    d = FD_STEP
    jobs = [x for p in pn for x in (p - d, p, p + d)]
    res = list(pool.map(fast_row, jobs, chunksize=3))
    out: dict[str, np.ndarray] = {}
    for key, name in (("T", "fast_T"), ("rho", "fast_rho"), ("h", "fast_h")):
        lo = np.stack([r[key] for r in res[0::3]])
        mid = np.stack([r[key] for r in res[1::3]])
        hi = np.stack([r[key] for r in res[2::3]])
        tab = np.empty(mid.shape[:2] + (4,))
        tab[..., :3] = mid
        tab[..., 3] = (hi[..., 2] - lo[..., 2]) / (2 * d)
        fd = (hi[..., 0] - lo[..., 0]) / (2 * d)
        err = np.abs(fd - mid[..., 1]).max() / np.abs(mid[..., 1]).max()
        if err > 1e-6:
            raise RuntimeError(f"{name}: analytic d/dp differs from finite differences ({err:.2g})")
        out[name] = tab
    out["fast_axes"] = np.array([FAST_P, FAST_H, (0.0, 1.0, FAST_TAU)], dtype=np.float64)
    return out
