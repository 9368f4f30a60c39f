"""Controller memory for agents: the error integral and short histories a memoryless
policy needs to remove a steady offset and to see a dead time, as extra observation
entries (the env's own observation is left as it is, first).

A PI controller integrates the error; an MLP policy acting on one observation cannot,
so under a persistent disturbance it keeps a steady offset (measured on
SupercriticalFSH: -1.36 K without an integral, 0.00 K with it;
docs/notes/agents_search.md). The memory adds:

- the error integral ``I_k = clamp(I_{k-1} + e_k dt / T_i, -L, L)`` (K; ``T_i``:
  ``integral_time_s``, ``L``: ``integral_limit_K``), with two anti-windups as a PI has
  them (e.g. Astrom and Hagglund, Advanced PID Control, ISA, 2006, sec. 3.5): clamping at
  +-L, and conditional integration: while every valve sits at a stop (opening <= 0.5 %
  or >= 99.5 %) the integral may only shrink; it is observed as ``I / e_scale`` (the
  error's own normalization, ``signals``);
- with ``secondary_integral``, the same integral of the error of each secondary scored
  temperature (``Plant.secondary``, e.g. BoilerTurbineMIMO's reheat: its setpoint minus
  its measurement), observed in that measurement's normalization: a plant that scores two
  temperatures needs an integral per temperature to remove both offsets;
- the error and the valve openings (``history_signals: error_valves``) or every observed
  signal (``observation``: inner temperatures, load, flows, the measured disturbances)
  ``history`` samples back, ``history_stride`` control steps apart (oldest last),
  normalized as the env normalizes them; agents/horizons.py gives the stride at which
  they span the plant's dead time plus lag;
- with ``rates``, the per-minute changes of the load demand and of the setpoint, filtered
  with a lag of ``rate_filter_s`` (what a load feed-forward acts on).

One batched implementation (:class:`MemoryState`) serves three front ends that give the
same observations: :class:`ControllerMemory` (a ``gymnasium.Wrapper``, hence RL Zoo's
``env_wrapper``), :class:`VecControllerMemory` (an SB3 ``VecEnvWrapper``, which also
extends ``terminal_observation``) and the shipped agents' Policy (agents/policy.py). The
state (integral, histories) lives in the wrapper; nothing of the plant is revealed.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvWrapper

from agents.memory import MEMORY_WRAPPER, MemoryConfig, memory_options  # noqa: F401 - re-exported
from agents.residual import ResidualBase
from baselines.loops import observation_layout
from steamtemp_gym.signals import OBS_LIMIT

#: Valve openings within this distance of 0 or 1 are at a stop (conditional integration).
STOP_MARGIN = 0.005


class MemoryState:
    """The memory of a batch of rows for one env's observation layout.

    Args:
        env: The env (single or vector) whose observations it extends.
        config: What to add.
    """

    def __init__(self, env: Any, config: MemoryConfig) -> None:
        names, scale, center = observation_layout(env)
        plant = env.unwrapped.plant
        self.config = config
        self.i_err = names.index("error_K")
        self.e_scale = float(scale[self.i_err])
        self.i_valve = np.array([names.index(v) for v in plant.valves])
        self.v_scale, self.v_center = scale[self.i_valve], center[self.i_valve]
        self.dt = plant.dt_s
        self.n_obs = len(names)
        # secondary scored temperatures: (observation index, setpoint) of each measurement
        second = (
            [(_measured(names, n), sp) for n, sp in plant.secondary]
            if config.secondary_integral
            else []
        )
        self.i_sec = np.array([i for i, _ in second], dtype=int)
        self.sp_sec = np.array([sp for _, sp in second], dtype=float)
        self.sec_scale, self.sec_center = scale[self.i_sec], center[self.i_sec]
        # every integral is observed in its own error's normalization
        self.i_scale = np.concatenate([[self.e_scale], self.sec_scale])
        self.n_extra = config.n_extra(len(self.i_valve), len(second), self.n_obs)
        self.i_sample = (
            np.arange(self.n_obs)
            if config.history_signals == "observation"
            else np.concatenate([[self.i_err], self.i_valve]).astype(int)
        )
        # rates: the filtered per-minute change of the load demand and of the setpoint, in
        # their observations' normalization
        self.i_rate = np.array([names.index("load_demand"), names.index("setpoint_C")])
        self.a_rate = float(np.exp(-self.dt / config.rate_filter_s))
        self.integral_step = self.dt / config.integral_time_s
        self._integral = np.zeros((0, 1 + len(second)))
        # the history as a ring of the last `keep` samples of every row (rows, keep, signals):
        # the newest at `_head`, the one j steps back at (_head - j) mod keep
        self.keep = config.history * config.history_stride + 1
        lags = config.history_stride * np.arange(1, config.history + 1)
        self._past = (np.arange(self.keep)[:, None] - lags) % self.keep  # per head
        self._buf = np.zeros((0, self.keep, self.i_sample.size))
        self._head = 0
        self._rate = np.zeros((0, 2))
        self._last = np.zeros((0, 2))

    def extend_space(self, space: gym.spaces.Box) -> gym.spaces.Box:
        """The observation space with the memory's entries appended (last axis)."""
        shape = (*space.shape[:-1], space.shape[-1] + self.n_extra)
        return gym.spaces.Box(-OBS_LIMIT, OBS_LIMIT, shape=shape, dtype=space.dtype)

    def __call__(self, obs: np.ndarray, restart: np.ndarray | None = None) -> np.ndarray:
        """The extended observations of a batch ``obs`` (rows, n_obs) after this step;
        rows flagged in ``restart`` (and every row of a new batch size) start afresh."""
        obs = np.asarray(obs)
        n = obs.shape[0]
        c = self.config
        if self._integral.shape[0] != n:
            self._integral = np.zeros((n, 1 + self.i_sec.size))
            self._buf = np.zeros((n, self.keep, self.i_sample.size))
            self._rate, self._last = np.zeros((n, 2)), np.zeros((n, 2))
            restart = np.ones(n, dtype=bool)
        sample = obs[:, self.i_sample]
        now = obs[:, self.i_rate]
        if restart is not None and restart.any():
            self._integral[restart] = 0.0
            self._buf[restart] = sample[restart, None, :]
            self._rate[restart] = 0.0
            self._last[restart] = now[restart]
        parts = [obs]
        if c.integral:
            e_K = obs[:, self.i_err : self.i_err + 1] * self.e_scale
            if self.i_sec.size:
                measured = obs[:, self.i_sec] * self.sec_scale + self.sec_center
                e_K = np.concatenate([e_K, self.sp_sec - measured], axis=1)
            step = e_K * self.integral_step
            opening = obs[:, self.i_valve] * self.v_scale + self.v_center
            at_stop = ((opening <= STOP_MARGIN) | (opening >= 1.0 - STOP_MARGIN)).all(axis=1)
            if at_stop.any():
                grows = np.abs(self._integral + step) > np.abs(self._integral)
                step[at_stop[:, None] & grows] = 0.0
            self._integral = np.clip(self._integral + step, -c.integral_limit_K, c.integral_limit_K)
            parts.append(self._integral / self.i_scale)
        if c.rates:
            self._rate = self.a_rate * self._rate + (1.0 - self.a_rate) * (now - self._last) * (
                60.0 / self.dt
            )
            self._last = now
            parts.append(self._rate)
        if c.history:
            self._head = (self._head + 1) % self.keep
            self._buf[:, self._head] = sample
            parts.append(self._buf[:, self._past[self._head]].reshape(n, -1))
        return np.concatenate(parts, axis=1).astype(obs.dtype, copy=False)

    def state(self) -> tuple[np.ndarray, ...]:
        """A copy of (integral, history ring, rates, last rate inputs, the ring's head) (to
        extend a terminal observation)."""
        return (
            *(a.copy() for a in (self._integral, self._buf, self._rate, self._last)),
            self._head,
        )

    def set_state(self, state: tuple) -> None:
        *arrays, self._head = state
        self._integral, self._buf, self._rate, self._last = (a.copy() for a in arrays)


def _measured(names: list[str], true_name: str) -> int:
    """Index of the observed measurement of a secondary temperature ``<x>_C``
    (``<x>_meas_C``)."""
    meas = true_name[: -len("_C")] + "_meas_C" if true_name.endswith("_C") else true_name
    if meas not in names:
        raise ValueError(
            f"no measurement {meas!r} of the secondary temperature "
            f"{true_name!r} among the observations {names}"
        )
    return names.index(meas)


class ControllerMemory(gym.Wrapper):
    """Gymnasium wrapper adding the controller memory to a single env's observation.

    Usable from RL Zoo's YAML: ``env_wrapper: [{agents.wrappers.ControllerMemory:
    {integral_time_s: 60}}]``. Keyword arguments: the fields of :class:`MemoryConfig`.
    """

    def __init__(self, env: gym.Env, **kwargs: Any) -> None:
        super().__init__(env)
        self.memory = MemoryState(env, MemoryConfig.from_kwargs(kwargs))
        self.observation_space = self.memory.extend_space(env.observation_space)

    def reset(self, **kwargs: Any):
        obs, info = self.env.reset(**kwargs)
        return self.memory(obs[None], np.ones(1, dtype=bool))[0], info

    def step(self, action: Any):
        obs, r, term, trunc, info = self.env.step(action)
        return self.memory(obs[None])[0], r, term, trunc, info


class VecControllerMemory(VecEnvWrapper):
    """SB3 VecEnv wrapper adding the controller memory (same-step autoreset aware: an
    ended sub-env's ``terminal_observation`` is extended with its final memory, and its
    memory restarts on the new episode's first observation)."""

    def __init__(self, venv: VecEnv, env: Any, **kwargs: Any) -> None:
        self.memory = MemoryState(env, MemoryConfig.from_kwargs(kwargs))
        super().__init__(venv, observation_space=self.memory.extend_space(venv.observation_space))

    def reset(self) -> np.ndarray:
        obs = self.venv.reset()
        return self.memory(obs, np.ones(obs.shape[0], dtype=bool))

    def step_wait(self):
        obs, rew, dones, infos = self.venv.step_wait()
        if dones.any():
            before = self.memory.state()
            final = obs.copy()
            ended = np.flatnonzero(dones)
            for b in ended:
                final[b] = infos[b]["terminal_observation"]
            extended = self.memory(final)
            for b in ended:
                infos[b]["terminal_observation"] = extended[b]
            self.memory.set_state(before)
        return self.memory(obs, dones), rew, dones, infos


class VecResidual(VecEnvWrapper):
    """SB3 VecEnv wrapper for a residual agent (agents/residual.py): the env receives the
    base controller's action plus ``scale`` times the agent's, clipped to [-1, 1]; in the
    observed form (``base`` named) the agent's observation ends with the base's action
    of the step it acts in (an ended row's ``terminal_observation`` with the base action
    of its last step)."""

    def __init__(self, venv: VecEnv, env: Any, scale: float, base: str | None = None) -> None:
        self.base = ResidualBase(env, scale, base)
        super().__init__(venv, observation_space=self.base.extend_space(venv.observation_space))

    def reset(self) -> np.ndarray:
        obs = self.venv.reset()
        self.base.step(obs, np.ones(self.num_envs, dtype=bool))
        return self.base.extend(obs)

    def step_async(self, actions: np.ndarray) -> None:
        self.venv.step_async(self.base.combine(actions))

    def step_wait(self):
        obs, rew, dones, infos = self.venv.step_wait()
        if self.base.observed and dones.any():
            last = self.base.action
            for b in np.flatnonzero(dones):
                final = np.asarray(infos[b]["terminal_observation"])[None]
                infos[b]["terminal_observation"] = self.base.extend(final, last[[b]])[0]
        self.base.step(obs, np.asarray(dones, dtype=bool))
        return self.base.extend(obs), rew, dones, infos
