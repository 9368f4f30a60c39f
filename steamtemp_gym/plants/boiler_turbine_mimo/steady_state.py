"""Steady state of the boiler-turbine unit: the operating point at which SP1, SP2 and
RGD hold their targets under the built-in controllers."""

from __future__ import annotations

from steamtemp_gym._jit import njit
from steamtemp_gym.plants.base import D_HEAT_BIAS, D_LOAD
from steamtemp_gym.plants.boiler_turbine_mimo.kernel import (
    _gas,
    _h_crh_target,
    _h_up_target,
    _kA,
    _line_offsets,
    _offsets,
    _pressure,
    _reheat_pressure,
    _sprays,
)
from steamtemp_gym.plants.boiler_turbine_mimo.layout import (
    I_FRH,
    I_KAF_F,
    I_KAF_P,
    I_KAF_PL,
    I_KAF_R,
    I_KAW_F,
    I_KAW_P,
    I_KAW_PL,
    I_KAW_R,
    I_N1,
    I_N2,
    I_N3,
    I_N4,
    I_NL,
    I_NRL,
    I_TRH,
    I_WNOM,
    S_A11,
    S_A12,
    S_A21,
    S_A22,
    S_CRH,
    S_FB,
    S_G,
    S_HUP,
    S_LF,
    S_LW,
    S_MILL,
    S_TR1,
    S_TR2,
    S_TS1,
    S_TS2,
    S_V1,
    S_V2,
)
from steamtemp_gym.plants.superheater import chain_steady, pipe_steady
from steamtemp_gym.plants.valve import steady_opening
from steamtemp_gym.steam import T_ph


@njit(cache=True)
def _rh_steady(x, g, d, P):
    """Steady reheater outlet enthalpy at RGD opening g (x holds loads and x[S_CRH])."""
    o_r = _offsets(P)[3]
    n4 = int(P[I_N4])
    x[S_G] = g
    lw = min(max(x[S_LW], 0.05), 1.3)
    prh, _ = _reheat_pressure(P, lw)
    Wr = P[I_FRH] * lw * P[I_WNOM]
    kA = _kA(P[I_KAF_R], P[I_KAW_R], Wr, P[I_FRH] * P[I_WNOM])[0]
    uag_r, tg_r = _gas(P, x[S_LF], g, d)[2], _gas(P, x[S_LF], g, d)[5]
    return chain_steady(x, o_r, n4, x[S_CRH], Wr, prh, kA / n4, uag_r / n4, tg_r, 0.0)


@njit(cache=True)
def _sh_steady(x, v, d, P):
    """Steady STE enthalpy with both spray valves at opening v (x holds loads, h_up, RGD)."""
    o_p, o_pl, o_f, _ = _offsets(P)
    n1, n2, n3 = int(P[I_N1]), int(P[I_N2]), int(P[I_N3])
    x[S_V1] = v
    x[S_V2] = v
    lw = min(max(x[S_LW], 0.05), 1.3)
    W = lw * P[I_WNOM]
    p, _ = _pressure(P, lw)
    h_sp, w1, w2, _, _ = _sprays(P, x, d, lw)
    uag_p, uag_f, _, tg_p, tg_f, _, q_pl = _gas(P, x[S_LF], x[S_G], d)
    Wp, Wpl = W - w1 - w2, W - w2
    kA = _kA(P[I_KAF_P], P[I_KAW_P], Wp, P[I_WNOM])[0]
    h_po = chain_steady(x, o_p, n1, x[S_HUP], Wp, p, kA / n1, uag_p / n1, tg_p, 0.0)
    kA = _kA(P[I_KAF_PL], P[I_KAW_PL], Wpl, P[I_WNOM])[0]
    h_plo = chain_steady(x, o_pl, n2, (Wp * h_po + w1 * h_sp) / Wpl, Wpl, p, kA / n2, 0.0, 0.0,
                         q_pl / n2)  # fmt: skip
    kA = _kA(P[I_KAF_F], P[I_KAW_F], W, P[I_WNOM])[0]
    return chain_steady(x, o_f, n3, (Wpl * h_plo + w2 * h_sp) / W, W, p, kA / n3, uag_f / n3,
                        tg_f, 0.0)  # fmt: skip


@njit(cache=True)
def _neg_reheat_T(x, g, d, P, prh):  # noqa: N803
    """Minus the steady reheat outlet temperature (K) at RGD opening g (it rises with g)."""
    return -T_ph(prh, _rh_steady(x, g, d, P))


@njit(cache=True)
def _main_steam_T(x, v, d, P, p):  # noqa: N803
    """Steady STE (K) at common spray opening v."""
    return T_ph(p, _sh_steady(x, v, d, P))


_rgd_for = steady_opening("BoilerTurbineMIMO.rgd", _neg_reheat_T)
_spray_for = steady_opening("BoilerTurbineMIMO.spray", _main_steam_T)


@njit(cache=True)
def _bisect_rgd(x, d, P, T_target):  # noqa: N803
    """RGD opening holding the reheat outlet at T_target (K), clipped to [0, 1]."""
    prh, _ = _reheat_pressure(P, min(max(x[S_LW], 0.05), 1.3))
    return _rgd_for(x, d, P, prh, -T_target)


@njit(cache=True)
def _bisect_spray(x, d, P, T_target):  # noqa: N803
    """Common spray opening holding STE at T_target (K), clipped to [0, 1]."""
    p, _ = _pressure(P, min(max(x[S_LW], 0.05), 1.3))
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
        x[S_LF] = L
        x[S_MILL] = L
        x[S_LW] = L
        x[S_FB] = 0.5
        x[S_HUP] = _h_up_target(P, L, L, d[D_HEAT_BIAS])
        x[S_CRH] = _h_crh_target(P, sp_K[b], L)
        x[S_G] = _bisect_rgd(x, d, P, P[I_TRH])
        _rh_steady(x, x[S_G], d, P)
        v = _bisect_spray(x, d, P, sp_K[b])
        _sh_steady(x, v, d, P)
        lw = L
        W = lw * P[I_WNOM]
        p, _ = _pressure(P, lw)
        prh, _ = _reheat_pressure(P, lw)
        h_sp, w1, w2, _, _ = _sprays(P, x, d, lw)
        o_p, o_pl, o_f, o_r = _offsets(P)
        Wp, Wpl = W - w1 - w2, W - w2
        T1 = T_ph(p, (Wp * x[o_pl - 1] + w1 * h_sp) / Wpl)
        T2 = T_ph(p, (Wpl * x[o_f - 1] + w2 * h_sp) / W)
        T_ms = T_ph(p, x[o_r - 1])
        n4 = int(P[I_N4])
        T_r = T_ph(prh, x[o_r + 2 * n4 - 1])
        o_l, o_rl = _line_offsets(P)
        pipe_steady(x, o_l, int(P[I_NL]), x[o_r - 1])
        pipe_steady(x, o_rl, int(P[I_NRL]), x[o_r + 2 * n4 - 1])
        x[S_TS1] = x[S_TS2] = T_ms
        x[S_TR1] = x[S_TR2] = T_r
        x[S_A11] = x[S_A12] = T1
        x[S_A21] = x[S_A22] = T2
