"""Action repeat: the agent decides every ``k`` control intervals, as a DCS block with a
scan period of ``k`` intervals does, and between its decisions its output is held.

Held means: a valve position (plain or through the output filter, agents/moves.py) stays
the agent's last one, and the filter keeps running on it every interval; an incremental
agent's move is made once per decision, so its command is held (a zero move in the other
intervals); a residual agent's correction stays, added to its base controller's action of
every interval. With ``k`` decisions fewer, the agent's transitions span ``k`` intervals:
the discount and the GAE window per decision are those of ``k`` intervals
(agents/horizons.py), the exploration noise is drawn once per decision, and a deterministic
actor that would dither on the measurement noise moves an incremental command at most
``max_move`` per decision instead of per interval.

The controller memory and every wrapper below it still see every interval (the error
integral, the history); the agent sees the observation of its decision intervals.

One rule (:func:`held`) serves the training wrapper (:class:`VecRepeat`, an SB3
``VecEnvWrapper`` over the controller memory) and the shipped agents' Policy
(agents/policy.py, :class:`Decisions`), so that what the agent trained with holds at
evaluation. In training a row whose episode ends inside a decision starts its next
episode on the held action for the rest of that decision, and those intervals' rewards
are not the agent's (a scenario's length is a multiple of ``k`` intervals in every shipped
entry, so this happens only after a trip).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvWrapper

#: Largest action repeat accepted (intervals per decision).
REPEAT_MAX = 100


def check_repeat(k: Any) -> int:
    """``k`` (control intervals per decision) as an int in [1, :data:`REPEAT_MAX`];
    ValueError otherwise."""
    if not (isinstance(k, (int, np.integer)) and not isinstance(k, bool) and 1 <= k <= REPEAT_MAX):
        raise ValueError(
            f"action_repeat must be an integer in [1, {REPEAT_MAX}] (control "
            f"intervals per decision), got {k!r}"
        )
    return int(k)


def held(action: np.ndarray, incremental: bool) -> np.ndarray:
    """The agent's action in the intervals between its decisions (module docstring): zero
    moves for an incremental agent, else the decided action itself."""
    return np.zeros_like(action) if incremental else action


class VecRepeat(VecEnvWrapper):
    """SB3 VecEnv wrapper: each agent action acts for ``k`` control intervals (module
    docstring); the reward is their sum, the observation the last interval's.

    Args:
        venv: The VecEnv to wrap (the controller memory, or the env's observations).
        k: Control intervals per decision.
        incremental: Whether the actions are incremental moves (held as zero moves).
    """

    def __init__(self, venv: VecEnv, k: int, incremental: bool) -> None:
        super().__init__(venv)
        self.k, self.incremental = check_repeat(k), bool(incremental)
        self._actions: np.ndarray | None = None

    def reset(self) -> np.ndarray:
        return self.venv.reset()

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions)

    def step_wait(self):
        total = np.zeros(self.num_envs)
        ended = np.zeros(self.num_envs, dtype=bool)
        last: dict[int, dict] = {}  # the infos of the rows whose episode ended, at its end
        action = self._actions
        for i in range(self.k):
            self.venv.step_async(action)
            obs, rew, dones, infos = self.venv.step_wait()
            live = ~ended  # a row's transition ends with its episode
            total[live] += rew[live]
            for b in np.flatnonzero(live & dones):
                last[int(b)] = infos[b]
            ended |= np.asarray(dones, dtype=bool)
            if i == 0:
                action = held(self._actions, self.incremental)
        return (
            obs,
            total.astype(np.float32),
            ended,
            [last.get(b, info) for b, info in enumerate(infos)],
        )


class Decisions:
    """The decision clock of a Policy with action repeat ``k``, per row: which rows decide
    in this interval (every ``k``-th since a row's episode start), and the action of every
    row in this interval given the decisions (the held action elsewhere, :func:`held`)."""

    def __init__(self, k: int, incremental: bool) -> None:
        self.k, self.incremental = check_repeat(k), bool(incremental)
        self._t: np.ndarray | None = None  # intervals since each row's episode start
        self._last: np.ndarray | None = None  # each row's decided action

    def due(self, restart: np.ndarray) -> np.ndarray:
        """Rows that decide in this interval (bool mask), ``restart`` rows from their
        episode's start."""
        n = len(restart)
        if self._t is None or len(self._t) != n:
            self._t, self._last = np.zeros(n, dtype=np.int64), None
        self._t[restart] = 0
        return self._t % self.k == 0

    def act(self, due: np.ndarray, decided: np.ndarray | None) -> np.ndarray:
        """This interval's actions (rows, n): ``decided`` (the due rows' new actions, in
        row order; None if no row is due) where due, else the held one; the clock moves
        on."""
        if due.any():
            decided = np.asarray(decided, dtype=np.float32).reshape(int(due.sum()), -1)
            if self._last is None:
                self._last = np.zeros((len(due), decided.shape[1]), dtype=np.float32)
            self._last[due] = decided
        elif self._last is None:
            raise ValueError("Decisions.act: no row has decided since its episode's start")
        self._t += 1
        return np.where(due[:, None], self._last, held(self._last, self.incremental))


__all__ = ["REPEAT_MAX", "Decisions", "VecRepeat", "check_repeat", "held"]
