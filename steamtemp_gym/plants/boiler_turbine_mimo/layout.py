"""Packed parameters of the boiler-turbine unit: indices of the scalars and the load
schedules in the flat vector P, of the states in x and of the outputs in z, and the
Jacobian pattern the rhs fills."""

from __future__ import annotations

import numpy as np

from steamtemp_gym.plants.boiler_turbine_mimo.params import BoilerTurbineParams
from steamtemp_gym.plants.superheater import chain_pattern, pipe_pattern

# Indices into P (module constants, frozen into the kernels).
I_N1, I_N2, I_N3, I_N4 = 0, 1, 2, 3  # segments: primary, platen, final, reheater
I_WNOM, I_PNOM, I_PMIN, I_KNEE, I_LMIN = 4, 5, 6, 7, 8
I_PRH, I_PRHMIN, I_FRH = 9, 10, 11
I_KAF_P, I_KAW_P, I_V_P, I_CM_P, I_UAG_P, I_TG_P = 12, 13, 14, 15, 16, 17
I_KAF_PL, I_KAW_PL, I_V_PL, I_CM_PL, I_Q_PL = 18, 19, 20, 21, 22
I_KAF_F, I_KAW_F, I_V_F, I_CM_F, I_UAG_F, I_TG_F = 23, 24, 25, 26, 27, 28
I_KAF_R, I_KAW_R, I_V_R, I_CM_R, I_UAG_R, I_TG_R = 29, 30, 31, 32, 33, 34
I_DTG, I_GEXP, I_REXP, I_RMAX, I_RNOM, I_PLGR = 35, 36, 37, 38, 39, 40
I_CV1, I_CV2, I_DPB = 41, 42, 43
I_TAUF, I_TBIR, I_TAUW, I_TAUUP, I_FWR, I_TAUHP = 44, 45, 46, 47, 48, 49
I_FBACT, I_FBMAX, I_TAUFB = 50, 51, 52
I_TAUV, I_RATEV, I_TAUD, I_RATED, I_TC1, I_TC2 = 53, 54, 55, 56, 57, 58
I_JOFF_PL, I_JOFF_F, I_JOFF_R = 59, 60, 61
I_VD, I_GD, I_TRH, I_DTGR = 62, 63, 64, 65  # design spray and RGD openings, RTE set (K)
I_TAUM, I_HERR, I_BUP, I_NL, I_LCM, I_LV, I_NRL, I_RLCM, I_RLV, I_JOFF_L, I_JOFF_RL = range(
    66, 77)  # fmt: skip
I_TAB = 80  # start of the load schedule tables
TAB_LOADS = np.linspace(0.2, 1.2, 21)
N_TAB = TAB_LOADS.shape[0]
# schedule tables (offset I_TAB + k * N_TAB)
T_HUP, T_RISE, T_HSP, T_RHOSP, T_CPSP, T_CRHR, T_HCRH, T_CPCRH, T_TCRH = range(9)
N_P = I_TAB + 9 * N_TAB
# State indices (the chains follow from S_CHAIN: primary, platen, final, reheater)
S_LF, S_LW, S_HUP, S_V1, S_V2, S_G, S_FB, S_CRH = range(8)
S_TS1, S_TS2, S_TR1, S_TR2, S_A11, S_A12, S_A21, S_A22 = range(8, 16)
S_MILL = 16  # coal flow out of the mills, fraction of rated firing
S_CHAIN = 17  # then the chains, then the main-steam line and hot-reheat line cells
# Output indices (order of BoilerTurbineMIMO.outputs)
(Z_STE, Z_STEM, Z_RTE, Z_RTEM, Z_T1, Z_T1M, Z_T2, Z_T2M, Z_TCRH, Z_W, Z_P, Z_V1, Z_V2, Z_G,
 Z_FB, Z_W1, Z_W2, Z_LF, Z_Q, Z_QRH, Z_TMMAX, Z_WDES, Z_TFSH, Z_TRHO) = range(24)  # fmt: skip


def patterns(params: BoilerTurbineParams) -> list[tuple[int, int]]:
    """Strictly-lower Jacobian pattern of the unit (the four chains, in row order)."""
    n1, n2, n3, n4 = (
        params.n_seg_primary,
        params.n_seg_platen,
        params.n_seg_final,
        params.n_seg_reheat,
    )
    o_p = S_CHAIN
    o_pl = o_p + 2 * n1
    o_f = o_pl + 2 * n2
    o_r = o_f + 2 * n3
    o_l = o_r + 2 * n4
    o_rl = o_l + params.n_line
    return (
        chain_pattern(o_p, n1, (S_HUP,), S_LW)
        + chain_pattern(o_pl, n2, (o_pl - 1, S_V1, S_V2), S_LW)
        + chain_pattern(o_f, n3, (o_f - 1, S_V2), S_LW)
        + chain_pattern(o_r, n4, (S_CRH,), S_LW)
        + pipe_pattern(o_l, params.n_line, (o_r - 1,), S_LW)
        + pipe_pattern(o_rl, params.n_rh_line, (o_l - 1,), S_LW)
    )
