"""The search for the optimum: L-BFGS-B over a sequence of parameterizations, from each
warm start (agents/optimum/__init__.py)."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.optimize import minimize

from agents.optimum.certificate import certify
from agents.optimum.problem import (
    Episode,
    Knots,
    exact_return,
    smoothing,
    to_actions,
    value_and_gradient,
)

#: Knot spacings of the parameterizations, coarse to fine: 30 s and 10 s, then every
#: second control interval, then every interval (:func:`levels`).
KNOTS_S = (30.0, 10.0)
#: The smoothing scale of the parameterization levels, then the continuation's scales at
#: the finest level (the widths go to 1/1000 of problem.SMOOTHING).
LEVEL_SMOOTHING = 0.1
CONTINUATION = (0.01, 0.001)
#: A level stops when the smoothed return gained less than this share of the best start's
#: headroom over its last ``Stop.window`` iterations.
LEVEL_TOL = 2e-5


def levels(dt_s: float) -> tuple[int, ...]:
    """The knot spacings in control intervals, coarse to fine (:data:`KNOTS_S`, then 2 and 1)."""
    ks = {max(1, round(s / dt_s)) for s in KNOTS_S} | {2, 1}
    return tuple(sorted(ks, reverse=True))


@dataclass
class Stop:
    """When a level stops: after ``maxiter`` iterations, or when the smoothed return gained
    less than ``tol`` over the last ``window`` iterations."""

    tol: float
    maxiter: int = 2000
    window: int = 20


def solve_level(
    ep: Episode, base: np.ndarray, k: int, eps: tuple[float, float, float], stop: Stop
) -> tuple[np.ndarray, dict]:
    """Maximize the smoothed return over a piecewise-linear correction of ``base`` through
    knots every k steps (clipped to the bounds), or at k = 1 over the commands themselves
    within their bounds. Returns the commands and what the search did."""
    knots, m = Knots(ep.T, k), base.shape[1]
    history: list[float] = []
    cache: dict = {}

    def commands(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if k == 1:
            U = theta.reshape(ep.T, m)
            return U, U
        raw = base + knots.expand(theta.reshape(knots.n, m))
        return np.clip(raw, 0.0, 1.0), raw

    def fun(theta: np.ndarray) -> tuple[float, np.ndarray]:
        U, raw = commands(theta)
        J, g = value_and_gradient(ep, U, eps, cache=cache)
        if not math.isfinite(J):
            return 1e30, np.zeros_like(theta)
        if k > 1:
            g = knots.pull(np.where((raw > 0.0) & (raw < 1.0), g, 0.0))
        return -J, -g.ravel()

    def callback(intermediate_result: Any) -> None:
        history.append(-float(intermediate_result.fun))
        w = stop.window
        if len(history) > w and history[-1] - history[-1 - w] < stop.tol:
            raise StopIteration

    if k == 1:
        x0, bounds = base.ravel().copy(), [(0.0, 1.0)] * base.size
    else:
        x0, bounds = np.zeros(knots.n * m), None
    t0 = time.process_time()
    res = minimize(
        fun,
        x0,
        jac=True,
        method="L-BFGS-B",
        bounds=bounds,
        callback=callback,
        options={"maxiter": stop.maxiter, "maxcor": 20, "ftol": 0.0, "gtol": 0.0},
    )
    U = commands(res.x)[0]
    return U, {
        "knot_steps": k,
        "eps": list(eps),
        "iterations": int(res.nit),
        "evaluations": int(res.nfev),
        "smoothed": -float(res.fun),
        "cpu_s": time.process_time() - t0,
    }


def refine(ep: Episode, U: np.ndarray, tol: float, log: list[dict]) -> np.ndarray:
    """One start's path (module docstring): every level of :func:`levels` at the smoothing
    of :data:`LEVEL_SMOOTHING`, then the continuation at every interval; each step's exact
    return in ``log``. Returns the commands of the best exact return on the path."""
    best_U = U
    best = exact_return(ep, to_actions(U))[0]
    steps = [(k, LEVEL_SMOOTHING) for k in levels(ep.plant.dt_s)]
    steps += [(1, s) for s in CONTINUATION]
    for k, scale in steps:
        U, info = solve_level(ep, U, k, smoothing(scale), Stop(tol))
        info["return"], info["tripped"] = exact_return(ep, to_actions(U))
        log.append(info)
        if info["return"] > best and not info["tripped"]:
            best, best_U = info["return"], U
        else:  # go on from the best so far
            U = best_U
    return best_U


@dataclass
class Path:
    """One start's refinement: its name, its start's return and every step's log."""

    start: str
    start_return: float
    steps: list[dict]
    U: np.ndarray = field(repr=False)
    final: float = -math.inf


def solve(
    ep: Episode,
    starts: dict[str, np.ndarray],
    start_returns: dict[str, float],
    zero: float,
    n_paths: int = 2,
) -> dict:
    """The optimum of episode ``ep`` from the warm starts (name -> actions, with their exact
    returns): the best ``n_paths`` starts refined (:func:`refine`), the best result kept, and
    its certificate (agents/optimum/certificate.py) against the headroom over the return
    ``zero`` (the score's 0 on the episode)."""
    order = sorted(starts, key=lambda n: start_returns[n], reverse=True)[:n_paths]
    tol = LEVEL_TOL * max(start_returns[order[0]] - zero, 1e-9)
    paths = []
    for name in order:
        a = np.asarray(starts[name], dtype=np.float64)
        if len(a) < ep.T:  # a start that tripped: its last commands held
            a = np.vstack([a, np.repeat(a[-1:], ep.T - len(a), axis=0)])
        t0 = time.process_time()
        log: list[dict] = []
        U = refine(ep, (a + 1.0) / 2.0, tol, log)
        path = Path(name, start_returns[name], log, U)  # U: the start's own if none beat it
        path.final = exact_return(ep, to_actions(U))[0]
        path.steps.append({"cpu_s_path": time.process_time() - t0})
        paths.append(path)
    best = max(paths, key=lambda p: p.final)
    actions = to_actions(best.U)
    R1, tripped = exact_return(ep, actions)
    logs = [
        {"start": p.start, "start_return": p.start_return, "final": p.final, "steps": p.steps}
        for p in paths
    ]
    return {
        "return": R1,
        "tripped": tripped,
        "zero": zero,
        "actions": actions,
        "paths": logs,
        "certificate": certify(
            ep, best.U, R1, zero, logs, best.start, smoothing(CONTINUATION[-1]), LEVEL_SMOOTHING
        ),
    }
