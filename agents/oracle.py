"""The oracle: the score's 1, the best any controller could do on an episode.

Not an admissible controller: a reference, like the frozen valve. When a row's episode
starts it copies the *full internal state* of the row of the env it acts on (plant,
valve and thermowell states, the plant's own random generators, the coloured
heat-absorption disturbance, the noise key and step counter, the scenario with its whole
future: envs/snapshot.py) into rows of a planning core of the same plant object (with
``plant_randomization``, each row's own drawn plant: ``snapshot.planning_core``), chooses
the episode's whole command sequence there on the env's own compiled kernel and reward,
and replays it. Since the noise is counter-based and the scenario is known, the copy's
future is the row's, bit for bit. The observation it is handed is ignored (only its shape
is checked). Its engine (:data:`ENGINES`) is how the sequence is found:

- ``optimum``: the clairvoyant optimum of the episode (agents/optimum/: the whole
  command sequence optimized by L-BFGS-B with the adjoint gradient, with a certificate),
  taken from the package's store where a stored one replays to its stored return
  (agents/optima.py: bit for bit on the machine that stored it, to 1e-9 on another CPU),
  else solved now from the CEM's and the incumbents' sequences,
  saying so on stderr;
- ``cem``: the best of a receding-horizon CEM search and of the :data:`INCUMBENTS`
  (below): a lower bound of the optimum.

The CEM: the cross-entropy method over move-blocked command trajectories (Rubinstein
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
candidates. With them an episode costs about 1.2x the CEM alone. The ``optimum`` engine
starts from all three sequences and keeps the best it finds, so it is never below them.

The CEM's budget (samples, iterations, horizon, knots, replanning interval) was chosen by
measurement: docs/oracle.md, "The receding-horizon CEM", gives the return as the budget doubles.
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import baselines
from agents import optima, optimum
from agents.cem import Budget, Planner
from steamtemp_gym.envs.actions import check_action
from steamtemp_gym.envs.core import Core
from steamtemp_gym.envs.snapshot import copy_rows, env_core, planning_core

#: The causal controllers whose whole-episode command sequences compete with the CEM's
#: (module docstring): the leaderboard's best causal controller and the score's 0.
INCUMBENTS = ("mpc_linear", baselines.INDUSTRIAL_REFERENCE)


#: How the oracle finds each episode's command sequence: ``"optimum"``, the clairvoyant
#: whole-episode optimum (agents/optimum.py; stored ones replayed), or ``"cem"``, the
#: receding-horizon search alone (a lower bound of the optimum, for quick looks).
ENGINES = ("optimum", "cem")
#: The engine of the leaderboard's oracle unless ``--oracle`` says otherwise.
DEFAULT_ENGINE = "optimum"


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
    """The clairvoyant optimum of each episode (engine ``optimum``, the default) or the
    receding-horizon CEM (``cem``) on the env's own kernel, at least the causal controllers
    of :data:`INCUMBENTS` on every episode (module docstring).

    Args:
        env: The env (single or native vector env) whose rows it acts on and reads.
        budget: The CEM's budget (agents/cem.py: :class:`Budget`).
        incumbents: Baseline names whose closed-loop episodes compete with the CEM's
            (default :data:`INCUMBENTS`; ``()``: the CEM alone).
        engine: ``"optimum"`` or ``"cem"`` (:data:`ENGINES`; default
            :data:`DEFAULT_ENGINE`).
        store: Where the ``optimum`` engine finds stored optima (agents/optima.py).
    """

    def __init__(
        self,
        env: Any,
        budget: Budget | None = None,
        incumbents: tuple[str, ...] = INCUMBENTS,
        engine: str = DEFAULT_ENGINE,
        store: Path = optima.STORE,
    ) -> None:
        try:
            src = env_core(env)
        except ValueError as exc:
            raise ValueError(f"the oracle acts on a steamtemp_gym env: {exc}") from None
        unknown = [n for n in incumbents if n not in baselines.NAMES]
        if isinstance(incumbents, str) or unknown:
            raise ValueError(
                f"oracle incumbents must be a tuple of baseline names "
                f"({', '.join(baselines.NAMES)}), got {incumbents!r}"
            )
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

    def _keep(
        self, r: int, j: int, run: tuple, source: str, returns: dict, sequences: dict
    ) -> None:
        """Commit row r to row j of ``run`` (a :func:`rollout`)."""
        acts, rew, obs, steps = run
        k = steps[j]
        self.committed[r] = Committed(
            int(self.src.noise_keys()[r]),
            int(self.src.steps()[r]),
            acts[:k, j].copy(),
            rew[:k, j].copy(),
            obs[:k, j].copy(),
            source,
            returns,
            sequences,
        )
        self._key[r] = self.src.noise_keys()[r]

    def _stored(self, rows: np.ndarray) -> np.ndarray:
        """Commit the rows at their episode's start whose stored optimum (agents/optima.py)
        replays to its stored return (``optima.replays``); returns the other rows."""
        keys, counter = self.src.noise_keys(), self.src.steps()
        found = {}
        for r in rows.tolist():
            record = (
                None
                if counter[r]
                else optima.find(self.src.plant.id, self.src.scenario[r], int(keys[r]), self.store)
            )
            a = None if record is None else optima.actions(record, self.store)
            if a is not None:
                found[r] = (record, a)
        if not found:
            return rows
        run = self._play(np.array(list(found)), [a for _, a in found.values()])
        for j, (r, (record, a)) in enumerate(found.items()):
            total = float(np.cumsum(run[1][: run[3][j], j])[-1])  # summed in order
            if optima.replays(total, record["return"]):
                self._keep(
                    r, j, run, "stored optimum", {"stored optimum": total}, {"stored optimum": a}
                )
            else:
                print(
                    f"oracle: the stored optimum of {self.src.plant.id} "
                    f"{record['scenario']} seed {record['seed']} replays to {total!r}, not "
                    f"its stored {record['return']!r} (the plant's code has changed): "
                    "solving it anew",
                    file=sys.stderr,
                    flush=True,
                )
        return np.array(
            [
                r
                for r in rows.tolist()
                if self.committed[r] is None
                or self._key[r] != keys[r]
                or self.committed[r].start != counter[r]
            ],
            dtype=np.int64,
        )

    def _solve(self, r: int) -> None:
        """Commit row r to the whole-episode optimum from its state (agents/optimum.py),
        warm started by the sequences of its CEM commit, saying so on stderr."""
        c = self.committed[r]
        scenario = self.src.scenario[r]
        zero = c.returns.get(baselines.INDUSTRIAL_REFERENCE, min(c.returns.values()))
        print(
            f"oracle: solving the clairvoyant optimum of {self.src.plant.id} "
            f"{scenario.name!r} (noise key {c.key}) from step {c.start}: a few minutes of "
            "one core",
            file=sys.stderr,
            flush=True,
        )
        t0 = time.process_time()
        out = optimum.solve(optimum.episode(self.src, r), c.sequences, c.returns, zero)
        run = self._play(np.array([r]), [out["actions"]])
        returns = {**c.returns, "optimum": out["return"]}
        self._keep(r, 0, run, "optimum", returns, {**c.sequences, "optimum": out["actions"]})
        print(
            f"oracle: done in {time.process_time() - t0:.0f} s of CPU: return "
            f"{out['return']:.4f} (CEM {c.returns.get('cem', float('nan')):.4f}); certificate "
            f"{'holds' if out['certificate']['holds'] else 'fails'}",
            file=sys.stderr,
            flush=True,
        )

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
            runs[name] = rollout(
                shadow,
                lambda obs, first, p=policy: p.predict(
                    obs, episode_start=np.full(n, first), deterministic=True
                )[0],
            )
        for j, r in enumerate(rows):
            # summed in order, as the evaluation adds; a tie keeps the CEM's
            totals = {
                name: float(np.cumsum(run[1][: run[3][j], j])[-1]) for name, run in runs.items()
            }
            best = max(totals, key=totals.get)
            acts, rew, obs, steps = runs[best]
            k = steps[j]
            sequences = {name: run[0][: run[3][j], j].copy() for name, run in runs.items()}
            self.committed[r] = Committed(
                int(keys[r]),
                int(counter[r]),
                acts[:k, j].copy(),
                rew[:k, j].copy(),
                obs[:k, j].copy(),
                best,
                totals,
                sequences,
            )
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
