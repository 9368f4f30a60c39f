"""Packing and calibration of the Benson boiler: BensonParams -> the flat vector P
(states and Jacobian pattern laid out, then the gas sides, radiant heats, valves, fuel
and load schedules sized so that the rated steady state hits the design temperatures)."""

from __future__ import annotations

import functools
import math

import numpy as np

from steamtemp_gym._jit import read_only
from steamtemp_gym.plants.attemperator import mix
from steamtemp_gym.plants.base import K0, nominal_disturbances
from steamtemp_gym.plants.benson_subcritical.kernel import boundary, p_setpoint, reheat, table
from steamtemp_gym.plants.benson_subcritical.layout import (
    COPIED,
    IF,
    IP,
    ITB,
    IX,
    N_P,
    N_SENS,
    N_TAB,
    NF,
    PRESSURE_JAC,
    TAB_LOADS,
)
from steamtemp_gym.plants.benson_subcritical.params import P_SHARE, SEC, SECTIONS, BensonParams
from steamtemp_gym.plants.benson_subcritical.steady_state import (
    section_steady,
    sh_steady,
    upstream_steady,
)
from steamtemp_gym.plants.copies import write_copies
from steamtemp_gym.plants.integrator import pattern_arrays
from steamtemp_gym.plants.roots import secant
from steamtemp_gym.plants.superheater import chain_pattern, pipe_cells, pipe_pattern
from steamtemp_gym.steam import T_ph, cp_pT, h_pT, rho_ph


def _secant(fun, a: float, b: float, what: str, tol: float = 1e-4) -> float:
    b, fb = secant(fun, a, b, tol, floor=1e-3)
    if abs(fb) < 1e3 * tol:
        return b
    raise ValueError(
        f"BensonParams: cannot calibrate {what} (residual {fb:.4g}); "
        "check the design temperatures and gas temperatures"
    )


def _calibrate(pr: BensonParams, P: np.ndarray) -> None:
    """Size gas sides, radiant heats, valves, fuel and the load schedules (P in place)."""
    n_x = int(P[IP.NX])
    x = np.zeros(n_x)
    Pk = read_only(P)  # what the kernels read (see steamtemp_gym._jit.read_only)
    _feedwater_tables(pr, P, Pk)
    h_ev = _rated_design(pr, P, Pk, x)
    _storage(pr, P, x)
    _load_schedules(pr, P, Pk, n_x)
    if abs(table(Pk, ITB.HEV, 1.0) - h_ev) > 1.0:  # the schedule must pass the design point
        raise ValueError("BensonParams: inconsistent calibration at rated load")


def _feedwater_tables(pr: BensonParams, P: np.ndarray, Pk: np.ndarray) -> None:
    """Feedwater and spray-water tables over load (sliding pressure at design sprays)."""
    for i, L in enumerate(TAB_LOADS):
        p = p_setpoint(Pk, L)
        T_da = pr.T_deaerator_C - pr.dT_deaerator_dload_K * (1.0 - L) + K0
        T_fw = T_da + pr.dT_hp_heaters_K - pr.dT_hp_dload_K * (1.0 - L)
        p_eco = p + P_SHARE[SEC.ECO] * P[IP.DPB] * L * L
        p_pump = p + P[IP.DPPUMP] * L * L
        h_sp = h_pT(p_pump, T_da)
        vals = (
            h_pT(p_eco, T_fw),
            cp_pT(p_eco, T_fw),
            h_sp,
            cp_pT(p_pump, T_da),
            rho_ph(p_pump, h_sp),
        )
        for tb, v in zip((ITB.HFW, ITB.CPFW, ITB.HSP, ITB.CPSP, ITB.RHOSP), vals, strict=True):
            P[IP.TAB + tb * N_TAB + i] = v


def _rated_design(pr: BensonParams, P: np.ndarray, Pk: np.ndarray, x: np.ndarray) -> float:
    """Size every section's gas side or radiant heat, the spray valves and the rated fuel
    flow on the rated design balance (the steady sections written into x); the rated
    evaporator outlet enthalpy (J/kg)."""
    d = nominal_disturbances(1.0)[0]
    p = P[IP.PNOM]
    dpb = P[IP.DPB]
    W_nom = P[IP.WNOM]
    W_eco = P[IP.WECO]
    sec = IP.SEC

    def setf(k: int, f: int, v: float) -> None:
        P[sec + NF * k + f] = v

    def conv(k: int, h0: float, W: float, pk: float, T_out: float) -> float:
        target = h_pT(pk, T_out + K0)
        n = int(P[sec + NF * k + IF.N])
        q0 = W * (target - h0) / n

        def resid(uag: float) -> float:
            setf(k, IF.UAG, uag)
            return (section_steady(x, Pk, k, h0, W, pk, 1.0, d) - target) * 1e-3

        Tg = P[sec + NF * k + IF.TGN]
        T_mean = 0.5 * (T_out + K0 + T_ph(pk, h0))
        guess = q0 / max(Tg - T_mean, 50.0)
        setf(k, IF.UAG, _secant(resid, guess, 1.2 * guess, f"the {SECTIONS[k]} gas side"))
        return target

    def rad(k: int, h0: float, W: float, pk: float, T_out: float) -> float:
        target = h_pT(pk, T_out + K0)
        if target <= h0:
            raise ValueError(f"BensonParams: the {SECTIONS[k]} design outlet is below its inlet")
        setf(k, IF.QRAD, W * (target - h0) / int(P[sec + NF * k + IF.N]))
        return section_steady(x, Pk, k, h0, W, pk, 1.0, d)

    h_fw = table(Pk, ITB.HFW, 1.0)
    h = conv(SEC.ECO, h_fw, W_eco, p + P_SHARE[SEC.ECO] * dpb, pr.T_eco_out_C)
    h = rad(SEC.EV, h, W_eco, p + P_SHARE[SEC.EV] * dpb, pr.T_evap_out_C)
    h_ev = h
    h = conv(SEC.SH1, h, W_eco, p + P_SHARE[SEC.SH1] * dpb, pr.T_sh1_out_C)
    h = rad(SEC.SH2, h, W_eco, p + P_SHARE[SEC.SH2] * dpb, pr.T_sh2_out_C)
    # spray valves: fully open passes spray*_max_fraction of W_nom at rated load
    rho_sp = table(Pk, ITB.RHOSP, 1.0)
    h_sp = table(Pk, ITB.HSP, 1.0)
    for i_cv, share, smax in (
        (IP.CV1, P_SHARE[SEC.SH2], pr.spray1_max_fraction),
        (IP.CV2, P_SHARE[SEC.SH3], pr.spray2_max_fraction),
    ):
        P[i_cv] = smax * W_nom / math.sqrt(rho_sp * (P[IP.DPPUMP] - share * dpb))
    P[IP.V1D] = pr.spray1_design_fraction / pr.spray1_max_fraction
    P[IP.V2D] = pr.spray2_design_fraction / pr.spray2_max_fraction
    w1 = pr.spray1_design_fraction * W_nom
    w2 = pr.spray2_design_fraction * W_nom
    W3, h = mix(W_eco, h, w1, h_sp)
    h = conv(SEC.SH3, h, W3, p + P_SHARE[SEC.SH3] * dpb, pr.T_sh3_out_C)
    W4, h = mix(W3, h, w2, h_sp)
    h_ms = conv(SEC.SH4, h, W4, p, pr.T_ms_C)
    W_t, W_rh, p_rh, p_crh, _ = reheat(Pk, p, 1.0)
    T_crh = (pr.T_ms_C + K0) * (p_crh / p) ** P[IP.KE]
    h_crh = h_pT(p_crh, T_crh)
    h_rh = conv(SEC.RH, h_crh, W_rh, p_rh, pr.T_rh_C)
    P[IP.CPRAT] = cp_pT(p_crh, T_crh) / cp_pT(p, pr.T_ms_C + K0)
    absorbed = W_nom * h_ms - W_eco * h_fw - (w1 + w2) * h_sp + W_rh * (h_rh - h_crh)
    P[IP.FNOM] = absorbed / (pr.boiler_efficiency * pr.fuel_cv_MJ_kg * 1e6)
    return h_ev


def _storage(pr: BensonParams, P: np.ndarray, x: np.ndarray) -> None:
    """The pressure's storage constant from the steam mass in SH1-SH4 at rated load (x: the
    rated steady sections)."""
    p = P[IP.PNOM]
    dpb = P[IP.DPB]
    sec = IP.SEC
    # eq. (13): m_v = steam mass in SH1-SH4 at rated load
    m_v = 0.0
    for k in (SEC.SH1, SEC.SH2, SEC.SH3, SEC.SH4):
        off, n = int(P[sec + NF * k + IF.OFF]), int(P[sec + NF * k + IF.N])
        pk = p + P_SHARE[k] * dpb
        m_v += sum(rho_ph(pk, x[off + 2 * i + 1]) * P[sec + NF * k + IF.V] for i in range(n))
    P[IP.CSTOR] = P[IP.PNOM] / (pr.storage_tau * m_v)


def _load_schedules(pr: BensonParams, P: np.ndarray, Pk: np.ndarray, n_x: int) -> None:
    """Load schedules: firing, evaporator outlet and SH3 outlet enthalpies at design sprays,
    and the cold-reheat enthalpy."""
    W_nom = P[IP.WNOM]
    xs = np.zeros(n_x)
    for i, L in enumerate(TAB_LOADS):
        dL = nominal_disturbances(L)[0]
        xs[IX.V1], xs[IX.V2] = P[IP.V1D], P[IP.V2D]
        _, _, W_e, w1, w2, *_ = boundary(xs, dL, Pk)
        pL = p_setpoint(Pk, L) * (W_e + w1 + w2) / (W_nom * L)
        xs[IX.P] = pL
        target = h_pT(pL, pr.T_ms_C + K0)

        def resid(lf: float, dL=dL, pL=pL, target=target) -> float:
            upstream_steady(xs, dL, Pk, lf, pL)
            return (sh_steady(xs, dL, Pk, lf, pL, 4) - target) * 1e-3

        lf = _secant(resid, L, 1.02 * L, f"the firing schedule at {L:.2f} load")
        P[IP.TAB + ITB.FUEL * N_TAB + i] = lf
        P[IP.TAB + ITB.HEV * N_TAB + i] = upstream_steady(xs, dL, Pk, lf, pL)
        P[IP.TAB + ITB.H3 * N_TAB + i] = sh_steady(xs, dL, Pk, lf, pL, 3)
        _, _, _, p_crh, _ = reheat(Pk, pL, L)
        T_crh = (pr.T_ms_C + K0) * (p_crh / pL) ** P[IP.KE]
        P[IP.TAB + ITB.HCRH * N_TAB + i] = h_pT(p_crh, T_crh)


@functools.lru_cache(maxsize=32)
def pack_params(pr: BensonParams) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    P = np.zeros(N_P)
    _pack_scalars(pr, P)
    pat, off = _pack_sections(pr, P)
    # thermowells: T1 from the measured enthalpy, T2 from T1; then the trim from h_evap
    P[IP.S0] = off
    P[IP.JSEN] = len(pat)
    blk = [IP.SEC + NF * k for k in range(7)]
    last_h = [int(P[b + IF.OFF] + 2 * P[b + IF.N] - 1) for b in blk]
    last_h[SEC.SH4] = int(P[IP.LOFF] + pr.n_line - 1)  # the main-steam thermocouple: turbine inlet
    for j, k in enumerate((SEC.EV, SEC.SH1, SEC.SH2, SEC.SH2, SEC.SH3, SEC.SH3, SEC.SH4, SEC.RH)):
        pat += [(off + 2 * j, last_h[k]), (off + 2 * j + 1, off + 2 * j)]
    off += 2 * N_SENS
    P[IP.STRIM] = off
    pat.append((off, last_h[SEC.EV]))
    n_x = off + 1
    P[IP.NX] = n_x
    _calibrate(pr, P)
    jrow, jcol = pattern_arrays(pat)
    P.setflags(write=False)
    return P, jrow, jcol, n_x


def _pack_scalars(pr: BensonParams, P: np.ndarray) -> None:
    """The scalar parameters of P: the copied fields (layout.COPIED) and the economizer and
    reheat flows, pump head and expansion exponent derived from them."""
    write_copies(P, IP, COPIED, pr)
    W_nom = pr.W_nom_kg_s
    s_des = pr.spray1_design_fraction + pr.spray2_design_fraction
    P[IP.WECO] = W_nom * (1.0 - s_des)
    P[IP.DPPUMP] = (pr.p_pump_MPa - pr.p_nom_MPa) * 1e6
    P[IP.WRHN] = pr.rh_flow_fraction * W_nom
    P[IP.KE] = (pr.k_expansion - 1.0) / pr.k_expansion


def _pack_sections(pr: BensonParams, P: np.ndarray) -> tuple[list[tuple[int, int]], int]:
    """Each section's block of P and its states (economizer .. SH4, the main-steam line,
    the reheater): the Jacobian pattern so far and the next free state index."""
    W_nom = pr.W_nom_kg_s
    W_rated = (
        P[IP.WECO],
        P[IP.WECO],
        P[IP.WECO],
        P[IP.WECO],
        W_nom * (1.0 - pr.spray2_design_fraction),
        W_nom,
        P[IP.WRHN],
    )
    Tg = {
        SEC.ECO: pr.Tg_eco_C,
        SEC.SH1: pr.Tg_sh1_C,
        SEC.SH3: pr.Tg_sh3_C,
        SEC.SH4: pr.Tg_sh4_C,
        SEC.RH: pr.Tg_rh_C,
    }
    off = IX.CHAINS
    pat: list[tuple[int, int]] = []
    prev_h = -1
    for k, name in enumerate(SECTIONS):
        if k == SEC.RH:  # outlet header and main-steam line, between SH4 and the reheater
            P[IP.LOFF], P[IP.JLINE] = off, len(pat)
            P[IP.LV], P[IP.LCM] = pipe_cells(
                pr.n_line, pr.line_volume_m3, pr.line_metal_t, pr.c_metal_J_kgK
            )
            pat += pipe_pattern(off, pr.n_line, (prev_h,))
            prev_h = off + pr.n_line - 1
            off += pr.n_line
        n = getattr(pr, f"n_{name}")
        b = IP.SEC + NF * k
        P[b + IF.N] = n
        P[b + IF.OFF] = off
        P[b + IF.JOFF] = len(pat)
        P[b + IF.KA] = getattr(pr, f"kA_{name}_MW_K") * 1e6 / n
        P[b + IF.V] = getattr(pr, f"volume_{name}_m3") / n
        P[b + IF.CM] = getattr(pr, f"metal_{name}_t") * 1e3 * pr.c_metal_J_kgK / n
        P[b + IF.TGN] = Tg[k] + K0 if k in Tg else 0.0
        P[b + IF.WN] = W_rated[k]
        inlet: tuple[int, ...] = ()
        if k != SEC.ECO:
            inlet = (prev_h,)
        pat += chain_pattern(off, n, inlet, IX.P if PRESSURE_JAC else -1)
        prev_h = off + 2 * n - 1
        off += 2 * n
    return pat, off
