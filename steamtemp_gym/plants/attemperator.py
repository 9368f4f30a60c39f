"""Spray attemperator: algebraic mass and energy balance (negligible storage), protection.

    W_out = W_in + w_sp,   h_out = (W_in h_in + w_sp h_sp) / W_out

(the mass and energy balance of a mixing point with negligible storage; document
001 eq. (17)-(20) in steady form, docs/references.md). Spray flow through the
valve follows the incompressible valve equation w_sp = v C_v sqrt(rho_w dp) with a
linear characteristic.
"""

from __future__ import annotations

import math

from steamtemp_gym._jit import njit


@njit(cache=True, error_model="numpy")
def mix(W_in, h_in, w_sp, h_sp):
    """Outlet flow (kg/s) and enthalpy (J/kg) of the attemperator."""
    W_out = W_in + w_sp
    return W_out, (W_in * h_in + w_sp * h_sp) / W_out


@njit(cache=True, error_model="numpy")
def spray_flow(opening, Cv, rho_w, dp):
    """Spray water flow (kg/s) through a linear valve: opening * Cv * sqrt(rho_w * dp).

    Args:
        opening: Valve opening in [0, 1] (clipped). Cv: valve flow coefficient,
            m2 (kg/s per sqrt(kg/m3 * Pa)). rho_w: water density (kg/m3).
        dp: Pressure drop across the valve (Pa), clipped at zero.
    """
    v = min(max(opening, 0.0), 1.0)
    return v * Cv * math.sqrt(rho_w * max(dp, 0.0))


@njit(cache=True, error_model="numpy")
def protected_spray_out(w_valve, W_out, h_in, h_sp, h_min):
    """Spray flow (kg/s) after the attemperator protection: at most the flow whose mix
    reaches ``h_min`` (J/kg; the enthalpy a margin above saturation), never below zero.

    Plants limit spray so that the attemperator outlet stays well above saturation
    (10-15 K: no water droplets reach the next stage's tubes). The downstream flow W_out
    (kg/s) is set (turbine, load controller) and the spray replaces steam upstream
    (W_in = W_out - w): (W_out - w) h_in + w h_sp = W_out h_min gives the cap
    w = W_out (h_in - h_min) / (h_in - h_sp).
    """
    if h_in <= h_min or h_min <= h_sp:
        return 0.0
    return min(w_valve, W_out * (h_in - h_min) / (h_in - h_sp))
