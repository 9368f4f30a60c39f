"""Linearized n-division heating-surface model of Sagara et al. 1998, eq. (1)-(8).

All variables are normalized deviations (Table 2). With G = 1/(T s + 1) per
division, T = T_s / n:

    theta_0 = u_1 - theta_A,  theta_A = sum_i f_i theta_i          (eq. 2)
    x_i = G theta_{i-1},  theta_i = x_i + w/n,  y = theta_n          (eq. 1)
    f_i = C(n, i) (1/nu - 1)^i,  0 < nu <= 1                        (eq. 4)

so that theta_n = nu^n F^n u_1 + (1/n) nu (F/G) sum_k F^k w with
F = 1/(nu T_s + 1) (eq. 5). The "delay" of a transfer function P is
D = lim_{s->0} (1 - P/P^0)/s = -P'(0)/P(0) (eq. 6); Table 1 gives
P^0 = nu^n, D = nu n T for theta_n/u_1 and P^0 = nu, D = ((n+1)/2 nu - 1) T
for theta_n/w. This module builds the state space and computes P^0 and D, as
used by the Table 1 validation test and by the FAO baseline's compensator gains.
"""

from __future__ import annotations

from math import comb

import numpy as np


def feedback_gains(n: int, nu: float) -> np.ndarray:
    """State-feedback gains f_1..f_n of eq. (4); n = 3, nu = 1/3 gives 6, 12, 8."""
    if not (0.0 < nu <= 1.0):
        raise ValueError(f"nu must be in (0, 1], got {nu}")
    return np.array([comb(n, i) * (1.0 / nu - 1.0) ** i for i in range(1, n + 1)])


def state_space(n: int, nu: float, T: float = 1.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(A, B, C) of eq. (1)-(2) with states x_1..x_n, inputs (u_1, w), output theta_n."""
    f = feedback_gains(n, nu)
    A = np.zeros((n, n))
    B = np.zeros((n, 2))
    # theta_i = x_i + w/n ;  theta_0 = u_1 - sum_j f_j theta_j
    for i in range(n):
        A[i, i] -= 1.0 / T
        if i == 0:
            A[0, :] -= f / T
            B[0, 0] += 1.0 / T
            B[0, 1] -= f.sum() / n / T
        else:
            A[i, i - 1] += 1.0 / T
            B[i, 1] += 1.0 / n / T
    C = np.zeros((1, n))
    C[0, n - 1] = 1.0
    return A, B, C


def gain_and_delay(n: int, nu: float, T: float = 1.0) -> dict[str, tuple[float, float]]:
    """(P^0, D) of theta_n/u_1 and theta_n/w by eq. (6), from the state space.

    For P(s) = C (sI - A)^-1 B + D_ff: P(0) = -C A^-1 B + D_ff, P'(0) = -C A^-2 B.
    """
    A, B, C = state_space(n, nu, T)
    Ainv = np.linalg.inv(A)
    out = {}
    for name, j, dff in (("u1", 0, 0.0), ("w", 1, 1.0 / n)):
        p0 = float(-(C @ Ainv @ B[:, j])[0] + dff)
        dp0 = float(-(C @ Ainv @ Ainv @ B[:, j])[0])
        out[name] = (p0, -dp0 / p0)
    return out


def table1(n: int, nu: float, T: float = 1.0) -> dict[str, tuple[float, float]]:
    """The closed forms of Table 1 of Sagara et al. 1998: (P^0, D) for theta_n/u_1 and theta_n/w."""
    return {"u1": (nu**n, nu * n * T), "w": (nu, ((n + 1) / 2.0 * nu - 1.0) * T)}
