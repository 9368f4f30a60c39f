"""Steady state of the boiler-turbine unit: the operating point at which SP1, SP2 and
RGD hold their targets under the built-in controllers."""

from __future__ import annotations

from steamtemp_gym._jit import njit
from steamtemp_gym.plants.base import D_HEAT_BIAS, D_LOAD
from steamtemp_gym.plants.boiler_turbine_mimo.kernel import (
    gas_side,
    h_crh_target,
    h_up_target,
    line_offsets,
    offsets,
    pressure,
    reheat_pressure,
    sprays,
    tube_kA,
)
from steamtemp_gym.plants.boiler_turbine_mimo.layout import IP, IX
from steamtemp_gym.plants.superheater import chain_steady, pipe_steady
from steamtemp_gym.plants.valve import steady_opening
from steamtemp_gym.steam import T_ph


@njit(cache=True)
def _rh_steady(x, g, d, P):
    """Steady reheater outlet enthalpy at RGD opening g (x holds loads and x[IX.CRH])."""
    o_r = offsets(P)[3]
    n4 = int(P[IP.N4])
    x[IX.G] = g
    lw = min(max(x[IX.LW], 0.05), 1.3)
    prh, _ = reheat_pressure(P, lw)
    Wr = P[IP.FRH] * lw * P[IP.WNOM]
    kA = tube_kA(P[IP.KAF_R], P[IP.KAW_R], Wr, P[IP.FRH] * P[IP.WNOM])[0]
    uag_r, tg_r = gas_side(P, x[IX.LF], g, d)[2], gas_side(P, x[IX.LF], g, d)[5]
    return chain_steady(x, o_r, n4, x[IX.CRH], Wr, prh, kA / n4, uag_r / n4, tg_r, 0.0)


@njit(cache=True)
def sh_steady(x, v, d, P):
    """Steady STE enthalpy with both spray valves at opening v (x holds loads, h_up, RGD)."""
    o_p, o_pl, o_f, _ = offsets(P)
    n1, n2, n3 = int(P[IP.N1]), int(P[IP.N2]), int(P[IP.N3])
    x[IX.V1] = v
    x[IX.V2] = v
    lw = min(max(x[IX.LW], 0.05), 1.3)
    W = lw * P[IP.WNOM]
    p, _ = pressure(P, lw)
    h_sp, w1, w2, _, _ = sprays(P, x, d, lw)
    uag_p, uag_f, _, tg_p, tg_f, _, q_pl = gas_side(P, x[IX.LF], x[IX.G], d)
    Wp, Wpl = W - w1 - w2, W - w2
    kA = tube_kA(P[IP.KAF_P], P[IP.KAW_P], Wp, P[IP.WNOM])[0]
    h_po = chain_steady(x, o_p, n1, x[IX.HUP], Wp, p, kA / n1, uag_p / n1, tg_p, 0.0)
    kA = tube_kA(P[IP.KAF_PL], P[IP.KAW_PL], Wpl, P[IP.WNOM])[0]
    h_plo = chain_steady(
        x, o_pl, n2, (Wp * h_po + w1 * h_sp) / Wpl, Wpl, p, kA / n2, 0.0, 0.0, q_pl / n2
    )
    kA = tube_kA(P[IP.KAF_F], P[IP.KAW_F], W, P[IP.WNOM])[0]
    return chain_steady(
        x, o_f, n3, (Wpl * h_plo + w2 * h_sp) / W, W, p, kA / n3, uag_f / n3, tg_f, 0.0
    )


@njit(cache=True)
def _neg_reheat_T(x, g, d, P, prh):  # noqa: N803
    """Minus the steady reheat outlet temperature (K) at RGD opening g (it rises with g)."""
    return -T_ph(prh, _rh_steady(x, g, d, P))


@njit(cache=True)
def _main_steam_T(x, v, d, P, p):  # noqa: N803
    """Steady STE (K) at common spray opening v."""
    return T_ph(p, sh_steady(x, v, d, P))


_rgd_for = steady_opening("BoilerTurbineMIMO.rgd", _neg_reheat_T)
_spray_for = steady_opening("BoilerTurbineMIMO.spray", _main_steam_T)


@njit(cache=True)
def bisect_rgd(x, d, P, T_target):  # noqa: N803
    """RGD opening holding the reheat outlet at T_target (K), clipped to [0, 1]."""
    prh, _ = reheat_pressure(P, min(max(x[IX.LW], 0.05), 1.3))
    return _rgd_for(x, d, P, prh, -T_target)


@njit(cache=True)
def _bisect_spray(x, d, P, T_target):  # noqa: N803
    """Common spray opening holding STE at T_target (K), clipped to [0, 1]."""
    p, _ = pressure(P, min(max(x[IX.LW], 0.05), 1.3))
    return _spray_for(x, d, P, p, T_target)


@njit(cache=True)
def steady(D, sp_K, P, X):
    """Steady state at each row's disturbances holding STE = sp_K and RTE at its setpoint.

    RGD is set first (the reheater sees STE only through the HP-turbine exhaust, which
    is fixed by STE = sp), then both spray valves at a common opening.
    """
    for b in range(X.shape[0]):
        x = X[b]
        d = D[b]
        L = min(max(d[D_LOAD], 0.05), 1.3)
        x[IX.LF] = L
        x[IX.MILL] = L
        x[IX.LW] = L
        x[IX.FB] = 0.5
        x[IX.HUP] = h_up_target(P, L, L, d[D_HEAT_BIAS])
        x[IX.CRH] = h_crh_target(P, sp_K[b], L)
        x[IX.G] = bisect_rgd(x, d, P, P[IP.TRH])
        _rh_steady(x, x[IX.G], d, P)
        v = _bisect_spray(x, d, P, sp_K[b])
        sh_steady(x, v, d, P)
        lw = L
        W = lw * P[IP.WNOM]
        p, _ = pressure(P, lw)
        prh, _ = reheat_pressure(P, lw)
        h_sp, w1, w2, _, _ = sprays(P, x, d, lw)
        o_p, o_pl, o_f, o_r = offsets(P)
        Wp, Wpl = W - w1 - w2, W - w2
        T1 = T_ph(p, (Wp * x[o_pl - 1] + w1 * h_sp) / Wpl)
        T2 = T_ph(p, (Wpl * x[o_f - 1] + w2 * h_sp) / W)
        T_ms = T_ph(p, x[o_r - 1])
        n4 = int(P[IP.N4])
        T_r = T_ph(prh, x[o_r + 2 * n4 - 1])
        o_l, o_rl = line_offsets(P)
        pipe_steady(x, o_l, int(P[IP.NL]), x[o_r - 1])
        pipe_steady(x, o_rl, int(P[IP.NRL]), x[o_r + 2 * n4 - 1])
        x[IX.TS1] = x[IX.TS2] = T_ms
        x[IX.TR1] = x[IX.TR2] = T_r
        x[IX.A11] = x[IX.A12] = T1
        x[IX.A21] = x[IX.A22] = T2
