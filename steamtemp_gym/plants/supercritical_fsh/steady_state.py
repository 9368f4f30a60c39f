"""Steady state of the supercritical final superheater: the valve opening that holds the
setpoint at each row's disturbances, and the states at rest."""

from __future__ import annotations

from steamtemp_gym._jit import njit
from steamtemp_gym.plants.base import (
    D_HEAT_BIAS,
    D_LOAD,
)
from steamtemp_gym.plants.supercritical_fsh.kernel import (
    boundary,
    h_up_target,
    pressure,
)
from steamtemp_gym.plants.supercritical_fsh.layout import IP, IX, s_line, s_mill
from steamtemp_gym.plants.superheater import (
    chain_steady,
    pipe_steady,
)
from steamtemp_gym.plants.valve import steady_opening
from steamtemp_gym.steam import T_dTdh_ph


@njit(cache=True, error_model="numpy")
def _outlet_steady(x, v, d, P, lw):
    """Steady FSH outlet enthalpy for valve opening v (x holds h_up; chain written into x)."""
    n = int(P[IP.N])
    x[IX.V] = v
    W, p, w_sp, h0, h_sp, kA, UAg, Tg, capped = boundary(x, x[IX.V : IX.V + 1], d, P)
    return chain_steady(x, IX.CHAIN, n, h0, W, p, kA[0], UAg, Tg, 0.0)


@njit(cache=True, error_model="numpy")
def _outlet_T(x, v, d, P, aux):  # noqa: N803
    """Steady outlet temperature (K) at opening v; aux = (pressure Pa, load)."""
    return T_dTdh_ph(aux[0], _outlet_steady(x, v, d, P, aux[1]))[0]


_opening_for = steady_opening("SupercriticalFSH", _outlet_T)


@njit(cache=True, error_model="numpy")
def steady(D, sp_K, P, X):
    """Steady state at each row's disturbances, valve set by bisection to hold sp_K."""
    for b in range(X.shape[0]):
        x = X[b]
        d = D[b]
        L = min(max(d[D_LOAD], 0.05), 1.3)
        n = int(P[IP.N])
        x[IX.LF] = L
        x[s_mill(n)] = L
        x[IX.LW] = L
        x[IX.HUP] = h_up_target(P, L, L, d[D_HEAT_BIAS])
        p = pressure(P, L)
        v = _opening_for(x, d, P, (p, L), sp_K[b])
        h_out = _outlet_steady(x, v, d, P, L)
        W, p, w_sp, h0, h_sp, kA, UAg, Tg, capped = boundary(x, x[IX.V : IX.V + 1], d, P)
        T_out, _ = T_dTdh_ph(p, h_out)
        T_att, _ = T_dTdh_ph(p, h0)
        x[IX.TC1] = T_out
        x[IX.TC2] = T_out
        pipe_steady(x, s_line(n), int(P[IP.NL]), h_out)
        x[IX.TA1] = T_att
        x[IX.TA2] = T_att
