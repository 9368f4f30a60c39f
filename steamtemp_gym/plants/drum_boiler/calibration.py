"""Packing and calibration of the drum boiler plant: DrumBoilerParams -> the flat vector
P and the Jacobian pattern, with the gas-side conductances sized so that the rated
design holds and the design-spray function generator from the steady sprays."""

from __future__ import annotations

import functools
import math

import numpy as np

from steamtemp_gym._jit import read_only
from steamtemp_gym.plants import drum as dr
from steamtemp_gym.plants.attemperator import mix
from steamtemp_gym.plants.base import D_FOULING, D_LOAD, K0
from steamtemp_gym.plants.copies import write_copies
from steamtemp_gym.plants.drum_boiler.kernel import boundary, feedwater
from steamtemp_gym.plants.drum_boiler.layout import (
    COPIED,
    DSP_LOADS,
    FW_DT_K,
    FW_T0_K,
    IP,
    IX,
    N_FW,
    N_P,
    SHARE_1,
    pattern,
)
from steamtemp_gym.plants.drum_boiler.params import DrumBoilerParams
from steamtemp_gym.plants.drum_boiler.steady_state import steady
from steamtemp_gym.plants.integrator import pattern_arrays
from steamtemp_gym.plants.roots import secant
from steamtemp_gym.plants.superheater import chain_steady, pipe_cells, steam_side_kA
from steamtemp_gym.steam import h_pT, rho_ph, sat_p


def _secant(fun, a: float, b: float, tol: float = 1e-6) -> float:
    """Root of fun by the secant method from a, b."""
    return secant(fun, a, b, tol)[0]


def _calibrate(params: DrumBoilerParams, P: np.ndarray, n_x: int) -> None:
    """Level reference, rated firing and SH gas-side conductances (writes P in place).

    Rated design: drum steam q_s,nom at p_drum and T_fw,nom, spray fraction s of the
    main steam W_nom = q_s,nom/(1 - s); UA_g1 gives T_primary_out after the primary SH,
    UA_g2 then gives T_out at the outlet.
    """
    x = np.zeros(n_x)
    Pk = read_only(P)  # what the kernels read (see steamtemp_gym._jit.read_only)
    n = params.n_segments
    c2 = IX.CHAIN1 + 2 * n
    p = params.p_drum_MPa * 1e6
    q_s = params.q_s_nom_kg_s
    h_f, _, _ = feedwater(Pk, P[IP.TFW])
    # level reference: l = 0 at V_wt = V_wt,nom in the rated steady state
    P[IP.DRUM + dr.D_L0] = 0.0
    Q, _ = dr.drum_steady(p, q_s, h_f, 0.0, Pk, IP.DRUM, x, IX.DRUM)
    P[IP.QNOM] = Q
    dV = params.V_wt_nom_m3 - x[IX.DRUM + dr.VWT]
    P[IP.DRUM + dr.D_L0] = dV / params.A_d_m2
    # gas side at rated firing
    W = P[IP.WNOM]
    w_sp = W - q_s
    dpsh = P[IP.DPSH]
    p1, p2 = p - SHARE_1 * dpsh, p - dpsh
    h_s = float(sat_p(p)[4])
    h1_target = h_pT(p1, params.T_primary_out_C + K0)
    kA1 = steam_side_kA(P[IP.KA1], q_s, q_s)[0]
    kA2 = steam_side_kA(P[IP.KA2], W, W)[0]
    q1 = q_s * (h1_target - h_s) / n / 300.0
    P[IP.UAG1] = _secant(
        lambda g: chain_steady(x, IX.CHAIN1, n, h_s, q_s, p1, kA1, g, P[IP.TG1], 0.0) - h1_target,
        q1,
        1.2 * q1,
    )
    h_sp, rho_sp, _ = feedwater(Pk, P[IP.TFW])
    _, h_att = mix(q_s, h1_target, w_sp, h_sp)
    h_out = h_pT(p2, params.T_out_C + K0)
    q2 = W * (h_out - h_att) / n / 500.0
    P[IP.UAG2] = _secant(
        lambda g: chain_steady(x, c2, n, h_att, W, p2, kA2, g, P[IP.TG2], 0.0) - h_out,
        q2,
        1.2 * q2,
    )
    P[IP.CV] = params.spray_max_fraction * W / math.sqrt(rho_sp * P[IP.DPSP])


@functools.lru_cache(maxsize=32)
def pack_params(params: DrumBoilerParams) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    n = params.n_segments
    P = np.zeros(N_P)
    write_copies(P, IP, COPIED, params)
    s = params.spray_design_fraction
    P[IP.WNOM] = params.q_s_nom_kg_s / (1.0 - s)
    for i, (ika, iv, icm) in enumerate(
        ((IP.KA1, IP.V1, IP.CM1), (IP.KA2, IP.V2, IP.CM2)),
        start=1,
    ):
        nt = getattr(params, f"n_tubes_{i}")
        di, do = getattr(params, f"tube_id_{i}_m"), getattr(params, f"tube_od_{i}_m")
        seg = getattr(params, f"tube_length_{i}_m") / n
        P[ika] = params.alpha_nom_W_m2K * math.pi * di * seg * nt
        P[iv] = math.pi / 4.0 * di**2 * seg * nt
        P[icm] = (
            math.pi
            / 4.0
            * (do**2 - di**2)
            * seg
            * nt
            * params.rho_metal_kg_m3
            * params.c_metal_J_kgK
        )
    P[IP.LV], P[IP.LCM] = pipe_cells(
        params.n_line, params.line_volume_m3, params.line_metal_t, params.c_metal_J_kgK
    )
    P[IP.DRUM : IP.DRUM + dr.N_DRUM_P] = dr.drum_block(
        params.V_d_m3,
        params.V_r_m3,
        params.V_dc_m3,
        params.m_t_kg,
        params.m_r_kg,
        params.m_d_kg,
        params.C_p_J_kgK,
        params.A_d_m2,
        params.A_dc_m2,
        params.k_friction,
        params.beta,
        params.T_d_s,
        params.V_sd0_m3,
    )
    p_fw = params.p_fw_MPa * 1e6
    for k in range(N_FW):
        h = h_pT(p_fw, FW_T0_K + FW_DT_K * k)
        P[IP.FW + k] = h
        P[IP.FW + N_FW + k] = rho_ph(p_fw, h)
    n_x = IX.CHAIN1 + 4 * n + 1 + params.n_line + 4
    _calibrate(params, P, n_x)
    # design-spray function generator: the undisturbed steady sprays at DSP_LOADS
    D = np.zeros((len(DSP_LOADS), 5))
    D[:, D_LOAD], D[:, D_FOULING] = DSP_LOADS, 1.0
    X = np.zeros((len(DSP_LOADS), n_x))
    Pk = read_only(P)
    steady(D, np.full(len(DSP_LOADS), params.T_out_C + K0), Pk, X)
    for k in range(len(DSP_LOADS)):
        P[IP.DSP + k] = boundary(X[k], D[k], Pk)[4]
    pat = pattern(n, params.n_line)
    jrow, jcol = pattern_arrays(pat)
    P.setflags(write=False)
    return P, jrow, jcol, n_x
