"""Packing and calibration of the boiler-turbine unit: BoilerTurbineParams -> the flat
vector P and the Jacobian pattern, with the gas sides, the platen's radiant heat, the
valves and the load schedules sized so that the rated balance holds."""

from __future__ import annotations

import functools
import math

import numpy as np

from steamtemp_gym._jit import read_only
from steamtemp_gym.plants.base import D_LOAD
from steamtemp_gym.plants.boiler_turbine_mimo.kernel import (
    _h_crh_target,
    _kA,
    _offsets,
    _pressure,
    _reheat_pressure,
    _tab,
)
from steamtemp_gym.plants.boiler_turbine_mimo.layout import (
    I_BUP,
    I_CM_F,
    I_CM_P,
    I_CM_PL,
    I_CM_R,
    I_CV1,
    I_CV2,
    I_DPB,
    I_DTG,
    I_DTGR,
    I_FBACT,
    I_FBMAX,
    I_FRH,
    I_FWR,
    I_GD,
    I_GEXP,
    I_HERR,
    I_JOFF_F,
    I_JOFF_L,
    I_JOFF_PL,
    I_JOFF_R,
    I_JOFF_RL,
    I_KAF_F,
    I_KAF_P,
    I_KAF_PL,
    I_KAF_R,
    I_KAW_F,
    I_KAW_P,
    I_KAW_PL,
    I_KAW_R,
    I_KNEE,
    I_LCM,
    I_LMIN,
    I_LV,
    I_N1,
    I_N2,
    I_N3,
    I_N4,
    I_NL,
    I_NRL,
    I_PLGR,
    I_PMIN,
    I_PNOM,
    I_PRH,
    I_PRHMIN,
    I_Q_PL,
    I_RATED,
    I_RATEV,
    I_REXP,
    I_RLCM,
    I_RLV,
    I_RMAX,
    I_RNOM,
    I_TAB,
    I_TAUD,
    I_TAUF,
    I_TAUFB,
    I_TAUHP,
    I_TAUM,
    I_TAUUP,
    I_TAUV,
    I_TAUW,
    I_TBIR,
    I_TC1,
    I_TC2,
    I_TG_F,
    I_TG_P,
    I_TG_R,
    I_TRH,
    I_UAG_F,
    I_UAG_P,
    I_UAG_R,
    I_V_F,
    I_V_P,
    I_V_PL,
    I_V_R,
    I_VD,
    I_WNOM,
    N_P,
    N_TAB,
    S_CHAIN,
    S_CRH,
    S_FB,
    S_G,
    S_HUP,
    S_LF,
    S_LW,
    T_CPCRH,
    T_CPSP,
    T_CRHR,
    T_HCRH,
    T_HSP,
    T_HUP,
    T_RHOSP,
    T_RISE,
    T_TCRH,
    TAB_LOADS,
    patterns,
)
from steamtemp_gym.plants.boiler_turbine_mimo.params import K0, BoilerTurbineParams
from steamtemp_gym.plants.boiler_turbine_mimo.steady_state import _bisect_rgd, _sh_steady
from steamtemp_gym.plants.integrator import pattern_arrays
from steamtemp_gym.plants.roots import secant
from steamtemp_gym.plants.superheater import chain_steady
from steamtemp_gym.steam import T_ph, cp_pT, h_pT, rho_ph


def _secant(fun, a: float, b: float, what: str, tol: float = 1e-4) -> float:
    """Root of fun by the secant method (ValueError naming ``what`` if it fails)."""
    b, fb = secant(fun, a, b, tol)
    if abs(fb) < tol or (abs(fb) < 1e-2 and math.isfinite(b) and b > 0):
        return b
    raise ValueError(
        f"BoilerTurbineParams: cannot calibrate {what} (check the design temperatures)"
    )


def _calibrate(params: BoilerTurbineParams, P: np.ndarray, n_x: int) -> None:
    """Size the gas side, sprays and load schedules so the rated design balance holds.

    Writes into P: spray-water and cold-reheat tables over TAB_LOADS, the valve
    coefficients, the platen's radiant heat, the convective UA_g of the primary SH, final
    SH and reheater (secant on the rated balance, design RGD opening), and the evaporator
    outlet schedule h_up(L) for which the design spray openings hold T_ms when RGD holds
    T_rh at load L.
    """
    x = np.zeros(n_x)
    Pk = read_only(P)  # what the kernels read (see steamtemp_gym._jit.read_only)
    o_p, o_pl, o_f, o_r = _offsets(Pk)
    n1, n2, n3, n4 = (int(P[i]) for i in (I_N1, I_N2, I_N3, I_N4))
    W = params.W_nom_kg_s
    T_ms = params.T_ms_C + K0
    p_nom = params.p_nom_MPa * 1e6
    kappa = math.log((params.T_crh_nom_C + K0) / T_ms) / math.log(
        params.p_rh_nom_MPa / params.p_nom_MPa
    )
    for k, L in enumerate(TAB_LOADS):
        p, _ = _pressure(Pk, L)
        p_sp = p + P[I_DPB] * L * L
        T_fw = params.T_fw_nom_C + K0 - params.dT_fw_dload_K * (1.0 - L)
        h = h_pT(p_sp, T_fw)
        P[I_TAB + T_HSP * N_TAB + k] = h
        P[I_TAB + T_RHOSP * N_TAB + k] = rho_ph(p_sp, h)
        P[I_TAB + T_CPSP * N_TAB + k] = cp_pT(p_sp, T_fw)
        prh, _ = _reheat_pressure(Pk, L)
        ratio = (prh / p) ** kappa
        P[I_TAB + T_CRHR * N_TAB + k] = ratio
        P[I_TAB + T_TCRH * N_TAB + k] = T_ms * ratio
        P[I_TAB + T_HCRH * N_TAB + k] = h_pT(prh, T_ms * ratio)
        P[I_TAB + T_CPCRH * N_TAB + k] = cp_pT(prh, T_ms * ratio)
    # spray valves: the design opening passes the design fraction at rated load
    h_sp = _tab(Pk, T_HSP, 1.0)
    s = math.sqrt(_tab(Pk, T_RHOSP, 1.0) * P[I_DPB])
    P[I_CV1] = params.sp1_design_fraction * W / (params.valve_design_opening * s)
    P[I_CV2] = params.sp2_design_fraction * W / (params.valve_design_opening * s)
    # rated design balance
    w1, w2 = params.sp1_design_fraction * W, params.sp2_design_fraction * W
    Wp, Wpl = W - w1 - w2, W - w2
    h_ms = h_pT(p_nom, T_ms)
    h_fi = h_pT(p_nom, params.T_sp2_out_design_C + K0)
    h_pli = h_pT(p_nom, params.T_sp1_out_design_C + K0)
    h_up = h_pT(p_nom, params.T_up_design_C + K0)
    h_plo = (W * h_fi - w2 * h_sp) / Wpl
    h_po = (Wpl * h_pli - w1 * h_sp) / Wp
    if not (h_plo > h_pli and h_po > h_up):
        raise ValueError(
            "BoilerTurbineParams: the design temperatures and sprays leave no heat for the "
            "platen or the primary SH"
        )
    P[I_Q_PL] = Wpl * (h_plo - h_pli)
    d = np.array([1.0, 0.0, 0.0, 1.0, 0.0])

    def stage(i_uag, off, n, h_in, w, p, kA, tg, h_out, what):
        def out(uag):
            return chain_steady(x, off, n, h_in, w, p, kA / n, uag / n, tg, 0.0) - h_out

        T_out = T_ph(p, h_out)
        a = w * (h_out - h_in) / max(tg - T_out, 10.0)
        P[i_uag] = _secant(out, a, 1.3 * a, what)

    stage(I_UAG_F, o_f, n3, h_fi, W, p_nom, _kA(P[I_KAF_F], P[I_KAW_F], W, W)[0], P[I_TG_F], h_ms,
          "the final SH gas side")  # fmt: skip
    stage(I_UAG_P, o_p, n1, h_up, Wp, p_nom, _kA(P[I_KAF_P], P[I_KAW_P], Wp, W)[0], P[I_TG_P],
          h_po, "the primary SH gas side")  # fmt: skip
    Wr = P[I_FRH] * W
    prh, _ = _reheat_pressure(Pk, 1.0)
    stage(I_UAG_R, o_r, n4, _tab(Pk, T_HCRH, 1.0), Wr, prh, _kA(P[I_KAF_R], P[I_KAW_R], Wr, Wr)[0],
          P[I_TG_R], h_pT(prh, P[I_TRH]), "the reheater gas side")  # fmt: skip
    # evaporator-outlet schedule: design sprays hold T_ms where RGD holds T_rh
    for k, L in enumerate(TAB_LOADS):
        d[D_LOAD] = L
        x[S_LF] = x[S_LW] = L
        x[S_FB] = 0.5
        x[S_CRH] = _h_crh_target(Pk, T_ms, L)
        x[S_G] = _bisect_rgd(x, d, Pk, P[I_TRH])
        p, _ = _pressure(Pk, L)

        def ste(h, L=L, p=p):
            x[S_HUP] = h
            return T_ph(p, _sh_steady(x, P[I_VD], d, Pk)) - T_ms

        h = _secant(ste, h_up, h_up + 50e3, f"the evaporator-outlet schedule at load {L:.2f}")
        P[I_TAB + T_HUP * N_TAB + k] = h
        P[I_TAB + T_RISE * N_TAB + k] = h - _tab(Pk, T_HSP, L)


def _conductances(n_tubes: int, length: float, d_i: float, d_o: float, alpha: float, k: float,
                  rho_c: float) -> tuple[float, float, float, float]:  # fmt: skip
    """(kA_film at rated flow, kA_wall of eq. (4), steam volume, metal heat capacity) of a bank."""
    a_in = math.pi * d_i * length * n_tubes
    wall = a_in * 4.0 * k / (d_o - d_i)  # A / ((r_o - r_i) / (2 k))
    vol = math.pi / 4.0 * d_i**2 * length * n_tubes
    cm = math.pi / 4.0 * (d_o**2 - d_i**2) * length * n_tubes * rho_c
    return alpha * a_in, wall, vol, cm


@functools.lru_cache(maxsize=32)
def _pack(params: BoilerTurbineParams) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    q = params
    P = np.zeros(N_P)
    P[I_N1], P[I_N2], P[I_N3], P[I_N4] = (
        q.n_seg_primary,
        q.n_seg_platen,
        q.n_seg_final,
        q.n_seg_reheat,
    )
    P[I_WNOM] = q.W_nom_kg_s
    P[I_PNOM], P[I_PMIN] = q.p_nom_MPa * 1e6, q.p_min_MPa * 1e6
    P[I_KNEE], P[I_LMIN] = q.slide_knee_load, q.slide_min_load
    P[I_PRH], P[I_PRHMIN], P[I_FRH] = (
        q.p_rh_nom_MPa * 1e6,
        q.p_rh_min_MPa * 1e6,
        q.reheat_flow_fraction,
    )
    rc = q.rho_metal_kg_m3 * q.c_metal_J_kgK
    P[I_KAF_P], P[I_KAW_P], P[I_V_P], P[I_CM_P] = _conductances(
        q.primary_n_tubes, q.primary_length_m, q.primary_id_m, q.primary_od_m, q.alpha_sh_W_m2K,
        q.k_wall_W_mK, rc)  # fmt: skip
    P[I_KAF_F], P[I_KAW_F], P[I_V_F], P[I_CM_F] = _conductances(
        q.final_n_tubes, q.final_length_m, q.final_id_m, q.final_od_m, q.alpha_sh_W_m2K,
        q.k_wall_W_mK, rc)  # fmt: skip
    P[I_KAF_R], P[I_KAW_R], P[I_V_R], P[I_CM_R] = _conductances(
        q.reheat_n_tubes, q.reheat_length_m, q.reheat_id_m, q.reheat_od_m, q.alpha_rh_W_m2K,
        q.k_wall_W_mK, rc)  # fmt: skip
    P[I_KAF_PL], P[I_KAW_PL] = q.platen_kA_film_MW_K * 1e6, q.platen_kA_wall_MW_K * 1e6
    P[I_V_PL], P[I_CM_PL] = q.platen_volume_m3, q.platen_metal_MJ_K * 1e6
    P[I_TG_P], P[I_TG_F], P[I_TG_R] = q.Tg_primary_C + K0, q.Tg_final_C + K0, q.Tg_reheat_C + K0
    P[I_DTG], P[I_GEXP], P[I_REXP] = q.dTg_dload_K, q.gas_flow_exponent, q.radiant_exponent
    P[I_DTGR] = q.dTg_reheat_dload_K
    P[I_RMAX] = q.recirc_max_fraction
    P[I_RNOM] = q.recirc_max_fraction * q.rgd_design_opening
    P[I_PLGR] = q.platen_recirc_sensitivity
    P[I_DPB] = q.dp_boiler_nom_MPa * 1e6
    P[I_TAUF], P[I_TBIR], P[I_TAUW] = q.tau_firing_s, q.T_bir_s, q.tau_steam_s
    P[I_TAUUP], P[I_FWR], P[I_TAUHP] = q.tau_upstream_s, q.fwr_coupling, q.tau_hp_s
    P[I_FBACT], P[I_FBMAX], P[I_TAUFB] = (
        float(q.fuel_bias_action),
        q.fuel_bias_max,
        q.tau_fuel_bias_s,
    )
    P[I_TAUV], P[I_RATEV] = q.tau_valve_s, q.valve_rate_per_s
    P[I_TAUD], P[I_RATED] = q.tau_damper_s, q.damper_rate_per_s
    P[I_TC1], P[I_TC2] = q.tau_tc1_s, q.tau_tc2_s
    P[I_VD], P[I_GD], P[I_TRH] = q.valve_design_opening, q.rgd_design_opening, q.T_rh_C + K0
    n1, n2, n3, n4 = q.n_seg_primary, q.n_seg_platen, q.n_seg_final, q.n_seg_reheat
    P[I_JOFF_PL] = 4 * n1
    P[I_JOFF_F] = P[I_JOFF_PL] + 4 * n2 + 2
    P[I_JOFF_R] = P[I_JOFF_F] + 4 * n3 + 1
    P[I_TAUM], P[I_HERR], P[I_BUP] = q.tau_mill_s, q.fwr_schedule_error_kJ_kg * 1e3, \
        q.bias_upstream_share  # fmt: skip
    cm = q.c_metal_J_kgK * 1e3
    P[I_NL], P[I_LCM] = q.n_line, q.line_metal_t * cm / q.n_line
    P[I_LV] = q.line_volume_m3 / q.n_line
    P[I_NRL], P[I_RLCM], P[I_RLV] = (q.n_rh_line, q.rh_line_metal_t * cm / q.n_rh_line,
                                     q.rh_line_volume_m3 / q.n_rh_line)  # fmt: skip
    P[I_JOFF_L] = P[I_JOFF_R] + 4 * n4
    P[I_JOFF_RL] = P[I_JOFF_L] + 2 * q.n_line
    n_x = S_CHAIN + 2 * (n1 + n2 + n3 + n4) + q.n_line + q.n_rh_line
    _calibrate(params, P, n_x)
    pat = patterns(params)
    assert len(pat) == P[I_JOFF_RL] + 2 * q.n_rh_line
    jrow, jcol = pattern_arrays(pat)
    P.setflags(write=False)
    return P, jrow, jcol, n_x
