"""The oracle: a clairvoyant nonlinear MPC on the true plant, the 1 of the normalized score.

Not an admissible controller: a reference, like the frozen valve. At every replanning
instant it copies the *full internal state* of each row of the env it acts on (plant,
valve and thermowell states, the plant's own random generators, the coloured
heat-absorption disturbance, the noise key and step counter, the scenario with its whole
future: envs/snapshot.py) into rows of a planning core of the same plant object (with
``plant_randomization``, each row's own drawn plant: ``snapshot.planning_core``), and
optimizes the valve commands over a receding horizon on the env's own compiled kernel
and reward. Since the noise is counter-based and the scenario is known, its rollouts see
the true future disturbances exactly: up to the optimizer's suboptimality, no causal
controller can score more than it. The observation it is handed is ignored (only its
shape is checked).

Optimizer: the cross-entropy method over move-blocked command trajectories (Rubinstein
and Kroese 2004; for MPC, e.g. Pinneri et al. 2020, "Sample-efficient cross-entropy
method for real-time planning"). A plan is a piecewise-linear command trajectory through
knots every ``knot_s`` seconds over ``horizon_s``. Each replan (every ``replan_s``)
starts from the previous best plan shifted by the time elapsed (warm start), samples
``samples - 1`` Gaussian perturbations of the mean knots per iteration next to the best
plan so far (kept in the population, so a replan never returns a worse plan than its warm
start within the horizon), scores every candidate by the env's own reward summed over the
horizon (trip penalty included; nothing after the episode's end or a trip counts) and
refits mean and spread to the best ``elites``. It returns the best plan's commands.
Commands are openings in [0, 1]; the valve rate limits, lags and bounds are those the
plant kernel enforces on every command.

Deterministic given the episode: each row's random draws come from a generator seeded by
the row's noise key and step counter, so a row gets the same plan alone or in a batch,
in the single env or in the vector env.

At least the causal controllers, by construction: when a row's episode starts (or its
state is not where the oracle left it), the oracle plays the whole rest of the episode on a
copy of the row three times, with its receding-horizon CEM and with each of the
:data:`INCUMBENTS` (``mpc_linear``, the best causal controller of the leaderboard, and
``cascade_pi_ff``, the score's 0) acting on the copy's observations, and commits to the
command sequence of the highest return. The row then replays it, and as the copy's future is
the row's, bit for bit, the row's return is the committed one: never below an incumbent's on
the same episode, and the CEM's where the CEM wins (as before, to the bit). An optimizer
that knows the future chooses among whole command sequences; the incumbents' are two more
candidates. With them an episode costs about 1.2x the CEM alone.

The budget (samples, iterations, horizon, knots, replanning interval) was chosen by
measurement: docs/leaderboard.md, "The oracle", gives the return as the budget doubles.
"""

from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import baselines
from agents import optima, optimum
from steamtemp_gym.checks import check_fields, ranged
from steamtemp_gym.envs.core import Core, check_action
from steamtemp_gym.envs.snapshot import copy_rows, env_core, planning_core

#: The causal controllers whose whole-episode command sequences compete with the CEM's
#: (module docstring): the leaderboard's best causal controller and the score's 0.
INCUMBENTS = ("mpc_linear", baselines.INDUSTRIAL_REFERENCE)


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
            eps = np.stack([g.standard_normal((self.samples - 1, *mean.shape[1:]))
                            for g in rngs])  # fmt: skip
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


#: How the oracle finds each episode's command sequence: ``"optimum"``, the clairvoyant
#: whole-episode optimum (agents/optimum.py; stored ones replayed), or ``"cem"``, the
#: receding-horizon search alone (a lower bound of the optimum, for quick looks).
ENGINES = ("optimum", "cem")
#: The engine of the leaderboard's oracle unless ``--oracle`` says otherwise.
DEFAULT_ENGINE = "cem"


class Replay:
    """A policy that plays a fixed sequence of actions (steps, n_u) in a single env, one per
    step from its reset on, then holds the last."""

    def __init__(self, actions: np.ndarray) -> None:
        self.actions = np.asarray(actions, dtype=np.float32)
        self.i = 0

    def reset(self) -> None:
        self.i = 0

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        a = self.actions[min(self.i, len(self.actions) - 1)]
        self.i += 1
        return a.copy(), None


@dataclass
class Committed:
    """A row's committed command sequence from step ``start`` of its episode on: the
    actions (steps, n_u) and the rewards and observations after each, of the rollout it
    won (``source``: ``"cem"`` or an incumbent's name), and every candidate's return and
    actions."""

    key: int
    start: int
    actions: np.ndarray
    rewards: np.ndarray
    observations: np.ndarray
    source: str
    returns: dict[str, float]
    #: every candidate's actions (steps, n_u), the winner's included: the warm starts of
    #: the whole-episode optimum (agents/optimum.py)
    sequences: dict[str, np.ndarray]


def rollout(core: Core, act: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Run every row of ``core`` to its episode's end (a trip or the end of its scenario),
    ``act(observations, first) -> actions`` deciding. Returns the actions (steps, rows,
    n_u) as the core took them, the rewards (steps, rows), the observations after each
    step and each row's number of steps; rows that ended keep stepping until the last one
    ends (their rewards there are 0)."""
    n = core.B
    shape = (n, core.plant.n_u)
    alive = np.ones(n, dtype=bool)
    steps = np.zeros(n, dtype=np.int64)
    acts, rews, obs = [], [], []
    while alive.any():
        a = check_action(act(core.obs.copy(), not acts), shape)
        core.step(a)
        acts.append(np.array(a, dtype=np.float64))
        rews.append(np.where(alive, core.reward, 0.0))
        obs.append(core.obs.copy())
        steps += alive
        alive &= ~core.ended()
    return np.asarray(acts), np.asarray(rews), np.asarray(obs), steps


class Oracle:
    """Clairvoyant CEM-MPC on the env's own kernel, at least the causal controllers of
    :data:`INCUMBENTS` on every episode (module docstring).

    Args:
        env: The env (single or native vector env) whose rows it acts on and reads.
        budget: The optimizer's budget (:class:`Budget`).
        incumbents: Baseline names whose closed-loop episodes compete with the CEM's
            (default :data:`INCUMBENTS`; ``()``: the CEM alone).
        engine: ``"optimum"`` or ``"cem"`` (:data:`ENGINES`).
        store: Where the ``optimum`` engine finds stored optima (agents/optima.py).
    """

    def __init__(self, env: Any, budget: Budget | None = None,
                 incumbents: tuple[str, ...] = INCUMBENTS, engine: str = "cem",
                 store: Path = optima.STORE) -> None:  # fmt: skip
        try:
            src = env_core(env)
        except ValueError as exc:
            raise ValueError(f"the oracle acts on a steamtemp_gym env: {exc}") from None
        unknown = [n for n in incumbents if n not in baselines.NAMES]
        if isinstance(incumbents, str) or unknown:
            raise ValueError(f"oracle incumbents must be a tuple of baseline names "
                             f"({', '.join(baselines.NAMES)}), got {incumbents!r}")  # fmt: skip
        if engine not in ENGINES:
            raise ValueError(f"oracle engine must be one of {ENGINES}, got {engine!r}")
        self.engine, self.store = engine, Path(store)
        self.env, self.src = env, src
        self.budget = budget or Budget()
        self.incumbents = tuple(incumbents)
        self._policies: list[Any] | None = None
        self.reset()

    def reset(self) -> None:
        B = self.src.B
        self.committed: list[Committed | None] = [None] * B
        self._next = np.full(B, -1, dtype=np.int64)  # the counter each row is due at
        self._key = np.full(B, -1, dtype=np.int64)  # the noise key of its committed episode

    def _incumbent_policies(self) -> list[Any]:
        """The incumbents, commissioned once on the env (as the leaderboard makes them)."""
        if self._policies is None:
            self._policies = [baselines.make(n, self.env) for n in self.incumbents]
        return self._policies

    def _commit(self, rows: np.ndarray) -> None:
        """Commit each row to its episode's command sequence: with the ``optimum`` engine
        the stored optimum where it replays (:meth:`_stored`), else the whole-episode
        optimum solved now from the CEM's and the incumbents' sequences (:meth:`_solve`);
        with the ``cem`` engine the best of those."""
        if self.engine == "optimum":
            rows = self._stored(rows)
        if rows.size:
            self._commit_cem(rows)
        if self.engine == "optimum":
            for r in rows:
                self._solve(int(r))

    def _play(self, rows: np.ndarray, sequences: list[np.ndarray]) -> tuple:
        """:func:`rollout` of copies of ``rows`` each playing its sequence of actions (its
        last action held after its end)."""
        n = len(rows)
        shadow = planning_core(self.src, n)
        copy_rows(self.src, rows, shadow, np.arange(n))
        step = [0]

        def act(obs: np.ndarray, first: bool) -> np.ndarray:
            i = step[0]
            step[0] += 1
            return np.stack([a[min(i, len(a) - 1)] for a in sequences])

        return rollout(shadow, act)

    def _keep(self, r: int, j: int, run: tuple, source: str, returns: dict,
              sequences: dict) -> None:  # fmt: skip
        """Commit row r to row j of ``run`` (a :func:`rollout`)."""
        acts, rew, obs, steps = run
        k = steps[j]
        self.committed[r] = Committed(int(self.src.noise_keys()[r]), int(self.src.steps()[r]),
                                      acts[:k, j].copy(), rew[:k, j].copy(), obs[:k, j].copy(),
                                      source, returns, sequences)  # fmt: skip
        self._key[r] = self.src.noise_keys()[r]

    def _stored(self, rows: np.ndarray) -> np.ndarray:
        """Commit the rows at their episode's start whose stored optimum (agents/optima.py)
        replays to its stored return bit for bit; returns the other rows."""
        keys, counter = self.src.noise_keys(), self.src.steps()
        found = {}
        for r in rows.tolist():
            record = None if counter[r] else optima.find(
                self.src.plant.id, self.src.scenario[r], int(keys[r]), self.store)
            a = None if record is None else optima.actions(record, self.store)
            if a is not None:
                found[r] = (record, a)
        if not found:
            return rows
        run = self._play(np.array(list(found)), [a for _, a in found.values()])
        for j, (r, (record, a)) in enumerate(found.items()):
            total = float(np.cumsum(run[1][: run[3][j], j])[-1])  # summed in order
            if total == record["return"]:
                self._keep(r, j, run, "stored optimum", {"stored optimum": total},
                           {"stored optimum": a})  # fmt: skip
            else:
                print(f"oracle: the stored optimum of {self.src.plant.id} "
                      f"{record['scenario']} seed {record['seed']} replays to {total!r}, not "
                      f"its stored {record['return']!r} (the plant's code has changed): "
                      "solving it anew", file=sys.stderr, flush=True)  # fmt: skip
        return np.array([r for r in rows.tolist() if self.committed[r] is None
                         or self._key[r] != keys[r] or self.committed[r].start != counter[r]],
                        dtype=np.int64)  # fmt: skip

    def _solve(self, r: int) -> None:
        """Commit row r to the whole-episode optimum from its state (agents/optimum.py),
        warm started by the sequences of its CEM commit, saying so on stderr."""
        c = self.committed[r]
        scenario = self.src.scenario[r]
        zero = c.returns.get(baselines.INDUSTRIAL_REFERENCE, min(c.returns.values()))
        print(f"oracle: solving the clairvoyant optimum of {self.src.plant.id} "
              f"{scenario.name!r} (noise key {c.key}) from step {c.start}: a few minutes of "
              "one core", file=sys.stderr, flush=True)  # fmt: skip
        t0 = time.process_time()
        out = optimum.solve(optimum.episode(self.src, r), c.sequences, c.returns, zero)
        run = self._play(np.array([r]), [out["actions"]])
        returns = {**c.returns, "optimum": out["return"]}
        self._keep(r, 0, run, "optimum", returns, {**c.sequences, "optimum": out["actions"]})
        print(f"oracle: done in {time.process_time() - t0:.0f} s of CPU: return "
              f"{out['return']:.4f} (CEM {c.returns.get('cem', float('nan')):.4f}); certificate "
              f"{'holds' if out['certificate']['holds'] else 'fails'}", file=sys.stderr,
              flush=True)  # fmt: skip

    def _commit_cem(self, rows: np.ndarray) -> None:
        """Roll the rest of each row's episode out on copies, by the CEM and by each
        incumbent, and commit to the best (module docstring)."""
        n = len(rows)
        keys, counter = self.src.noise_keys(), self.src.steps()
        shadow = planning_core(self.src, n)
        dst = np.arange(n)
        copy_rows(self.src, rows, shadow, dst)
        planner = Planner(shadow, self.budget)
        runs = {"cem": rollout(shadow, lambda obs, first: planner.act())}
        for name, policy in zip(self.incumbents, self._incumbent_policies(), strict=True):
            copy_rows(self.src, rows, shadow, dst)
            policy.reset()
            runs[name] = rollout(shadow, lambda obs, first, p=policy: p.predict(
                obs, episode_start=np.full(n, first), deterministic=True)[0])
        for j, r in enumerate(rows):
            # summed in order, as the evaluation adds; a tie keeps the CEM's
            totals = {name: float(np.cumsum(run[1][: run[3][j], j])[-1])
                      for name, run in runs.items()}  # fmt: skip
            best = max(totals, key=totals.get)
            acts, rew, obs, steps = runs[best]
            k = steps[j]
            sequences = {name: run[0][: run[3][j], j].copy() for name, run in runs.items()}
            self.committed[r] = Committed(int(keys[r]), int(counter[r]), acts[:k, j].copy(),
                                          rew[:k, j].copy(), obs[:k, j].copy(), best, totals,
                                          sequences)  # fmt: skip
            self._key[r] = keys[r]

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        """The next commands of each row's committed sequence, committing where due: a new
        episode, or a row not where its committed sequence left it (a restored snapshot,
        another episode). A row whose episode has ended holds its last commands."""
        obs = np.asarray(observation)
        src = self.src
        B = src.B
        if obs.shape[: obs.ndim - 1] != ((B,) if obs.ndim == 2 else ()):
            raise ValueError(f"the oracle's env has {B} row(s); observation shape {obs.shape}")
        if len(self.committed) != B:
            self.reset()
        counter = src.steps()
        ended = (counter > 0) & src.ended()
        due = (counter == 0) | (src.noise_keys() != self._key) | (counter != self._next)
        if episode_start is not None:
            due |= np.broadcast_to(np.asarray(episode_start, dtype=bool), (B,))
        rows = np.flatnonzero(due & ~ended)
        if rows.size:
            self._commit(rows)
        action = src.held_commands() * 2.0 - 1.0  # an ended row's last commands
        for r in np.flatnonzero(~ended):
            c = self.committed[r]
            action[r] = c.actions[counter[r] - c.start]
        self._next = np.where(ended, self._next, counter + 1)
        return (action if obs.ndim == 2 else action[0]), None
