"""Forward IAPWS-IF97 states with the derivatives the steam tables need (``iapws`` package),
and the constants of the table domain. Units: p in MPa, T in K, h in kJ/kg, rho in kg/m3."""

from __future__ import annotations

from dataclasses import dataclass

from iapws import iapws97 as if97

PC = float(if97.Pc)  # 22.064 MPa
TC = float(if97.Tc)  # 647.096 K
P13 = float(if97.Ps_623)  # psat(623.15 K) = 16.5291642526 MPa
T13 = 623.15  # region 1 / 3 boundary temperature (K)
TMIN = 283.15  # lower table edge: 10 C compressed liquid
TMAX = 1073.15  # upper table edge: 800 C (upper limit of IF97 region 2)
PMIN = 0.2  # MPa
PMAX = 35.0  # MPa
FD_STEP = 1e-4  # finite-difference step in q (MPa for q = p, sqrt(MPa) for q = sqrt(pc - p))


@dataclass
class State:
    """Thermodynamic state with the derivatives the tables need."""

    p: float
    T: float
    h: float
    rho: float
    cp: float  # kJ/(kg K)
    alpha: float  # cubic expansion coefficient (1/K)
    kt: float  # isothermal compressibility (1/MPa)


def _state_from(d: dict, p: float) -> State:
    return State(
        p=p,
        T=float(d["T"]),
        h=float(d["h"]),
        rho=1.0 / float(d["v"]),
        cp=float(d["cp"]),
        alpha=float(d["alfav"]),
        kt=float(d["kt"]),
    )


def region12_pT(region: int, p: float, T: float) -> State:
    """State from the region-1 or region-2 Gibbs equation at (p, T)."""
    d = if97._Region1(T, p) if region == 1 else if97._Region2(T, p)
    return _state_from(d, p)


def region3_rho_pT(p: float, T: float, rho: float) -> float:
    """Density root of the region-3 equation p(rho, T) = p by Newton from ``rho``."""
    for it in range(200):
        d = if97._Region3(rho, T)
        # dp/drho|T = 1 / (rho kt)
        res = d["P"] - p
        step = res * rho * d["kt"]
        step = max(min(step, 0.2 * rho), -0.2 * rho)
        rho -= step
        if abs(step) < 1e-13 * rho or (it > 20 and abs(res) < 1e-13 * p):
            return rho
    raise RuntimeError(f"region-3 density did not converge at p={p}, T={T}")


def region3_pT(p: float, T: float, rho_guess: float) -> State:
    """Region-3 state at (p, T) on the density root nearest ``rho_guess``."""
    rho = region3_rho_pT(p, T, rho_guess)
    d = if97._Region3(rho, T)
    return _state_from(d, p)


def state_ph(region: int, p: float, h: float, guess: State) -> State:
    """Solve the forward equation of ``region`` for T (and rho) at (p, h) by Newton."""
    T = guess.T
    if region in (1, 2):
        for _ in range(100):
            st = region12_pT(region, p, T)
            step = (st.h - h) / st.cp
            step = max(min(step, 50.0), -50.0)
            T -= step
            if abs(step) < 1e-12 * T:
                return region12_pT(region, p, T)
        raise RuntimeError(f"region {region} T(p,h) did not converge at p={p}, h={h}")
    rho = guess.rho
    for it in range(200):
        d = if97._Region3(rho, T)
        kt = d["kt"]
        p_rho = 1.0 / (rho * kt)  # MPa per kg/m3
        p_T = d["alfav"] / kt  # MPa/K
        h_T = d["cv"] + 1e3 * p_T / rho  # kJ/(kg K) at constant rho
        h_rho = 1e3 * (-T * p_T / rho**2 + p_rho / rho)  # kJ/kg per kg/m3 at constant T
        fp = d["P"] - p
        fh = d["h"] - h
        det = p_rho * h_T - p_T * h_rho
        d_rho = (fp * h_T - p_T * fh) / det
        d_T = (p_rho * fh - h_rho * fp) / det
        lim = 0.1 * rho
        if abs(d_rho) > lim:  # damp large steps (stay on the branch)
            f = lim / abs(d_rho)
            d_rho *= f
            d_T *= f
        if abs(d_T) > 5.0:
            f = 5.0 / abs(d_T)
            d_rho *= f
            d_T *= f
        rho -= d_rho
        T -= d_T
        small = abs(d_rho) < 1e-12 * rho and abs(d_T) < 1e-12 * T
        tiny_residual = abs(fp) < 1e-12 * p and abs(fh) < 1e-12 * abs(h)
        if small or (it > 40 and tiny_residual):
            d = if97._Region3(rho, T)
            return _state_from(d, p)
    raise RuntimeError(f"region-3 T(p,h) did not converge at p={p}, h={h}")


def t_b23(p: float) -> float:
    """B23 boundary temperature (K) at p (MPa)."""
    return float(if97._t_P(p))


def tsat(p: float) -> float:
    """Region-4 saturation temperature (K) at p (MPa)."""
    return float(if97._TSat_P(p))


def sat_state(p: float, phase: int, region3: bool) -> State:
    """Saturated liquid (phase 0) or vapour (phase 1) state at p, as ``IAPWS97(P=, x=)``.

    ``region3`` selects the region-3 branch (p > P13) rather than regions 1 / 2; it is
    passed explicitly so that finite-difference stencils never switch branch.
    """
    T = tsat(p)
    if not region3:
        return region12_pT(1 if phase == 0 else 2, p, T)
    rho0 = 1.0 / float(if97._Backward3_sat_v_P(max(p, P13), T, phase))
    return region3_pT(p, T, rho0)


def curve_state(name: str, p: float, seg: int) -> State:
    """State on a named boundary curve of segment ``seg`` at p."""
    if name == "hmin":
        return region12_pT(1, p, TMIN)
    if name == "h13":
        return region12_pT(1, p, T13)
    if name == "h23":
        return region12_pT(2, p, t_b23(p))
    if name == "hmax":
        return region12_pT(2, p, TMAX)
    if name == "hl":
        return sat_state(p, 0, seg == 1)
    if name == "hv":
        return sat_state(p, 1, seg == 1)
    raise KeyError(name)
