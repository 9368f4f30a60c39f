"""The compiled step and steady state of the 300 MW cascade plant: the lag chain of the
packed model at the row's load, the valve and the omega disturbance generators."""

from __future__ import annotations

import math

import numpy as np

from steamtemp_gym._jit import njit
from steamtemp_gym.plants.base import (
    D_FOULING,
    D_HEAT_BIAS,
    D_LOAD,
    D_SPRAY_T,
)
from steamtemp_gym.plants.cascade_300mw.layout import IP, IX, IZ, LOAD_STEP, N_GRID
from steamtemp_gym.plants.cascade_300mw.params import (
    LOAD_MAX,
    LOAD_MIN,
)
from steamtemp_gym.rng import gauss, uniform

SEED_SALT = np.uint64(0xC0FFEE300)  # separates the plant's stream from the sensor noise


@njit(cache=True)
def _draw(x, P):
    """Write omega and omega_2 of step counter x[IX.CNT] into the state.

    omega: the AR(1) Gaussian g (stationary draw at counter 0) through the Gaussian
    copula to U(-a, a); omega_2: white centred exponential (module docstring).
    """
    seed = np.uint64(x[IX.SEED])
    k = np.int64(x[IX.CNT])
    n = gauss(seed, k, 1)  # uniform channels 2, 3
    c = P[IP.COM]
    g = n if k == 0 else c * x[IX.G] + math.sqrt(1.0 - c * c) * n
    x[IX.G] = g
    x[IX.OM] = P[IP.AOM] * math.erf(g / math.sqrt(2.0))  # a (2 Phi(g) - 1)
    x[IX.OM2] = P[IP.BOM2] * (-math.log(uniform(seed, k, 1)) - 1.0)


@njit(cache=True)
def _where(P, load):
    """Offset of the matrix block below ``load`` and the interpolation weight of the next one."""
    nb = int(P[IP.NB])
    if P[IP.LD] == 0.0:
        return IP.GRID + N_GRID * nb, 0.0
    xg = (min(max(load, LOAD_MIN), LOAD_MAX) - LOAD_MIN) / LOAD_STEP
    k = min(int(xg), N_GRID - 2)
    return IP.GRID + k * nb, xg - k


@njit(cache=True)
def _coeffs(P, load, c):
    """Interpolated block (lower triangle of Ad, Bd columns) at ``load`` into c."""
    nb = int(P[IP.NB])
    off, a = _where(P, load)
    for m in range(nb):
        c[m] = P[off + m] + a * (P[off + nb + m] - P[off + m])


@njit(cache=True)
def _spray_demand(P, load):
    """Spray flow (kg/s) that holds the outlet operating point undisturbed at ``load``."""
    L = min(max(load, LOAD_MIN), LOAD_MAX)
    return P[IP.W100] + (P[IP.W100] - P[IP.W50]) * (L - 1.0) / 0.5


@njit(cache=True)
def _inputs(v, d, P, om, om2):
    """Inner input u_in (kg/s) and outer input q (K) for valve v and disturbances d."""
    u_in = v * P[IP.WMAX] * (1.0 - P[IP.CSW] * d[D_SPRAY_T]) - _spray_demand(P, d[D_LOAD]) + om2
    q = P[IP.CQ] * (d[D_FOULING] * (1.0 + d[D_HEAT_BIAS]) - 1.0) + om
    return u_in, q


@njit(cache=True)
def _outputs(x, d, P, z):
    n1 = int(P[IP.N1])
    n = n1 + int(P[IP.N2])
    z[IZ.outlet_temp_C] = P[IP.TOUT] + x[IX.X + n - 1]
    z[IZ.outlet_temp_meas_C] = z[IZ.outlet_temp_C]
    z[IZ.intermediate_temp_C] = P[IP.TI] + x[IX.X + n1 - 1]
    z[IZ.spray_valve] = x[IX.V]
    z[IZ.spray_flow_kg_s] = x[IX.V] * P[IP.WMAX]
    z[IZ.omega_K] = x[IX.OM]
    z[IZ.omega2_kg_s] = x[IX.OM2]
    z[IZ.outer_disturbance_K] = P[IP.CQ] * (d[D_FOULING] * (1.0 + d[D_HEAT_BIAS]) - 1.0) + x[IX.OM]
    z[IZ.design_spray_kg_s] = _spray_demand(P, d[D_LOAD])


@njit(cache=True, nogil=True)  # threads run it on blocks of rows (plants/threads.py)
def step(X, U, D, P, jrow, jcol, dt, n_sub, Z):  # noqa: N803
    """Advance every row by one sampling period (exact ZOH); dt = 0 only fills Z."""
    n = int(P[IP.N1]) + int(P[IP.N2])
    nb = int(P[IP.NB])
    tri = n * (n + 1) // 2
    if dt != 0.0 and abs(dt - P[IP.DT]) > 1e-9 * P[IP.DT]:
        raise ValueError("Cascade300MW: the kernel is discretized for params.dt_s only")
    c = np.empty(nb)
    for b in range(X.shape[0]):
        x = X[b]
        d = D[b]
        if dt != 0.0:
            v = min(max(U[b, 0], 0.0), 1.0)
            x[IX.V] = v
            u_in, q = _inputs(v, d, P, x[IX.OM], x[IX.OM2])
            _coeffs(P, d[D_LOAD], c)
            # lower-triangular update in place, last row first (rows read older states only)
            m = tri
            for i in range(n - 1, -1, -1):
                m -= i + 1
                acc = c[tri + i] * u_in + c[tri + n + i] * q
                for j in range(i + 1):
                    acc += c[m + j] * x[IX.X + j]
                x[IX.X + i] = acc
            x[IX.CNT] += 1.0
            _draw(x, P)
        _outputs(x, d, P, Z[b])


@njit(cache=True)
def _equilibrium(c, n, u_in, q, x, off):
    """Fixed point of x = Ad x + Bd (u_in, q) (forward substitution) into x[off:off+n]."""
    tri = n * (n + 1) // 2
    m = 0
    for i in range(n):
        acc = c[tri + i] * u_in + c[tri + n + i] * q
        for j in range(i):
            acc += c[m + j] * x[off + j]
        x[off + i] = acc / (1.0 - c[m + i])
        m += i + 1


@njit(cache=True)
def steady(D, sp_C, P, X):
    """Equilibrium of each row at its disturbances and its seeded step-0 omega values
    (X[:, IX.SEED] from seed_rows) holding sp_C (valve clipped to [0, 1])."""
    n = int(P[IP.N1]) + int(P[IP.N2])
    c = np.empty(int(P[IP.NB]))
    for b in range(X.shape[0]):
        x = X[b]
        d = D[b]
        x[IX.CNT] = 0.0
        _draw(x, P)
        om, om2 = x[IX.OM], x[IX.OM2]
        _coeffs(P, d[D_LOAD], c)
        _, q = _inputs(0.0, d, P, om, om2)
        _equilibrium(c, n, 1.0, 0.0, x, IX.X)
        g_u = x[IX.X + n - 1]
        _equilibrium(c, n, 0.0, q, x, IX.X)
        u_req = (sp_C[b] - P[IP.TOUT] - x[IX.X + n - 1]) / g_u
        w = (u_req + _spray_demand(P, d[D_LOAD]) - om2) / (1.0 - P[IP.CSW] * d[D_SPRAY_T])
        v = min(max(w / P[IP.WMAX], 0.0), 1.0)
        x[IX.V] = v
        u_in, q = _inputs(v, d, P, om, om2)
        _equilibrium(c, n, u_in, q, x, IX.X)
