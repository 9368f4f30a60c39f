"""How close a solution is to the optimum of its episode, in shares of the headroom.

The headroom is the solution's return R1 above the score's 0 on the episode, R0 (the
return of ``cascade_pi_ff``). :func:`certify` states three things, each with its tolerance
(:data:`TOLERANCES`); the certificate holds when all three are within them:

- ``step_gain``: first-order optimality. The gradient of the smoothed return at the finest
  smoothing, by central differences (problem.py), projected on the commands' bounds, is
  followed from the solution by steps moving no command by more than 1e-2 .. 1e-5
  (opening), each scored on the exact return: the most any of them gains. The reward's
  kinks make the gradient of the exact return discontinuous at an optimum (a projected
  gradient norm does not vanish there), so the residual is stated as the return a
  projected-gradient step still finds; ``kkt_residual``, max |P(u + g) - u| of that
  gradient, is given beside it.
- ``last_refinement``: the return gained by the last refinement of the parameterization
  (knots every second control interval to every interval), at equal smoothing.
- ``starts_agree``: the spread of the returns that the refinements from two different warm
  starts reach.

:func:`independent_check` is a second method, for checking a stored solution: gradient
ascent on a piecewise-linear correction of its commands through knots every 120, 30 and
10 s, the gradient by central finite differences of whole episodes' exact returns (every
perturbation a row of one batched env core), with a backtracking line search. It shares
nothing with the optimizer but the env it steps.
"""

from __future__ import annotations

import numpy as np

from agents.optimum.problem import (
    Episode,
    Knots,
    exact_return,
    smoothing,
    to_actions,
    value_and_gradient,
)
from steamtemp_gym.envs.snapshot import copy_rows, planning_core

#: The certificate's tolerances, in shares of the episode's headroom.
TOLERANCES = {"step_gain": 1e-3, "last_refinement": 1e-2, "starts_agree": 5e-3}
#: The largest command moves (opening) of the projected-gradient steps of ``step_gain``.
STEP_MOVES = (1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5)


def projected_gradient(ep: Episode, U: np.ndarray, eps: tuple[float, float, float]) -> np.ndarray:
    """The gradient of the smoothed return at U (central differences) with the components
    that push a command at a bound outwards removed."""
    _, g = value_and_gradient(ep, U, eps, central=True)
    outward = ((U <= 0.0) & (g < 0.0)) | ((U >= 1.0) & (g > 0.0))
    return np.where(outward, 0.0, g)


def step_gain(ep: Episode, U: np.ndarray, R: float, g: np.ndarray) -> float:
    """The most the exact return gains over R along the projected gradient g from U, in
    steps moving no command by more than each of :data:`STEP_MOVES`."""
    scale = float(np.max(np.abs(g)))
    if scale == 0.0:
        return 0.0
    best = R
    for move in STEP_MOVES:
        trial = np.clip(U + g * (move / scale), 0.0, 1.0)
        r, tripped = exact_return(ep, to_actions(trial))
        if not tripped:
            best = max(best, r)
    return best - R


def certify(
    ep: Episode,
    U: np.ndarray,
    R1: float,
    zero: float,
    paths: list[dict],
    best: str,
    eps: tuple[float, float, float],
    level_smoothing: float,
) -> dict:
    """The certificate of commands U with exact return R1 (module docstring): ``paths`` are
    the search's logs (agents/optimum/search.py), ``best`` the start of the best one,
    ``eps`` the finest smoothing and ``level_smoothing`` the scale of the levels."""
    headroom = R1 - zero
    g = projected_gradient(ep, U, eps)
    steps = next(p["steps"] for p in paths if p["start"] == best)
    by_k = {
        s["knot_steps"]: s["return"]
        for s in steps
        if "knot_steps" in s and s["eps"][0] == smoothing(level_smoothing)[0]
    }
    ks = sorted(by_k)
    finals = [p["final"] for p in paths]
    cert = {
        "headroom": headroom,
        "kkt_residual": float(np.max(np.abs(np.clip(U + g, 0.0, 1.0) - U))),
        "step_gain": step_gain(ep, U, R1, g) / headroom,
        "last_refinement": (by_k[ks[0]] - by_k[ks[1]]) / headroom if len(ks) > 1 else None,
        "starts_agree": (max(finals) - min(finals)) / headroom if len(finals) > 1 else None,
    }
    cert["holds"] = all(cert[k] is not None and cert[k] <= tol for k, tol in TOLERANCES.items())
    return cert


def _batch_returns(ep: Episode, U: np.ndarray) -> np.ndarray:
    """Exact returns of command sequences U (n, T, n_u) from the episode's start, each a row
    of one env core (a row that trips keeps its return up to the trip)."""
    n = len(U)
    core = planning_core(ep.source, n)
    copy_rows(ep.source, [ep.row] * n, core, np.arange(n))
    total, alive = np.zeros(n), np.ones(n, dtype=bool)
    for t in range(U.shape[1]):
        core.step(to_actions(U[:, t]))
        total += np.where(alive, core.reward, 0.0)
        alive &= ~core.ended()
    return total


def independent_check(
    ep: Episode,
    actions: np.ndarray,
    knots_s: tuple[float, ...] = (120.0, 30.0, 10.0),
    iterations: int = 4,
    h: float = 1e-3,
) -> tuple[float, list]:
    """The return that gradient ascent by finite differences of whole episodes adds to the
    solution ``actions`` (module docstring): (gain, log of each level)."""
    U = (np.asarray(actions, dtype=np.float64) + 1.0) / 2.0
    R = float(_batch_returns(ep, U[None])[0])
    start, log = R, []
    for ks in knots_s:
        knots = Knots(ep.T, max(1, round(ks / ep.plant.dt_s)))
        m = U.shape[1]
        for _ in range(iterations):
            dirs = np.zeros((knots.n * m, ep.T, m))
            for j in range(m):
                e = np.zeros((knots.n, m))
                for i in range(knots.n):
                    e[:] = 0.0
                    e[i, j] = 1.0
                    dirs[i * m + j] = knots.expand(e)
            trial = np.concatenate([np.clip(U + h * dirs, 0, 1), np.clip(U - h * dirs, 0, 1)])
            r = _batch_returns(ep, trial)
            g = (r[: len(dirs)] - r[len(dirs) :]) / (2.0 * h)
            step = np.tensordot(g, dirs, axes=1)
            step /= max(float(np.max(np.abs(step))), 1e-300)
            moves = np.array([3e-2, 1e-2, 3e-3, 1e-3, 3e-4])
            cand = np.clip(U[None] + moves[:, None, None] * step[None], 0.0, 1.0)
            rc = _batch_returns(ep, cand)
            i = int(np.argmax(rc))
            if rc[i] <= R:
                break
            U, R = cand[i], float(rc[i])
        log.append({"knot_s": ks, "return": R})
    return R - start, log
