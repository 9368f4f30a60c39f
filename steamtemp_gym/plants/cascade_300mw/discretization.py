"""The sections' exact zero-order-hold models over load, packed into P with the plant's
header (Zhang et al. 2012's transfer functions as lag chains)."""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy.linalg import expm

from steamtemp_gym.plants.base import K0
from steamtemp_gym.plants.cascade_300mw.layout import COPIED, IP, IX, N_GRID
from steamtemp_gym.plants.cascade_300mw.params import (
    LOAD_MAX,
    LOAD_MIN,
    CascadeParams,
)
from steamtemp_gym.plants.copies import write_copies
from steamtemp_gym.steam import cp_pT, h_pT


def continuous_model(params: CascadeParams, load: float) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) of the continuous lag chain at a load; B columns: inner input u_in, outer q."""
    K2, T2, K1, T1 = params.section_model(load)
    n1, n2 = params.lead_order, params.inertia_order
    n = n1 + n2
    A = np.zeros((n, n))
    B = np.zeros((n, 2))
    for i in range(n):
        T = T2 if i < n1 else T1
        A[i, i] = -1.0 / T
        if i > 0:
            A[i, i - 1] = (K1 if i == n1 else 1.0) / T
    B[0, 0] = K2 / T2
    B[n1, 1] = K1 / T1
    return A, B


def zoh(A: np.ndarray, B: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact zero-order-hold discretization (Ad, Bd) by the augmented matrix exponential."""
    n, m = B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n] = A * dt
    M[:n, n:] = B * dt
    E = expm(M)
    return E[:n, :n], E[:n, n:]


def block(params: CascadeParams, load: float) -> np.ndarray:
    """Packed lower triangle of Ad (row-major), then Bd[:, 0] and Bd[:, 1]."""
    Ad, Bd = zoh(*continuous_model(params, load), params.dt_s)
    n = Ad.shape[0]
    tri = [Ad[i, j] for i in range(n) for j in range(i + 1)]
    return np.concatenate([tri, Bd[:, 0], Bd[:, 1]])


@functools.lru_cache(maxsize=32)
def pack_params(params: CascadeParams) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    n1, n2 = params.lead_order, params.inertia_order
    n = n1 + n2
    nb = n * (n + 1) // 2 + 2 * n
    P = np.zeros(IP.GRID + (N_GRID + 2) * nb)
    write_copies(P, IP, COPIED, params)
    P[IP.CQ] = params.ht_rise_K / params.inertia_gain
    p = params.attemp_pressure_MPa * 1e6
    T_sw = params.spray_water_temp_C + K0
    h_s = h_pT(p, params.T_out_C - params.ht_rise_K + K0)
    P[IP.CSW] = cp_pT(p, T_sw) / (h_s - h_pT(p, T_sw))
    P[IP.TI] = params.T_out_C - params.ht_rise_K
    P[IP.NB] = nb
    tau_om = params.omega_corr_time_s
    P[IP.COM] = math.exp(-params.dt_s / tau_om) if tau_om > 0.0 else 0.0
    if params.load_dependent:
        blocks = [block(params, L) for L in np.linspace(LOAD_MIN, LOAD_MAX, N_GRID)]
    else:  # never read: the exact 100 % block is used at every load
        blocks = [np.zeros(nb)] * N_GRID
    exact = block(params, 1.0)
    P[IP.GRID :] = np.concatenate(blocks + [exact, exact])
    P.setflags(write=False)
    return P, np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), IX.X + n
