"""Packing FSHParams into P and sizing the plant against Sagara et al. 1998's rated
balance: the gas side and the fuel/water-ratio schedule over load."""

from __future__ import annotations

import functools
import math

import numpy as np

from steamtemp_gym._jit import read_only
from steamtemp_gym.plants.base import K0
from steamtemp_gym.plants.copies import write_copies
from steamtemp_gym.plants.integrator import pattern_arrays
from steamtemp_gym.plants.roots import secant
from steamtemp_gym.plants.supercritical_fsh.kernel import (
    pressure,
)
from steamtemp_gym.plants.supercritical_fsh.layout import (
    COPIED,
    INLET_COLS,
    IP,
    IX,
    N_P,
    TAB_LOADS,
)
from steamtemp_gym.plants.supercritical_fsh.params import FSHParams
from steamtemp_gym.plants.superheater import (
    chain_pattern,
    chain_steady,
    pipe_cells,
    pipe_pattern,
    steam_side_kA,
)
from steamtemp_gym.steam import h_pT, rho_ph


def _spray_water_exact(P: np.ndarray, lw: float, dT: float) -> tuple[float, float, float]:
    """Spray water (h J/kg, rho kg/m3, valve dp Pa) from IF97 at steam-flow fraction lw."""
    p = pressure(P, lw)
    dp = P[IP.DPB] * lw * lw
    T_fw = P[IP.TFW] - P[IP.DTFW] * (1.0 - lw) + dT
    h = h_pT(p + dp, T_fw)
    return h, rho_ph(p + dp, h), dp


def _design_inlet(P: np.ndarray, lw: float, h_target: float, x: np.ndarray) -> float:
    """Inlet enthalpy h_e such that the steady chain at load lw gives outlet h_target."""
    n = int(P[IP.N])
    W = lw * P[IP.WNOM]
    p = pressure(P, lw)
    kA = steam_side_kA(P[IP.KA], W, P[IP.WNOM])[0]
    UAg = P[IP.UAG] * lw ** P[IP.GEXP]
    Tg = P[IP.TGN] - P[IP.DTG] * (1.0 - lw)

    def resid(h_e: float) -> float:
        return chain_steady(x, IX.CHAIN, n, h_e, W, p, kA, UAg, Tg, 0.0) - h_target

    return secant(resid, h_target - 300e3, h_target - 100e3, 1e-4)[0]


def _calibrate(params: FSHParams, P: np.ndarray, n_x: int) -> None:
    """Size the gas side and the fuel/water-ratio schedule (writes P in place).

    UA_g is set so that, at rated load with inlet enthalpy h_a0 - 217.8 kJ/kg, the
    steady FSH delivers h_a0 = h(p_nom, T_out) (Sagara et al. 1998's rated balance). The
    schedule h_up(L) is what the fuel/water-ratio control must deliver for the
    design spray fraction to hold T_out at every load.
    """
    x = np.zeros(n_x)
    Pk = read_only(P)  # what the kernels read (see steamtemp_gym._jit.read_only)
    p_nom = params.p_nom_MPa * 1e6
    h_a0 = h_pT(p_nom, params.T_out_C + K0)
    h_e0 = h_a0 - params.dh_fsh_nom_kJ_kg * 1e3
    n = params.n_segments
    W = params.W_nom_kg_s
    kA = P[IP.KA]

    # secant on UAg for the rated balance
    def out(uag: float) -> float:
        return chain_steady(x, IX.CHAIN, n, h_e0, W, p_nom, kA, uag, P[IP.TGN], 0.0) - h_a0

    q0 = W * (h_a0 - h_e0) / n
    P[IP.UAG] = secant(out, q0 / 400.0, q0 / 300.0, 1e-4)[0]
    s = params.spray_design_fraction
    for k, L in enumerate(TAB_LOADS):
        h_sp, rho_sp, _ = _spray_water_exact(Pk, L, 0.0)
        h_p, _, _ = _spray_water_exact(Pk, L, 1.0)
        h_m, _, _ = _spray_water_exact(Pk, L, -1.0)
        P[IP.HFW + k], P[IP.RHOFW + k] = h_sp, rho_sp
        P[IP.CPFW + k] = 0.5 * (h_p - h_m)
        P[IP.DCPFW + k] = h_p - 2.0 * h_sp + h_m
        p = pressure(Pk, L)
        h_out = h_pT(p, params.T_out_C + K0)
        h_e = _design_inlet(Pk, L, h_out, x)
        P[IP.HUP + k] = (h_e - s * h_sp) / (1.0 - s)
        P[IP.DHUP + k] = P[IP.HUP + k] - h_sp
    # Valve coefficient: fully open passes spray_max_fraction of rated flow at rated load.
    h_sp, rho_sp, dp = _spray_water_exact(Pk, 1.0, 0.0)
    P[IP.CV] = params.spray_max_fraction * W / math.sqrt(rho_sp * dp)


@functools.lru_cache(maxsize=32)
def pack_params(params: FSHParams) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    n = params.n_segments
    area_flow = math.pi / 4.0 * params.tube_id_m**2
    area_metal = math.pi / 4.0 * (params.tube_od_m**2 - params.tube_id_m**2)
    seg_len = params.tube_length_m / n
    P = np.zeros(N_P)
    write_copies(P, IP, COPIED, params)
    P[IP.KA] = params.alpha_nom_W_m2K * math.pi * params.tube_id_m * seg_len * params.n_tubes
    P[IP.V] = area_flow * seg_len * params.n_tubes
    P[IP.CM] = area_metal * seg_len * params.n_tubes * params.rho_metal_kg_m3 * params.c_metal_J_kgK
    P[IP.LV], P[IP.LCM] = pipe_cells(
        params.n_line, params.line_volume_m3, params.line_metal_t, params.c_metal_J_kgK
    )
    n_x = IX.CHAIN + 2 * n + 1 + params.n_line
    _calibrate(params, P, n_x)
    pat = chain_pattern(IX.CHAIN, n, INLET_COLS, IX.LW)
    assert len(pat) == 4 * n + 1  # rhs writes the line's entries from here on
    sl = IX.CHAIN + 2 * n + 1
    pat += pipe_pattern(sl, params.n_line, (IX.CHAIN + 2 * n - 1,))
    jrow, jcol = pattern_arrays(pat)
    P.setflags(write=False)
    return P, jrow, jcol, n_x
