"""The receding-horizon CEM search of the oracle (agents/oracle.py): the ``cem`` engine, and
the warm start of the ``optimum`` engine's whole-episode optimization.

The cross-entropy method over move-blocked command trajectories (Rubinstein and Kroese
2004; for MPC, e.g. Pinneri et al. 2020, "Sample-efficient cross-entropy method for
real-time planning"), on the rows of a planning core whose future is the env rows' own:
:class:`Planner` gives every row's next commands, replanning the rows that are due, within
a :class:`Budget` (agents/oracle.py describes the search).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from steamtemp_gym.checks import check_fields, ranged
from steamtemp_gym.envs.core import Core
from steamtemp_gym.envs.snapshot import copy_rows, planning_core


@dataclass(frozen=True)
class Budget:
    """What one oracle decision may spend (module docstring): positive durations (s) and
    spreads, counts of at least one."""

    horizon_s: float = ranged(240.0, 0.0, math.inf, above=True)
    #: after the horizon the rollouts go on this long with the plan's last commands held, and
    #: the rewards there count: a plan must not buy savings at its end (less spray) with a
    #: temperature excursion that only its dead time and lag hide beyond the horizon
    tail_s: float = ranged(240.0, 0.0, math.inf)
    knot_s: float = ranged(30.0, 0.0, math.inf, above=True)
    replan_s: float = ranged(20.0, 0.0, math.inf, above=True)
    #: candidates per replan and iteration for a plant with one or two actuators; the
    #: search space has knots x actuators dimensions, and plants with three or four
    #: actuators get twice as many (``ceil(n_u / 2)`` times)
    samples: int = ranged(8, 1, math.inf)
    iterations: int = ranged(4, 1, math.inf)
    elites: int = ranged(2, 1, math.inf)
    sigma0: float = ranged(0.05, 0.0, math.inf, above=True)
    sigma_min: float = ranged(0.005, 0.0, math.inf, above=True)

    def __post_init__(self) -> None:
        check_fields(self, "oracle budget {name}")
        if self.elites > self.samples:
            raise ValueError(f"oracle budget: elites ({self.elites}) > samples ({self.samples})")
        if self.knot_s > self.horizon_s or self.replan_s > self.horizon_s:
            raise ValueError("oracle budget: knot_s and replan_s must not exceed horizon_s")


class Planner:
    """The receding-horizon CEM on the rows of one core (module docstring): :meth:`act`
    gives every row's next commands, replanning the rows that are due.

    Args:
        src: The core whose rows it plans for and reads.
        budget: The optimizer's budget (:class:`Budget`).
    """

    def __init__(self, src: Core, budget: Budget) -> None:
        self.src, self.budget = src, budget
        plant = src.plant
        dt = plant.dt_s
        b = budget
        self.H = max(1, round(b.horizon_s / dt))
        self.T = round(b.tail_s / dt)
        self.K = max(1, round(b.knot_s / dt))
        self.R = max(1, round(b.replan_s / dt))
        self.n_knots = math.ceil(self.H / self.K) + 1
        self.n_u = plant.n_u
        self.samples = b.samples * math.ceil(self.n_u / 2)
        # knot k sits at step k K of the plan; command of plan step h by linear interpolation
        t = np.arange(self.H) / self.K
        k0 = np.minimum(t.astype(np.int64), self.n_knots - 2)
        self._k0, self._w = k0, (t - k0)[:, None]
        self._core: Core | None = None
        B = src.B
        self.plan = np.zeros((B, self.H, self.n_u))  # commands of each row's plan
        self.knots = np.zeros((B, self.n_knots, self.n_u))  # its knots
        self.start = np.full(B, -1, dtype=np.int64)  # step counter at each row's plan start

    def _planner(self) -> Core:
        """The planning core (rows x samples rows); its rows simulate the plants of the rows
        copied into them (snapshot.planning_core)."""
        if self._core is None:
            self._core = planning_core(self.src, self.src.B * self.samples)
        return self._core

    def _commands(self, knots: np.ndarray) -> np.ndarray:
        """(..., H, n_u) commands of knots (..., n_knots, n_u)."""
        a, b = knots[..., self._k0, :], knots[..., self._k0 + 1, :]
        return a + (b - a) * self._w

    def _returns(self, rows: np.ndarray, cand: np.ndarray) -> np.ndarray:
        """Reward summed over the horizon and tail of each candidate (len(rows), samples, n_knots,
        n_u) from each source row's current state."""
        core = self._planner()
        S = self.samples
        n = len(rows) * S
        dst = np.arange(n)
        copy_rows(self.src, np.repeat(rows, S), core, dst)
        U = self._commands(cand).reshape(n, self.H, self.n_u)
        A = np.empty((core.B, self.n_u))
        A[n:] = 0.0
        ret = np.zeros(n)
        alive = np.ones(n, dtype=bool)
        left = core.time_left()[:n]
        for h in range(self.H + self.T):
            alive &= left > 1e-9
            if h < self.H:  # the tail holds the last commands
                A[:n] = (2.0 * U[:, h] - 1.0).astype(np.float32)  # as predict hands them out
            core.step(A)
            ret += np.where(alive, core.reward[:n], 0.0)
            alive &= core.trip[:n] == 0  # a trip ends the row's episode
            left -= self.src.plant.dt_s
        return ret.reshape(len(rows), S)

    def _optimize(self, rows: np.ndarray, mean: np.ndarray) -> np.ndarray:
        """Best knots of each row: CEM from ``mean``, which is kept as a candidate."""
        b = self.budget
        n = len(rows)
        sigma = np.full_like(mean, b.sigma0)
        keys, steps = self.src.noise_keys(), self.src.steps()
        rngs = [np.random.default_rng([int(keys[r]), int(steps[r])]) for r in rows]
        best, best_ret = mean.copy(), np.full(n, -np.inf)
        for _ in range(b.iterations):
            eps = np.stack([g.standard_normal((self.samples - 1, *mean.shape[1:])) for g in rngs])
            cand = np.empty((n, self.samples, *mean.shape[1:]))
            cand[:, 1:] = np.clip(mean[:, None] + sigma[:, None] * eps, 0.0, 1.0)
            cand[:, 0] = best
            if self.samples > 2:
                cand[:, 1] = mean  # the refitted mean itself, without noise
            ret = self._returns(rows, cand)
            top = np.argsort(-ret, axis=1, kind="stable")[:, : b.elites]
            elite = np.take_along_axis(cand, top[:, :, None, None], axis=1)
            mean = elite.mean(axis=1)
            sigma = np.maximum(elite.std(axis=1), b.sigma_min)
            i = top[:, 0]
            better = ret[np.arange(n), i] > best_ret
            best[better] = cand[np.arange(n), i][better]
            best_ret = np.maximum(best_ret, ret[np.arange(n), i])
        return best

    def _shifted(self, rows: np.ndarray) -> np.ndarray:
        """Warm start of each row: its plan shifted to now, held at its end (a new
        episode: the commands held at its start)."""
        U = self.src.held_commands()[rows]
        mean = np.repeat(U[:, None, :], self.n_knots, axis=1)
        counter = self.src.steps()
        for j, r in enumerate(rows):
            age = int(counter[r] - self.start[r])
            if self.start[r] < 0 or age < 0 or age > self.H or counter[r] == 0:
                continue
            t = np.minimum(age + np.arange(self.n_knots) * self.K, self.H - 1)
            mean[j] = self._commands(self.knots[r])[t]
        return mean

    def act(self) -> np.ndarray:
        """Every row's next commands as actions in [-1, 1] (float32), replanning the rows
        whose plan is due."""
        counter = self.src.steps()
        age = counter - self.start
        rows = np.flatnonzero((self.start < 0) | (age < 0) | (age >= self.R) | (counter == 0))
        if rows.size:
            best = self._optimize(rows, self._shifted(rows))
            self.knots[rows] = best
            self.plan[rows] = self._commands(best)
            self.start[rows] = counter[rows]
        age = counter - self.start
        return (2.0 * self.plan[np.arange(self.src.B), age] - 1.0).astype(np.float32)
