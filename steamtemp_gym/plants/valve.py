"""Control valve / damper actuator: first-order lag, rate limit, saturation.

    dv/dt = clip((u - v) / tau, -r, r),   u, v in [0, 1]

(the usual actuator model of plant simulators: first-order lag plus rate limit
plus saturation). With the command held over an interval the motion has a closed
form (:func:`valve_travel`); the shared integrator uses it so that jumpy
commands (an RL agent's) are integrated exactly (plants/integrator.py).
"""

from __future__ import annotations

import math
from collections.abc import Callable

from steamtemp_gym._jit import njit
from steamtemp_gym.plants.specialize import specialize


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


@njit(cache=True, error_model="numpy")
def valve_travel(v, u, tau, rate, h):
    """Exact motion over h at held command u: (opening at the end, mean opening).

    A rate-limited phase until |u - v| = rate tau, then the exponential approach.
    """
    u = min(max(u, 0.0), 1.0)
    if h <= 0.0:
        return v, v
    e = u - v
    s = 1.0 if e > 0.0 else -1.0
    t1 = max((abs(e) - rate * tau) / rate, 0.0)  # rate-limited phase
    if t1 >= h:
        return v + s * rate * h, v + 0.5 * s * rate * h
    v1 = v + s * rate * t1
    e1 = u - v1
    t2 = h - t1
    a = math.exp(-t2 / tau)
    integral = v * t1 + 0.5 * s * rate * t1 * t1 + u * t2 - e1 * tau * (1.0 - a)
    return u - e1 * a, integral / h


# The plant's steady outlet as a function of the opening, bound per plant by
# steady_opening (plants/specialize.py); the template is never compiled as it is.
outlet = None


def _steady_opening(x, d, P, aux, target):  # noqa: N803
    """Template of the solver returned by :func:`steady_opening`."""
    lo, hi = 0.0, 1.0
    if outlet(x, lo, d, P, aux) <= target:
        return lo
    if outlet(x, hi, d, P, aux) >= target:
        return hi
    for _ in range(60):
        v = 0.5 * (lo + hi)
        if outlet(x, v, d, P, aux) > target:
            lo = v
        else:
            hi = v
    return 0.5 * (lo + hi)


def steady_opening(name: str, outlet: Callable) -> Callable:
    """Compiled ``solve(x, d, P, aux, target)``: the opening in [0, 1] at which the
    plant's steady ``outlet(x, v, d, P, aux)`` equals ``target``, by bisection (60 halvings,
    below round-off).

    ``outlet`` must fall as the opening rises (more spray: colder steam; a quantity that
    rises, e.g. a damper's reheat temperature, is passed negated with a negated target).
    Where the target is out of reach the opening is clipped to 0 or 1. ``aux`` carries
    the plant's other arguments (any numba type, e.g. a tuple). One cached kernel per
    ``name`` (plants/specialize.py): every plant's steady state uses this one solver.
    """
    return specialize(_steady_opening, name, outlet=outlet)
