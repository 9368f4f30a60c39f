"""Packing and calibration of the boiler-turbine unit: BoilerTurbineParams -> the flat
vector P and the Jacobian pattern, with the gas sides, the platen's radiant heat, the
valves and the load schedules sized so that the rated balance holds."""

from __future__ import annotations

import functools
import math

import numpy as np

from steamtemp_gym._jit import read_only
from steamtemp_gym.plants.base import D_LOAD, K0, nominal_disturbances
from steamtemp_gym.plants.boiler_turbine_mimo.kernel import (
    h_crh_target,
    offsets,
    pressure,
    reheat_pressure,
    table,
    tube_kA,
)
from steamtemp_gym.plants.boiler_turbine_mimo.layout import (
    COPIED,
    IP,
    ITAB,
    IX,
    N_P,
    N_TAB,
    TAB_LOADS,
    patterns,
)
from steamtemp_gym.plants.boiler_turbine_mimo.params import BoilerTurbineParams
from steamtemp_gym.plants.boiler_turbine_mimo.steady_state import bisect_rgd, sh_steady
from steamtemp_gym.plants.copies import write_copies
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
    T_ms = params.T_ms_C + K0
    _water_and_reheat_tables(params, P, Pk)
    h_up = _rated_design(params, P, Pk, x)
    d = nominal_disturbances(1.0)[0]
    # evaporator-outlet schedule: design sprays hold T_ms where RGD holds T_rh
    for k, L in enumerate(TAB_LOADS):
        d[D_LOAD] = L
        x[IX.LF] = x[IX.LW] = L
        x[IX.FB] = 0.5
        x[IX.CRH] = h_crh_target(Pk, T_ms, L)
        x[IX.G] = bisect_rgd(x, d, Pk, P[IP.TRH])
        p, _ = pressure(Pk, L)

        def ste(h, L=L, p=p):
            x[IX.HUP] = h
            return T_ph(p, sh_steady(x, P[IP.VD], d, Pk)) - T_ms

        h = _secant(ste, h_up, h_up + 50e3, f"the evaporator-outlet schedule at load {L:.2f}")
        P[IP.TAB + ITAB.HUP * N_TAB + k] = h
        P[IP.TAB + ITAB.RISE * N_TAB + k] = h - table(Pk, ITAB.HSP, L)


def _water_and_reheat_tables(params: BoilerTurbineParams, P: np.ndarray, Pk: np.ndarray) -> None:
    """Spray-water and cold-reheat tables over TAB_LOADS."""
    T_ms = params.T_ms_C + K0
    kappa = math.log((params.T_crh_nom_C + K0) / T_ms) / math.log(
        params.p_rh_nom_MPa / params.p_nom_MPa
    )
    for k, L in enumerate(TAB_LOADS):
        p, _ = pressure(Pk, L)
        p_sp = p + P[IP.DPB] * L * L
        T_fw = params.T_fw_nom_C + K0 - params.dT_fw_dload_K * (1.0 - L)
        h = h_pT(p_sp, T_fw)
        P[IP.TAB + ITAB.HSP * N_TAB + k] = h
        P[IP.TAB + ITAB.RHOSP * N_TAB + k] = rho_ph(p_sp, h)
        P[IP.TAB + ITAB.CPSP * N_TAB + k] = cp_pT(p_sp, T_fw)
        prh, _ = reheat_pressure(Pk, L)
        ratio = (prh / p) ** kappa
        P[IP.TAB + ITAB.CRHR * N_TAB + k] = ratio
        P[IP.TAB + ITAB.TCRH * N_TAB + k] = T_ms * ratio
        P[IP.TAB + ITAB.HCRH * N_TAB + k] = h_pT(prh, T_ms * ratio)
        P[IP.TAB + ITAB.CPCRH * N_TAB + k] = cp_pT(prh, T_ms * ratio)


def _rated_design(
    params: BoilerTurbineParams, P: np.ndarray, Pk: np.ndarray, x: np.ndarray
) -> float:
    """Size the spray valves, the platen's radiant heat and the convective UA_g of the
    primary SH, final SH and reheater on the rated design balance; the design evaporator
    outlet enthalpy (J/kg)."""
    o_p, o_pl, o_f, o_r = offsets(Pk)
    n1, n2, n3, n4 = (int(P[i]) for i in (IP.N1, IP.N2, IP.N3, IP.N4))
    W = params.W_nom_kg_s
    T_ms = params.T_ms_C + K0
    p_nom = params.p_nom_MPa * 1e6
    # spray valves: the design opening passes the design fraction at rated load
    h_sp = table(Pk, ITAB.HSP, 1.0)
    s = math.sqrt(table(Pk, ITAB.RHOSP, 1.0) * P[IP.DPB])
    P[IP.CV1] = params.sp1_design_fraction * W / (params.valve_design_opening * s)
    P[IP.CV2] = params.sp2_design_fraction * W / (params.valve_design_opening * s)
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
    P[IP.Q_PL] = Wpl * (h_plo - h_pli)

    def stage(i_uag, off, n, h_in, w, p, kA, tg, h_out, what):
        def out(uag):
            return chain_steady(x, off, n, h_in, w, p, kA / n, uag / n, tg, 0.0) - h_out

        T_out = T_ph(p, h_out)
        a = w * (h_out - h_in) / max(tg - T_out, 10.0)
        P[i_uag] = _secant(out, a, 1.3 * a, what)

    stage(
        IP.UAG_F,
        o_f,
        n3,
        h_fi,
        W,
        p_nom,
        tube_kA(P[IP.KAF_F], P[IP.KAW_F], W, W)[0],
        P[IP.TG_F],
        h_ms,
        "the final SH gas side",
    )
    stage(
        IP.UAG_P,
        o_p,
        n1,
        h_up,
        Wp,
        p_nom,
        tube_kA(P[IP.KAF_P], P[IP.KAW_P], Wp, W)[0],
        P[IP.TG_P],
        h_po,
        "the primary SH gas side",
    )
    Wr = P[IP.FRH] * W
    prh, _ = reheat_pressure(Pk, 1.0)
    kA_r = tube_kA(P[IP.KAF_R], P[IP.KAW_R], Wr, Wr)[0]
    stage(
        IP.UAG_R,
        o_r,
        n4,
        table(Pk, ITAB.HCRH, 1.0),
        Wr,
        prh,
        kA_r,
        P[IP.TG_R],
        h_pT(prh, P[IP.TRH]),
        "the reheater gas side",
    )
    return h_up


def _conductances(
    n_tubes: int, length: float, d_i: float, d_o: float, alpha: float, k: float, rho_c: float
) -> tuple[float, float, float, float]:
    """(kA_film at rated flow, kA_wall of eq. (4), steam volume, metal heat capacity) of a bank."""
    a_in = math.pi * d_i * length * n_tubes
    wall = a_in * 4.0 * k / (d_o - d_i)  # A / ((r_o - r_i) / (2 k))
    vol = math.pi / 4.0 * d_i**2 * length * n_tubes
    cm = math.pi / 4.0 * (d_o**2 - d_i**2) * length * n_tubes * rho_c
    return alpha * a_in, wall, vol, cm


@functools.lru_cache(maxsize=32)
def pack_params(params: BoilerTurbineParams) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    q = params
    P = np.zeros(N_P)
    write_copies(P, IP, COPIED, params)
    rc = q.rho_metal_kg_m3 * q.c_metal_J_kgK
    P[IP.KAF_P], P[IP.KAW_P], P[IP.V_P], P[IP.CM_P] = _conductances(
        q.primary_n_tubes,
        q.primary_length_m,
        q.primary_id_m,
        q.primary_od_m,
        q.alpha_sh_W_m2K,
        q.k_wall_W_mK,
        rc,
    )
    P[IP.KAF_F], P[IP.KAW_F], P[IP.V_F], P[IP.CM_F] = _conductances(
        q.final_n_tubes,
        q.final_length_m,
        q.final_id_m,
        q.final_od_m,
        q.alpha_sh_W_m2K,
        q.k_wall_W_mK,
        rc,
    )
    P[IP.KAF_R], P[IP.KAW_R], P[IP.V_R], P[IP.CM_R] = _conductances(
        q.reheat_n_tubes,
        q.reheat_length_m,
        q.reheat_id_m,
        q.reheat_od_m,
        q.alpha_rh_W_m2K,
        q.k_wall_W_mK,
        rc,
    )
    P[IP.RNOM] = q.recirc_max_fraction * q.rgd_design_opening
    n1, n2, n3, n4 = q.n_seg_primary, q.n_seg_platen, q.n_seg_final, q.n_seg_reheat
    P[IP.JOFF_PL] = 4 * n1
    P[IP.JOFF_F] = P[IP.JOFF_PL] + 4 * n2 + 2
    P[IP.JOFF_R] = P[IP.JOFF_F] + 4 * n3 + 1
    cm = q.c_metal_J_kgK * 1e3
    P[IP.LCM], P[IP.LV] = q.line_metal_t * cm / q.n_line, q.line_volume_m3 / q.n_line
    P[IP.RLCM], P[IP.RLV] = q.rh_line_metal_t * cm / q.n_rh_line, q.rh_line_volume_m3 / q.n_rh_line
    P[IP.JOFF_L] = P[IP.JOFF_R] + 4 * n4
    P[IP.JOFF_RL] = P[IP.JOFF_L] + 2 * q.n_line
    n_x = IX.CHAIN + 2 * (n1 + n2 + n3 + n4) + q.n_line + q.n_rh_line
    _calibrate(params, P, n_x)
    pat = patterns(params)
    assert len(pat) == P[IP.JOFF_RL] + 2 * q.n_rh_line
    jrow, jcol = pattern_arrays(pat)
    P.setflags(write=False)
    return P, jrow, jcol, n_x
