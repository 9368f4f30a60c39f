"""Incremental and filtered actions for agents: the agent's action is a bounded valve move
per control interval, or a valve position through an output filter (:class:`LowPassState`),
not a valve position applied as it is.

An agent acting on positions can stroke a valve end to end from one interval to the next;
exploration noise then shows up one for one as valve travel. In the incremental mode (the
velocity form of a DCS output block, and pc-gym's ``a_delta`` action space) the agent's
action a in [-1, 1] per actuator moves the command by at most ``max_move`` (fraction of
full stroke) per interval:

    u_k = clip(u_(k-1) + max_move * clip(a_k, -1, 1), 0, 1),

and the env receives u_k in its own action units (2 u - 1). The command starts at the
valve opening observed at the episode's start (bumpless), and is held per row as the
agent's own state; nothing of the plant is revealed. With ``max_move`` m the valve travel
is at most m per actuator and interval, so a budget of travel is a budget of m.

Tied valves (``tied_valves``, e.g. BoilerTurbineMIMO's two spray stages in series): the
agent has one action for the named valves, which move together (incremental: by the same
move, so the split they start with is held; filtered: to the same position). A direction
of the actuators that the scored temperatures barely see (the two sprays in anti-phase)
is then not the agent's to explore.

One batched implementation (:class:`MoveState`) serves the training wrapper
(:class:`VecMoves`, an SB3 ``VecEnvWrapper``) and the shipped agents' Policy
(agents/policy.py), so that what the agent trained with holds at evaluation.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvWrapper

from baselines.loops import observation_layout


def check_max_move(max_move: Any) -> float:
    """``max_move`` as a float in (0, 1]; ValueError otherwise."""
    ok = isinstance(max_move, (int, float)) and not isinstance(max_move, bool)
    if not (ok and np.isfinite(max_move) and 0.0 < max_move <= 1.0):
        raise ValueError(
            f"max_move must be a number in (0, 1] (fraction of stroke per "
            f"control interval), got {max_move!r}"
        )
    return float(max_move)


def n_actions(expand: np.ndarray) -> int:
    """How many actions an agent has, given the action index of each valve (:func:`tie_map`)."""
    return int(expand.max()) + 1


def tie_map(valves: tuple[str, ...], tied_valves: Any = None) -> np.ndarray:
    """The agent's action index of each of ``valves`` when ``tied_valves`` (two or more of
    them, or None) share one action: e.g. valves (sp1, sp2, rgd) with sp1 and sp2 tied give
    [0, 0, 1]. ValueError for names that are not the plant's valves, repeated, or fewer
    than two."""
    if tied_valves is None:
        return np.arange(len(valves))
    tied = list(tied_valves) if isinstance(tied_valves, (list, tuple)) else None
    if (
        tied is None
        or len(tied) < 2
        or len(set(tied)) != len(tied)
        or not all(isinstance(v, str) for v in tied)
    ):
        raise ValueError(
            f"tied_valves must be a list of two or more different valve names, got {tied_valves!r}"
        )
    unknown = [v for v in tied if v not in valves]
    if unknown:
        raise ValueError(f"tied_valves: {unknown} not among the plant's valves {list(valves)}")
    first = min(valves.index(v) for v in tied)
    out, k = np.empty(len(valves), dtype=np.int64), 0
    for j, v in enumerate(valves):
        if v in tied and j != first:
            out[j] = out[first]
        else:
            out[j], k = k, k + 1
    return out


class _Commands:
    """The valve commands an agent's actions drive, per row, started bumpless from the
    openings observed at an episode's start; subclasses define the update. ``tied_valves``:
    valves that share one action (module docstring)."""

    def __init__(self, env: Any, tied_valves: Any = None) -> None:
        names, self._scale, self._center = observation_layout(env)
        valves = tuple(env.unwrapped.plant.valves)
        self.i_valve = [names.index(n) for n in valves]
        expand = tie_map(valves, tied_valves)
        #: how many actions the agent has, and the action index of each actuator where
        #: valves are tied (None: one action per actuator, passed as it is)
        self.n_actions = n_actions(expand)
        self._expand = None if tied_valves is None else expand
        self.u: np.ndarray | None = None  # (rows, actuators) last commands in [0, 1]

    def restart(self, obs: np.ndarray, rows: np.ndarray) -> None:
        """Start ``rows`` (bool mask) from the valve openings of their observations."""
        obs = np.atleast_2d(obs)
        opening = obs[:, self.i_valve] * self._scale[self.i_valve] + self._center[self.i_valve]
        if self.u is None or self.u.shape[0] != obs.shape[0]:
            self.u = np.zeros((obs.shape[0], len(self.i_valve)))
            rows = np.ones(obs.shape[0], dtype=bool)
        self.u[rows] = np.clip(opening[rows], 0.0, 1.0)

    def __call__(self, action: np.ndarray) -> np.ndarray:
        """The env's action (float32, 2 u - 1) for the agent's ``action`` (rows, n)."""
        if self.u is None:
            raise ValueError(
                f"{type(self).__name__}.restart must be called with the first observation"
            )
        a = np.clip(
            np.asarray(action, dtype=np.float64).reshape(self.u.shape[0], self.n_actions), -1.0, 1.0
        )
        self.u = self._next(a if self._expand is None else a[:, self._expand])
        return (2.0 * self.u - 1.0).astype(np.float32)

    def _next(self, a: np.ndarray) -> np.ndarray:
        raise NotImplementedError


class MoveState(_Commands):
    """The commands of an incremental agent, per row (module docstring).

    Args:
        env: The env (or vector env) acted on: its observation layout and valves.
        max_move: Largest move per actuator and control interval (fraction of stroke).
        tied_valves: Valves that share one action (module docstring), or None.
    """

    def __init__(self, env: Any, max_move: float, tied_valves: Any = None) -> None:
        self.max_move = check_max_move(max_move)
        super().__init__(env, tied_valves)

    def _next(self, a: np.ndarray) -> np.ndarray:
        return np.clip(self.u + self.max_move * a, 0.0, 1.0)


class LowPassState(_Commands):
    """The commands of an agent whose position action passes a first-order lag, per row::

        u_k = u_(k-1) + alpha (p_k - u_(k-1)),  p_k = (a_k + 1) / 2,  alpha = dt / (T_f + dt)

    (a DCS output filter of time constant ``T_f``; exploration noise through it is
    low-pass noise: its valve travel falls by about alpha).

    Args:
        env: The env (or vector env) acted on: its observation layout, valves and interval.
        filter_s: The filter's time constant T_f in s.
        tied_valves: Valves that share one action (module docstring), or None.
    """

    def __init__(self, env: Any, filter_s: float, tied_valves: Any = None) -> None:
        self.filter_s = check_filter(filter_s)
        super().__init__(env, tied_valves)
        self.alpha = filter_gain(env.unwrapped.plant.dt_s, self.filter_s)

    def _next(self, a: np.ndarray) -> np.ndarray:
        return self.u + self.alpha * (0.5 * (a + 1.0) - self.u)


def filter_gain(dt_s: float, filter_s: float) -> float:
    """alpha = dt / (T_f + dt): the output filter's gain per control interval."""
    return float(dt_s) / (float(filter_s) + float(dt_s))


def check_filter(filter_s: Any) -> float:
    """``filter_s`` as a float > 0 (s); ValueError otherwise."""
    ok = isinstance(filter_s, (int, float)) and not isinstance(filter_s, bool)
    if not (ok and np.isfinite(filter_s) and filter_s > 0):
        raise ValueError(
            f"action_filter_s must be a number > 0 (the output filter's time "
            f"constant in s), got {filter_s!r}"
        )
    return float(filter_s)


def command_state(
    env: Any, max_move: float | None = None, filter_s: float | None = None, tied_valves: Any = None
) -> _Commands | None:
    """The command state of an agent's action form: incremental (``max_move``), filtered
    positions (``filter_s``) or None (plain positions), with ``tied_valves`` sharing one
    action (either form); ValueError for both forms, or tied valves on plain positions."""
    if max_move is not None and filter_s is not None:
        raise ValueError(
            "an agent's actions are incremental (max_move) or filtered (action_filter_s), not both"
        )
    if max_move is not None:
        return MoveState(env, max_move, tied_valves)
    if filter_s is not None:
        return LowPassState(env, filter_s, tied_valves)
    if tied_valves is not None:
        raise ValueError(
            "tied_valves needs incremental (max_move) or filtered (action_filter_s) actions"
        )
    return None


class VecMoves(VecEnvWrapper):
    """SB3 VecEnv wrapper for an incremental or filtered agent (module docstring,
    :class:`LowPassState`): it takes the agent's actions and passes the env the resulting
    commands; the observation is the env's, the action space the agent's (one action per
    group of tied valves).

    Args:
        venv: The VecEnv to wrap (its observations are the env's raw ones).
        env: The native vector env under it (observation layout and valves).
        max_move: Largest move per actuator and control interval (fraction of stroke).
        filter_s: Instead, the time constant of a filter on position actions (s).
        tied_valves: Valves that share one action (module docstring), or None.
    """

    def __init__(
        self,
        venv: VecEnv,
        env: Any,
        max_move: float | None = None,
        filter_s: float | None = None,
        tied_valves: Any = None,
    ) -> None:
        moves = command_state(env, max_move, filter_s, tied_valves)
        if moves is None:
            raise ValueError("VecMoves needs max_move or filter_s")
        space = venv.action_space
        if moves.n_actions != space.shape[0]:
            space = gym.spaces.Box(-1.0, 1.0, (moves.n_actions,), dtype=space.dtype)
        super().__init__(venv, action_space=space)
        self.moves = moves

    def reset(self) -> np.ndarray:
        obs = self.venv.reset()
        self.moves.restart(obs, np.ones(self.num_envs, dtype=bool))
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self.venv.step_async(self.moves(actions))

    def step_wait(self):
        obs, rew, dones, infos = self.venv.step_wait()
        if np.any(dones):  # auto-reset rows: their observation is the new episode's first
            self.moves.restart(obs, np.asarray(dones, dtype=bool))
        return obs, rew, dones, infos


__all__ = [
    "LowPassState",
    "MoveState",
    "VecMoves",
    "check_filter",
    "check_max_move",
    "command_state",
    "filter_gain",
    "n_actions",
    "tie_map",
]
