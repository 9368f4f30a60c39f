"""Linear models of the plants for the model-based baselines (lqi, mpc_linear).

``Plant.linearize`` / ``Plant.linearize_disturbances`` give the discrete model of a plant's
compiled step at an operating point; this module holds what the model-based baselines do
with them: the states the inputs reach, interpolation of tables over load, the steady
operating points, and balanced truncation on a basis shared by several local models (so
that the reduced models of different loads live in the same coordinates and can be
interpolated entry by entry).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.linalg import solve_discrete_are, solve_discrete_lyapunov

from steamtemp_gym.plants.base import nominal_disturbances


def reachable(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Boolean mask of the states some input reaches through nonzero entries of A and B."""
    reach = np.any(B != 0.0, axis=1)
    G = A != 0.0
    while True:
        new = reach | np.any(G[:, reach], axis=1)
        if (new == reach).all():
            return reach
        reach = new


def interp_rows(L: np.ndarray, xp: np.ndarray, table: np.ndarray) -> np.ndarray:
    """Linear interpolation of the rows of ``table`` (len(xp), ...) at each L (held outside)."""
    L = np.asarray(L, dtype=np.float64)
    idx = np.clip(np.searchsorted(xp, L) - 1, 0, len(xp) - 2)
    a = np.clip((L - xp[idx]) / (xp[idx + 1] - xp[idx]), 0.0, 1.0)
    a = a.reshape(a.shape + (1,) * (table.ndim - 1))
    return (1.0 - a) * table[idx] + a * table[idx + 1]


def steady_point(plant: Any, load: float, outputs: list[str]) -> tuple[np.ndarray, ...]:
    """(x, u, y) of the undisturbed steady state at ``load`` (the point ``linearize`` uses):
    state, valve openings and the named outputs."""
    x, z = plant.steady_outputs(nominal_disturbances(load)[0])
    return x, z[[plant.index[v] for v in plant.valves]], z[[plant.index[o] for o in outputs]]


def _psd_factor(W: np.ndarray) -> np.ndarray:
    """L with L L' = W for a symmetric positive semi-definite W (negative rounding cut)."""
    lam, Q = np.linalg.eigh(0.5 * (W + W.T))
    return Q * np.sqrt(np.maximum(lam, 0.0))


def balanced_basis(
    models: list[tuple[np.ndarray, np.ndarray, np.ndarray]], tol: float, max_order: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Square-root balanced truncation on the summed Gramians of several stable models.

    Args:
        models: (A, Bw, Cw) per operating point: state matrix, input and output matrices
            already weighted (inputs by their typical sizes, outputs by their scales).
        tol: Keep the states whose Hankel singular value is at least ``tol`` times the
            largest.
        max_order: Keep at most this many.

    Returns:
        (T, Ti, hsv): x ~ T xi, xi = Ti x (Ti T = I) and the Hankel singular values of the
        summed Gramians (all of them).
    """
    Wc = sum(solve_discrete_lyapunov(A, Bw @ Bw.T) for A, Bw, _ in models)
    Wo = sum(solve_discrete_lyapunov(A.T, Cw.T @ Cw) for A, _, Cw in models)
    Lc, Lo = _psd_factor(Wc), _psd_factor(Wo)
    U, s, Vt = np.linalg.svd(Lo.T @ Lc)
    r = int(min(max_order, np.count_nonzero(s >= tol * s[0])))
    root = np.sqrt(s[:r])
    return Lc @ Vt[:r].T / root, (U[:, :r] / root).T @ Lo.T, s


def kalman_gain(A: np.ndarray, C: np.ndarray, W: np.ndarray, V: np.ndarray) -> np.ndarray:
    """Steady-state Kalman gain M of the filtered form x_k|k = x_k|k-1 + M (y_k - C x_k|k-1)
    for x_k+1 = A x_k + w, y_k = C x_k + v (covariances W, V), from the DARE of (A', C')."""
    S = solve_discrete_are(A.T, C.T, W, V)
    return S @ C.T @ np.linalg.inv(C @ S @ C.T + V)
