"""Steady state of the drum boiler plant: drum, firing, superheaters and the spray
opening that holds the outlet setpoint."""

from __future__ import annotations

from steamtemp_gym._jit import njit
from steamtemp_gym.plants import drum as dr
from steamtemp_gym.plants.attemperator import mix
from steamtemp_gym.plants.base import D_LOAD, D_LOAD_RATE
from steamtemp_gym.plants.drum_boiler.kernel import boundary
from steamtemp_gym.plants.drum_boiler.layout import IP, IW, IX, S_P, s_line, s_mill, sensors
from steamtemp_gym.plants.superheater import chain_steady, pipe_steady, steam_side_kA
from steamtemp_gym.plants.valve import steady_opening
from steamtemp_gym.steam import T_dTdh_ph, sat_p


@njit(cache=True)
def _steady_at(x, v, d, P):
    """Steady plant state for valve opening v at x[IX.W] (drum, firing, chains written into x).

    Returns the main-steam enthalpy (J/kg).
    """
    n = int(P[IP.N])
    c2 = IX.CHAIN1 + 2 * n
    x[IX.V] = v
    w_prev = -1.0
    h_out = 0.0
    # fixed point on the spray: the protection cap depends on the primary SH outlet
    for _ in range(30):
        bd = boundary(x, d, P)
        q_s, h_f = bd[3], bd[6]
        Q, _ = dr.drum_steady(P[IP.PSP], q_s, h_f, 0.0, P, IP.DRUM, x, IX.DRUM)
        L_f = Q / P[IP.QNOM]
        x[IX.LF] = L_f
        x[s_mill(n)] = L_f
        x[IX.QF] = q_s
        x[IX.IL] = 0.0
        x[IX.IP] = L_f - min(max(d[D_LOAD], 0.0), 1.3) - P[IP.TBIR] * d[D_LOAD_RATE]
        W, lw, dWok, q_s, w_sp, dw_dv, h_f, dhf, h_sp, p1, p2, dp1, dp2, L_f, mult = boundary(
            x, d, P
        )
        h_s = sat_p(P[IP.PSP])[4]
        kA1 = steam_side_kA(P[IP.KA1], q_s, P[IP.QSN])[0]
        Tg1 = P[IP.TG1] - P[IP.DTG1] * (1.0 - L_f)
        h1 = chain_steady(x, IX.CHAIN1, n, h_s, q_s, p1, kA1, P[IP.UAG1] * mult, Tg1, 0.0)
        _, h_att = mix(q_s, h1, w_sp, h_sp)
        kA2 = steam_side_kA(P[IP.KA2], W, P[IP.WNOM])[0]
        Tg2 = P[IP.TG2] - P[IP.DTG2] * (1.0 - L_f)
        h_out = chain_steady(x, c2, n, h_att, W, p2, kA2, P[IP.UAG2] * mult, Tg2, 0.0)
        if abs(w_sp - w_prev) < 1e-9:
            break
        w_prev = w_sp
    return h_out


@njit(cache=True)
def _outlet_T(x, v, d, P, p2):  # noqa: N803
    """Steady outlet temperature (K) at spray opening v and outlet pressure p2 (Pa)."""
    return T_dTdh_ph(p2, _steady_at(x, v, d, P))[0]


_opening_for = steady_opening("DrumBoilerSH", _outlet_T)


@njit(cache=True)
def steady(D, sp_K, P, X):
    """Steady state at each row's disturbances; spray valve set by bisection to hold sp_K."""
    for b in range(X.shape[0]):
        x = X[b]
        d = D[b]
        x[IX.W] = min(max(d[D_LOAD], 0.05), 1.3) * P[IP.WNOM]
        x[S_P] = P[IP.PSP]
        p2 = P[IP.PSP] - P[IP.DPSH] * (x[IX.W] / P[IP.WNOM]) ** 2
        v = _opening_for(x, d, P, p2, sp_K[b])
        h_out = _steady_at(x, v, d, P)
        bd = boundary(x, d, P)
        q_s, w_sp, h_sp, p1, p2 = bd[3], bd[4], bd[8], bd[9], bd[10]
        _, h_att = mix(q_s, x[IX.CHAIN1 + 2 * int(P[IP.N]) - 1], w_sp, h_sp)
        T_out, _ = T_dTdh_ph(p2, h_out)
        T_att, _ = T_dTdh_ph(p1, h_att)
        st = sensors(int(P[IP.N]), int(P[IP.NL]))
        pipe_steady(x, s_line(int(P[IP.N])), int(P[IP.NL]), h_out)
        x[st + IW.TC1] = T_out
        x[st + IW.TC2] = T_out
        x[st + IW.TA1] = T_att
        x[st + IW.TA2] = T_att
