"""The public lookups in SI units (``@njit`` scalar functions callable from Python and from
other jitted kernels) and :func:`check_domain`; the fast table inside its rectangle, the
patch tables elsewhere."""

from __future__ import annotations

import numpy as np

from steamtemp_gym._jit import njit
from steamtemp_gym.steam.fast import fast_h_of_T, fast_lookup
from steamtemp_gym.steam.patches import curve, patch_h_of_T, patch_lookup, qcell, saturation
from steamtemp_gym.steam.tables import (
    FH0,
    FH1,
    FP0,
    FP1,
    P_MAX,
    P_MIN,
    PC,
    PMAX,
    TC,
)


@njit(cache=True, error_model="numpy")
def _lookup(pm: float, hk: float, want: int) -> tuple[float, float, float, float]:
    """(T K, dT/dh K per kJ/kg, rho kg/m3, drho/dh) at (MPa, kJ/kg).

    ``want``: 0 computes T only, 1 rho only, 2 both (the others are returned as 0).
    The fast table inside its rectangle, the patch tables elsewhere.
    """
    if pm > PMAX:  # clamp first, so that the fast path also serves p > P_MAX
        pm = PMAX
    if FP0 <= pm <= FP1 and FH0 <= hk <= FH1:  # False for NaN
        return fast_lookup(pm, hk, want)
    return patch_lookup(pm, hk, want)


@njit(cache=True, error_model="numpy")
def _h_of_T(pm: float, T: float) -> float:
    """h (kJ/kg) at (MPa, K): exact inverse of the T table that ``_lookup`` uses there.

    The fast table if T lies within its range at p (then h lies in the fast rectangle),
    the patch tables otherwise.
    """
    if pm > PMAX:
        pm = PMAX
    if FP0 <= pm <= FP1:
        h = fast_h_of_T(pm, T)
        if h == h:
            return h
    return patch_h_of_T(pm, T)


@njit(cache=True, error_model="numpy")
def T_ph(p: float, h: float) -> float:
    """Temperature T(p, h).

    Args:
        p: Pressure (Pa).
        h: Specific enthalpy (J/kg).

    Returns:
        Temperature (K); Tsat(p) inside the two-phase dome. Inputs outside the table
        domain are clamped to its edge.
    """
    return _lookup(p * 1e-6, h * 1e-3, 0)[0]


@njit(cache=True, error_model="numpy")
def T_dTdh_ph(p: float, h: float) -> tuple[float, float]:
    """Temperature and its derivative at constant pressure (for Jacobians).

    Args:
        p: Pressure (Pa).
        h: Specific enthalpy (J/kg).

    Returns:
        (T in K, dT/dh at constant p in K per J/kg). dT/dh is 0 inside the dome; outside
        the table domain, value and derivative at the clamped point.
    """
    T, d, _, _ = _lookup(p * 1e-6, h * 1e-3, 0)
    return T, d * 1e-3


@njit(cache=True, error_model="numpy")
def rho_ph(p: float, h: float) -> float:
    """Density rho(p, h) (kg/m3); homogeneous mixture density inside the dome.

    Args:
        p: Pressure (Pa).
        h: Specific enthalpy (J/kg).
    """
    return _lookup(p * 1e-6, h * 1e-3, 1)[2]


@njit(cache=True, error_model="numpy")
def rho_drhodh_ph(p: float, h: float) -> tuple[float, float]:
    """Density and its derivative at constant pressure (for Jacobians).

    Args:
        p: Pressure (Pa).
        h: Specific enthalpy (J/kg).

    Returns:
        (rho in kg/m3, drho/dh at constant p in kg/m3 per J/kg).
    """
    _, _, r, d = _lookup(p * 1e-6, h * 1e-3, 1)
    return r, d * 1e-3


@njit(cache=True, error_model="numpy")
def T_rho_ph(p: float, h: float) -> tuple[float, float, float, float]:
    """T, dT/dh, rho and drho/dh at (p, h) with a single table location (cheaper than
    ``T_dTdh_ph`` plus ``rho_drhodh_ph``; for superheater segment updates).

    Args:
        p: Pressure (Pa).
        h: Specific enthalpy (J/kg).

    Returns:
        (T K, dT/dh K per J/kg, rho kg/m3, drho/dh kg/m3 per J/kg).
    """
    T, dT, r, dr = _lookup(p * 1e-6, h * 1e-3, 2)
    return T, dT * 1e-3, r, dr * 1e-3


@njit(cache=True, error_model="numpy")
def h_pT(p: float, T: float) -> float:
    """Specific enthalpy h(p, T) (J/kg) of single-phase water or steam.

    Compressed liquid for T < Tsat(p), superheated vapour for T >= Tsat(p) (at exactly
    Tsat the saturated-vapour value); supercritical above 22.064 MPa. Exact inverse of
    the ``T_ph`` table. Inputs outside the table domain are clamped.

    Args:
        p: Pressure (Pa).
        T: Temperature (K).
    """
    return _h_of_T(p * 1e-6, T) * 1e3


@njit(cache=True, error_model="numpy")
def cp_pT(p: float, T: float) -> float:
    """Isobaric heat capacity cp(p, T) = 1 / (dT/dh)_p of the T table (J/(kg K)).

    Args:
        p: Pressure (Pa).
        T: Temperature (K).
    """
    pm = p * 1e-6
    d = _lookup(pm, _h_of_T(pm, T), 0)[1]
    return 1e3 / max(d, 1e-12)


@njit(cache=True, error_model="numpy")
def sat_p(p: float) -> tuple[float, float, float, float, float, float, float, float, float, float]:
    """Saturation properties and their pressure derivatives (drum-boiler models).

    Valid (and tested) for 0.5 MPa <= p <= 21.5 MPa; p is clamped to [0.2 MPa, pc). IF97
    itself jumps slightly (h, rho) at p = 16.529 MPa, where the saturated states switch
    from regions 1 / 2 to region 3; the derivatives are one-sided there.

    Args:
        p: Pressure (Pa).

    Returns:
        (Tsat K, rho_l kg/m3, rho_v kg/m3, h_l J/kg, h_v J/kg, dTsat/dp K/Pa,
        drho_l/dp, drho_v/dp in kg/m3/Pa, dh_l/dp, dh_v/dp in J/kg/Pa).
    """
    Ts, rl, rv, hl, hv, dTs, drl, drv, dhl, dhv = saturation(p * 1e-6)
    return (
        Ts,
        rl,
        rv,
        hl * 1e3,
        hv * 1e3,
        dTs * 1e-6,
        drl * 1e-6,
        drv * 1e-6,
        dhl * 1e-3,
        dhv * 1e-3,
    )


@njit(cache=True, error_model="numpy")
def Tsat_p(p: float) -> float:
    """Saturation temperature (K) at p (Pa); Tc at and above pc, clamped below 0.2 MPa.

    Args:
        p: Pressure (Pa).
    """
    pm = p * 1e-6
    if pm >= PC:
        return TC
    return saturation(pm)[0]


@njit(cache=True, error_model="numpy")
def h_limits_p(p: float) -> tuple[float, float]:
    """Table enthalpy range (J/kg) at p (Pa), p clamped: (h(p, 10 C), h(p, 800 C)).

    Args:
        p: Pressure (Pa).
    """
    seg, i, a0, a1, a2, a3, _, _ = qcell(p * 1e-6)
    ctop = 5 if seg == 1 else 3
    return curve(seg, i, 0, a0, a1, a2, a3) * 1e3, curve(seg, i, ctop, a0, a1, a2, a3) * 1e3


def check_domain(p: float | np.ndarray, h: float | np.ndarray | None = None) -> None:
    """Raise ValueError unless every (p, h) lies inside the table domain.

    Args:
        p: Pressure(s) in Pa; must lie in [P_MIN, P_MAX] = [0.2, 35] MPa.
        h: Specific enthalpy(ies) in J/kg (broadcast against p); must lie between
            h(p, 10 C) and h(p, 800 C). Omit to check the pressure only.

    Raises:
        ValueError: naming the first offending value and the admissible range.
    """
    pa = np.asarray(p, dtype=np.float64)
    if h is None:
        bad = ~((pa >= P_MIN) & (pa <= P_MAX))
        if bad.any():
            v = pa[bad].ravel()[0]
            raise ValueError(f"steam tables: p = {v:.6g} Pa outside [{P_MIN:.6g}, {P_MAX:.6g}] Pa")
        return
    pa, ha = np.broadcast_arrays(pa, np.asarray(h, dtype=np.float64))
    for pv, hv in zip(pa.ravel(), ha.ravel(), strict=True):
        if not (P_MIN <= pv <= P_MAX):
            raise ValueError(f"steam tables: p = {pv:.6g} Pa outside [{P_MIN:.6g}, {P_MAX:.6g}] Pa")
        lo, hi = h_limits_p(float(pv))
        if not (lo <= hv <= hi):
            raise ValueError(
                f"steam tables: h = {hv:.6g} J/kg at p = {pv:.6g} Pa outside "
                f"[{lo:.6g}, {hi:.6g}] J/kg (10 C .. 800 C)"
            )
