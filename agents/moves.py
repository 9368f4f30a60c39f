"""Incremental actions for agents: the agent's action is a bounded valve move per control
interval, not a valve position.

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

One batched implementation (:class:`MoveState`) serves the training wrapper
(:class:`VecMoves`, an SB3 ``VecEnvWrapper``) and the shipped agents' Policy
(agents/policy.py), so that what the agent trained with holds at evaluation.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvWrapper

from baselines.loops import observation_layout


def check_max_move(max_move: Any) -> float:
    """``max_move`` as a float in (0, 1]; ValueError otherwise."""
    ok = isinstance(max_move, (int, float)) and not isinstance(max_move, bool)
    if not (ok and np.isfinite(max_move) and 0.0 < max_move <= 1.0):
        raise ValueError(f"max_move must be a number in (0, 1] (fraction of stroke per "
                         f"control interval), got {max_move!r}")  # fmt: skip
    return float(max_move)


class MoveState:
    """The commands of an incremental agent, per row (module docstring).

    Args:
        env: The env (or vector env) acted on: its observation layout and valves.
        max_move: Largest move per actuator and control interval (fraction of stroke).
    """

    def __init__(self, env: Any, max_move: float) -> None:
        self.max_move = check_max_move(max_move)
        names, self._scale, self._center = observation_layout(env)
        self.i_valve = [names.index(n) for n in env.unwrapped.plant.valves]
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
        """The env's action (float32, 2 u - 1) for the agent's moves ``action`` (rows, n)."""
        if self.u is None:
            raise ValueError("MoveState.restart must be called with the first observation")
        a = np.clip(np.asarray(action, dtype=np.float64).reshape(self.u.shape), -1.0, 1.0)
        self.u = np.clip(self.u + self.max_move * a, 0.0, 1.0)
        return (2.0 * self.u - 1.0).astype(np.float32)


class VecMoves(VecEnvWrapper):
    """SB3 VecEnv wrapper for an incremental agent (module docstring): it takes the agent's
    moves and passes the env the resulting commands; the observation is the env's.

    Args:
        venv: The VecEnv to wrap (its observations are the env's raw ones).
        env: The native vector env under it (observation layout and valves).
        max_move: Largest move per actuator and control interval (fraction of stroke).
    """

    def __init__(self, venv: VecEnv, env: Any, max_move: float) -> None:
        super().__init__(venv)
        self.moves = MoveState(env, max_move)

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


__all__ = ["MoveState", "VecMoves", "check_max_move"]
