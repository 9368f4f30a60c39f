"""The open-loop problem of one episode and its gradient (agents/optimum/__init__.py).

An :class:`Episode` holds what no command changes (the plant's start, the disturbances and
setpoints of every step); :func:`simulate` runs the plant's own compiled kernel over a
command sequence, :func:`returns` scores it with the smoothed reward of
steamtemp_gym/rewards.py, and :func:`value_and_gradient` gives the gradient of the
return over every command by the adjoint recursion through the trajectory's Jacobians,
which :func:`jacobians` takes by finite differences, every perturbation of every step a
row of one batched kernel call. :func:`exact_return` is the env's own return of a
sequence of actions, stepped by the env core.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from steamtemp_gym._jit import njit
from steamtemp_gym.envs.core import Core
from steamtemp_gym.envs.kernels import CFG, N_CFG, H
from steamtemp_gym.envs.snapshot import copy_rows, planning_core
from steamtemp_gym.rewards import N_WEIGHTS, W

#: Smoothing widths at scale 1: temperature error (K), valve opening, spray (the reward's
#: spray units); :func:`smoothing` scales them.
SMOOTHING = (0.5, 0.005, 0.005)
#: Relative step of the state's finite differences (times max(|x|, 1)) and the
#: commands' step (opening).
REL_STEP = 1e-6
DU = 1e-6


def smooth_reward(Z, U, U_prev, sp, layout, eps):
    """The env's reward (steamtemp_gym/rewards.py) of many transitions without the trip
    penalty, its kinks smoothed, and its derivatives: the optimizer's model of the reward.

    |x| becomes sqrt(x^2 + s^2) - s and max(0, x) becomes (x + sqrt(x^2 + s^2)) / 2, with
    the widths ``eps`` = (temperature error in K, valve opening, spray in the reward's spray
    units); ``eps`` = (0, 0, 0) gives the terms of ``steamtemp_gym.rewards.row_reward``
    exactly (tests/test_optimum.py checks it on trajectories of every plant).

    Args:
        Z: (T, n_z) plant outputs after each step. U, U_prev: (T, n_u) commands of each
            step and of the one before. sp: (T,) main-steam setpoint of each step (C).
        layout: ``i_out``, ``i_design`` (-1: none), ``sprays``, ``secondary`` (output
            columns), ``spray_scale``, ``w`` (:meth:`RewardConfig.to_array`) and
            ``secondary_sp`` (C), as the env's kernel reads them.
        eps: The smoothing widths.

    Returns:
        (r, dr/dZ, dr/dU, dr/dU_prev), arrays of the shapes of (sp, Z, U, U_prev).
    """
    w = layout["w"]
    e_K, e_u, e_s = eps
    gZ = np.zeros_like(Z)

    def absolute(x, s):
        root = np.sqrt(x * x + s * s)
        return root - s, np.divide(x, root, out=np.sign(x), where=root > 0)

    def positive(x, s):
        root = np.sqrt(x * x + s * s)
        return 0.5 * (x + root), 0.5 * (1.0 + np.divide(x, root, out=np.sign(x), where=root > 0))

    def temperature(e):
        """c(e) and dc/de."""
        T0 = w[W.T0_K]
        a, da = absolute(e, e_K)
        band, dband = positive(a - w[W.band_K], e_K)
        c = w[W.w_abs] * a / T0 + w[W.w_sq] * (e / T0) ** 2 + w[W.w_band] * band / T0
        dc = w[W.w_abs] * da / T0 + 2.0 * w[W.w_sq] * e / T0**2 + w[W.w_band] * dband * da / T0
        return c, dc

    i_out = layout["i_out"]
    c, dc = temperature(sp - Z[:, i_out])
    cost = c
    gZ[:, i_out] += dc  # e = sp - z: dc/dz = -dc/de, and r = -cost
    for col, target in zip(layout["secondary"], layout["secondary_sp"], strict=True):
        c2, dc2 = temperature(target - Z[:, col])
        cost = cost + w[W.w_secondary] * c2
        gZ[:, col] += w[W.w_secondary] * dc2
    sprays = layout["sprays"]
    if len(sprays):
        spray = Z[:, sprays].sum(axis=1)
        d_spray = np.ones_like(spray)
        if layout["i_design"] >= 0:
            spray, d_spray = positive(spray - Z[:, layout["i_design"]], e_s * layout["spray_scale"])
            gZ[:, layout["i_design"]] += w[W.w_spray] * d_spray / layout["spray_scale"]
        cost = cost + w[W.w_spray] * spray / layout["spray_scale"]
        for col in sprays:
            gZ[:, col] -= w[W.w_spray] * d_spray / layout["spray_scale"]
    move, d_move = absolute(U - U_prev, e_u)
    cost = cost + w[W.w_move] * move.sum(axis=1)
    return -cost, gZ, -w[W.w_move] * d_move, w[W.w_move] * d_move


@dataclass
class Episode:
    """One row's episode as an open-loop problem (module docstring): the plant, its state
    at the start and the disturbances and setpoints of every step, which no command
    changes.

    Attributes:
        plant: The plant object the row simulates.
        x0: (n_x,) plant state at the start. u_init: (n_u,) commands held at the start.
        D: (T, N_DIST) disturbances of each step. sp: (T,) the setpoint the reward of each
            step reads.
        layout: what the reward reads (:func:`reward_layout`).
        frozen: plant states that are its own random generators' seeds and counters (those
            ``Plant.seed_rows`` writes): no command moves them, and they are not perturbed.
    """

    plant: Any
    x0: np.ndarray
    u_init: np.ndarray
    D: np.ndarray
    sp: np.ndarray
    layout: dict
    frozen: np.ndarray
    source: Core = field(repr=False)
    row: int = 0

    @property
    def T(self) -> int:
        return len(self.sp)


def reward_layout(core: Core) -> dict:
    """What the reward reads of a core's rows: output columns and weights (envs/kernels.py)."""
    ints, cfg = core.state.ints, core.state.cfg
    return {
        "i_out": int(ints[H.outlet]),
        "i_design": int(ints[H.design_spray]),
        "sprays": np.array(ints[ints[H.sprays] : ints[H.secondary]]),
        "secondary": np.array(ints[ints[H.secondary] : ints[H.info]]),
        "spray_scale": float(cfg[CFG.spray_scale]),
        "w": np.array(cfg[N_CFG : N_CFG + N_WEIGHTS]),
        "secondary_sp": np.array(cfg[N_CFG + N_WEIGHTS :]),
    }


def episode(core: Core, row: int = 0) -> Episode:
    """The open-loop problem of ``row`` of ``core`` from its current state (normally its
    start): one rollout with the commands held records the disturbances and setpoints."""
    probe = planning_core(core, 1)
    copy_rows(core, [row], probe, [0])
    x0, u_init = probe.X[0].copy(), probe.U_prev[0].copy()
    hold = (2.0 * u_init - 1.0)[None, :]
    D, sp = [], []
    while True:
        D.append(probe.D[0].copy())
        probe.step(hold)
        sp.append(float(probe.sp[0]))
        if probe.truncated[0]:  # a trip of the held commands ends nothing here
            break
    plant = core.row_plant(row)
    # the plant's own random generators' seeds and counters: the states seed_rows writes
    marked = np.full((1, plant.n_x), np.nan)
    plant.seed_rows(marked, np.zeros(1, dtype=np.uint64))
    frozen = np.isfinite(marked[0])
    return Episode(
        plant, x0, u_init, np.array(D), np.array(sp), reward_layout(core), frozen, core, row
    )


def simulate(ep: Episode, U: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(X, Z): the plant state before each step and the outputs after it, commands U (T, n_u)."""
    plant = ep.plant
    X = ep.x0[None, :].copy()
    Z = np.zeros((1, plant.n_z))
    Xs, Zs = np.empty((ep.T, plant.n_x)), np.empty((ep.T, plant.n_z))
    U = np.ascontiguousarray(U, dtype=np.float64)
    args = list(plant.step_args(X, U[0:1], ep.D[0:1], Z))
    kern = plant.kernel()
    for t in range(ep.T):
        Xs[t] = X[0]
        args[1], args[2] = U[t : t + 1], ep.D[t : t + 1]
        kern(*args)
        Zs[t] = Z[0]
    return Xs, Zs


def returns(
    ep: Episode, U: np.ndarray, Zs: np.ndarray, eps: tuple[float, float, float]
) -> tuple[float, np.ndarray, np.ndarray]:
    """(J, dJ/dZ (T, n_z), dJ/dU (T, n_u) through the move terms) of the smoothed reward."""
    Uprev = np.vstack([ep.u_init[None, :], U[:-1]])
    r, gZ, gU, gUp = smooth_reward(Zs, U, Uprev, ep.sp, ep.layout, eps)
    gU = gU.copy()
    gU[:-1] += gUp[1:]
    return float(r.sum()), gZ, gU


def jacobians(
    ep: Episode,
    Xs: np.ndarray,
    Zs: np.ndarray,
    U: np.ndarray,
    cols: np.ndarray,
    central: bool = False,
) -> tuple[np.ndarray, ...]:
    """Finite differences along the trajectory: A (T, n_x, n_x) = dx'/dx, B (T, n_x, n_u),
    Cx (T, k, n_x) and Cu (T, k, n_u) of the outputs ``cols``; frozen states get zero
    columns. Every perturbation of every step is a row of one kernel call: forward
    differences from the trajectory itself (``Xs`` before each step, ``Zs`` after), or
    central ones (twice the rows, for the certificate). A command at a bound is
    perturbed inward."""
    plant = ep.plant
    T, n, m = ep.T, plant.n_x, plant.n_u
    live = np.flatnonzero(~ep.frozen)
    p, s = len(live) + m, 2 if central else 1
    hx = REL_STEP * np.maximum(np.abs(Xs[:, live]), 1.0)  # (T, len(live))
    # rows: for each step, each live state's +h (then -h), then each command's
    Xb = np.repeat(Xs, s * p, axis=0).reshape(T, s * p, n)
    Ub = np.repeat(U, s * p, axis=0).reshape(T, s * p, m)
    Db = np.repeat(ep.D, s * p, axis=0).reshape(T, s * p, -1)
    j = np.arange(len(live))
    Xb[:, s * j, live] += hx
    up = U + DU <= 1.0
    hi = np.where(up, U + DU, U)
    lo = np.where(up, U if not central else np.maximum(U - DU, 0.0), U - DU)
    k = np.arange(m)
    Ub[:, s * (len(live) + k), k] = hi
    if central:
        Xb[:, s * j + 1, live] -= hx
        Ub[:, s * (len(live) + k) + 1, k] = lo
    elif not up.all():  # the forward step from a command at 1 goes down
        Ub[:, len(live) + k, k] = np.where(up, hi, lo)
    Xf, Zf = Xb.reshape(T * s * p, n), np.zeros((T * s * p, plant.n_z))
    plant.step(Xf, Ub.reshape(-1, m).copy(), Db.reshape(T * s * p, -1).copy(), Zf)
    Xf = Xf.reshape(T, p, s, n)
    Zf = Zf[:, cols].reshape(T, p, s, len(cols))
    if central:
        dX, dZ = Xf[:, :, 0] - Xf[:, :, 1], Zf[:, :, 0] - Zf[:, :, 1]  # (T, p, n)
        h = np.concatenate([2.0 * hx, hi - lo], axis=1)  # (T, p)
    else:
        X1 = np.vstack([Xs[1:], _after(ep, Xs[-1], U[-1])])
        dX, dZ = Xf[:, :, 0] - X1[:, None, :], Zf[:, :, 0] - Zs[:, None, cols]
        h = np.concatenate([hx, np.where(up, hi - U, lo - U)], axis=1)
    dX /= h[:, :, None]
    dZ /= h[:, :, None]
    A = np.zeros((T, n, n))
    Cx = np.zeros((T, len(cols), n))
    A[:, :, live] = dX[:, : len(live)].transpose(0, 2, 1)
    Cx[:, :, live] = dZ[:, : len(live)].transpose(0, 2, 1)
    B = dX[:, len(live) :].transpose(0, 2, 1)
    Cu = dZ[:, len(live) :].transpose(0, 2, 1)
    return A, B, Cx, Cu


def _after(ep: Episode, x: np.ndarray, u: np.ndarray) -> np.ndarray:
    """The plant state after the last step (state x, commands u)."""
    X, Z = x[None, :].copy(), np.zeros((1, ep.plant.n_z))
    ep.plant.step(X, u[None, :].copy(), ep.D[-1:].copy(), Z)
    return X


@dataclass
class Linearization:
    """The trajectory's Jacobians (:func:`jacobians`) at commands ``U``, reused while the
    commands stay within :attr:`reach` of them (:func:`value_and_gradient`)."""

    U: np.ndarray
    cols: np.ndarray
    A: np.ndarray
    B: np.ndarray
    Cx: np.ndarray
    Cu: np.ndarray
    #: largest command change (opening) for which the Jacobians are reused
    reach: float = 0.05
    #: evaluations left before they are made anew
    uses: int = 30

    def covers(self, U: np.ndarray, cols: np.ndarray) -> bool:
        return (
            self.uses > 0
            and np.array_equal(cols, self.cols)
            and float(np.max(np.abs(U - self.U))) <= self.reach
        )


def value_and_gradient(
    ep: Episode,
    U: np.ndarray,
    eps: tuple[float, float, float],
    central: bool = False,
    cache: dict | None = None,
) -> tuple[float, np.ndarray]:
    """The smoothed return of commands U (T, n_u) and its gradient (T, n_u) by the adjoint
    recursion through the trajectory's Jacobians (:func:`jacobians`). The return and the
    reward's derivatives are always those of U's own trajectory; with a ``cache`` (a dict
    the caller keeps), the Jacobians of a nearby trajectory are reused
    (:class:`Linearization`): the plant's Jacobians change little with small command changes,
    and a whole-trajectory linearization costs 20-50 simulations. A trajectory that leaves
    the finite states returns -inf and a zero gradient."""
    Xs, Zs = simulate(ep, U)
    if not (np.isfinite(Zs).all() and np.isfinite(Xs).all()):
        return -math.inf, np.zeros_like(U)
    J, gZ, gU = returns(ep, U, Zs, eps)
    cols = np.flatnonzero(np.any(gZ != 0.0, axis=0))
    lin = None if cache is None else cache.get("lin")
    if lin is None or not lin.covers(U, cols):
        lin = Linearization(U.copy(), cols, *jacobians(ep, Xs, Zs, U, cols, central))
        if cache is not None:
            cache["lin"] = lin
    lin.uses -= 1
    A, B, Cx, Cu = lin.A, lin.B, lin.Cx, lin.Cu
    gz = gZ[:, cols]
    gx = np.einsum("tk,tkn->tn", gz, Cx)
    g = gU + np.einsum("tk,tkm->tm", gz, Cu)
    _adjoint(A, B, gx, g)
    return J, g


@njit(cache=True)
def _adjoint(A, B, gx, g):
    """The backward recursion: mu_T = 0, g_t += B_t' mu_{t+1}, mu_t = A_t' mu_{t+1} + gx_t
    (mu_t: the gradient of the rewards after step t - 1 with respect to the state x_t)."""
    T, n = gx.shape
    mu = np.zeros(n)
    nxt = np.zeros(n)
    for t in range(T - 1, -1, -1):
        for j in range(B.shape[2]):
            acc = 0.0
            for i in range(n):
                acc += mu[i] * B[t, i, j]
            g[t, j] += acc
        for j in range(n):
            acc = gx[t, j]
            for i in range(n):
                acc += mu[i] * A[t, i, j]
            nxt[j] = acc
        mu, nxt = nxt, mu


def to_actions(U: np.ndarray) -> np.ndarray:
    """Commands (openings in [0, 1]) as the float32 actions a policy hands the env."""
    return (2.0 * np.asarray(U, dtype=np.float64) - 1.0).astype(np.float32)


def exact_return(ep: Episode, actions: np.ndarray) -> tuple[float, bool]:
    """(return, tripped): the env's exact return of the float32 ``actions`` from the row's
    state, stepped on a copy of it by the env's own core and summed in order as the
    evaluation sums it."""
    probe = planning_core(ep.source, 1)
    copy_rows(ep.source, [ep.row], probe, [0])
    total = 0.0
    for a in actions:
        probe.step(a[None, :])
        total += float(probe.reward[0])
        if probe.ended()[0]:
            return total, bool(probe.trip[0])
    return total, False


def smoothing(scale: float) -> tuple[float, float, float]:
    return tuple(scale * e for e in SMOOTHING)  # type: ignore[return-value]


class Knots:
    """A piecewise-linear sequence through knots every ``k`` steps (k = 1: the commands
    themselves): u = M theta, with M^T for the gradient."""

    def __init__(self, T: int, k: int) -> None:
        self.T, self.k = T, k
        self.n = math.ceil((T - 1) / k) + 1 if k > 1 else T
        t = np.arange(T) / k
        self.k0 = np.minimum(t.astype(np.int64), self.n - 2) if k > 1 else np.arange(T)
        self.w = (t - self.k0)[:, None] if k > 1 else np.zeros((T, 1))

    def expand(self, theta: np.ndarray) -> np.ndarray:
        """M theta: (n, n_u) knots to (T, n_u) commands."""
        if self.k == 1:
            return theta
        a, b = theta[self.k0], theta[self.k0 + 1]
        return a + (b - a) * self.w

    def pull(self, g: np.ndarray) -> np.ndarray:
        """M^T g: a gradient over the commands to one over the knots."""
        if self.k == 1:
            return g
        out = np.zeros((self.n, g.shape[1]))
        np.add.at(out, self.k0, g * (1.0 - self.w))
        np.add.at(out, self.k0 + 1, g * self.w)
        return out
