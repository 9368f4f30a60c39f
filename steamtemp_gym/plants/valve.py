"""Control valve / damper actuator: first-order lag, rate limit, saturation.

    dv/dt = clip((u - v) / tau, -r, r),   u, v in [0, 1]

(../shared/REFERENCE_DATA.md: "Valve: first-order lag plus rate limit plus
saturation"). Returns the derivative and the diagonal Jacobian entry (0 while
rate limited).
"""

from __future__ import annotations

from numba import njit


@njit(cache=True, error_model="numpy")
def valve_rhs(v, u, tau, rate):
    """(dv/dt, d(dv/dt)/dv) for command u, time constant tau (s), rate limit rate (1/s)."""
    u = min(max(u, 0.0), 1.0)
    dv = (u - v) / tau
    if dv > rate:
        return rate, 0.0
    if dv < -rate:
        return -rate, 0.0
    return dv, -1.0 / tau
