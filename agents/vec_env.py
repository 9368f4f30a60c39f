"""The native vector env as a Stable-Baselines3 ``VecEnv``: one compiled kernel call steps
every sub-env, instead of a Python loop over single envs (``DummyVecEnv``) or processes
(``SubprocVecEnv``).

SB3's conventions, as its ``DummyVecEnv`` has them: same-step autoreset (the native env
in ``AutoresetMode.SAME_STEP``), ``dones = terminated | truncated``, float32 rewards, a
list of per-env info dicts where an ended sub-env's holds the ending step's info plus
``terminal_observation`` and ``TimeLimit.truncated``, ``reset_infos``, and seeds set by
:meth:`seed` used at the next reset (sub-env i gets seed + i). A sub-env over the same
seed gives the same transitions as ``DummyVecEnv`` over ``gym.make`` envs, bit for bit
(tests/test_agents_vec_env.py).

``get_attr``/``set_attr``/``env_method`` address the sub-envs through a light view per
row (:class:`SubEnv`: its scenario, plant, signals, spaces); attributes the view lacks
are the vector env's, shared by every row.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvIndices

from agents.moves import VecMoves
from agents.privileged import VecPrivileged
from agents.repeat import VecRepeat
from agents.train_config import ConfigError
from agents.travel_price import VecTravelPrice
from agents.wrappers import VecControllerMemory, VecResidual
from steamtemp_gym.envs.vector_env import SteamTempVectorEnv


class SubEnv:
    """What ``get_attr``/``env_method`` see of sub-env ``index`` of a native vector env."""

    render_mode = None

    def __init__(self, venv: SteamTempVectorEnv, index: int) -> None:
        self._venv, self.index = venv, index
        self.observation_space = venv.single_observation_space
        self.action_space = venv.single_action_space

    @property
    def scenario(self):
        """The scenario of this sub-env's current episode."""
        return self._venv.core.scenario[self.index]

    @property
    def unwrapped(self) -> SubEnv:
        return self

    def current_info(self) -> dict[str, Any]:
        """This sub-env's info now (engineering units), as SteamTempEnv reports it."""
        return self._venv.core.info_row(self.index)

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_"):
            raise AttributeError(name)
        return getattr(self._venv, name)


class NativeVecEnv(VecEnv):
    """SB3 VecEnv over ``SteamTempVectorEnv`` (module docstring).

    Args:
        env_id: Registered id.
        n_envs: Number of sub-envs.
        **options: As for ``gym.make`` (``scenario``, ``reward``, ``params``).
    """

    def __init__(self, env_id: str, n_envs: int = 1, **options: Any) -> None:
        if env_id not in gym.registry:
            raise ValueError(f"unknown env id {env_id!r}")
        venv = gym.make_vec(
            env_id,
            num_envs=n_envs,
            vectorization_mode="vector_entry_point",
            autoreset_mode=AutoresetMode.SAME_STEP,
            **options,
        )
        self.venv: SteamTempVectorEnv = venv.unwrapped
        self.views = [SubEnv(self.venv, i) for i in range(n_envs)]
        super().__init__(n_envs, self.venv.single_observation_space, self.venv.single_action_space)
        self.env_id = env_id
        self._actions: np.ndarray | None = None

    # ------------------------------------------------------------------ stepping
    def reset(self) -> np.ndarray:
        seeds = self._seeds if any(s is not None for s in self._seeds) else None
        opts = self._options[0] if self._options[0] else None
        if any(o != self._options[0] for o in self._options):
            raise ValueError("the native vector env takes one set of reset options for all envs")
        obs, info = self.venv.reset(seed=seeds, options=opts)
        self.reset_infos = _rows(info, self.num_envs)
        self._reset_seeds()
        self._reset_options()
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self):
        obs, rew, term, trunc, info = self.venv.step(self._actions)
        dones = term | trunc
        infos = _rows(info, self.num_envs, full=True)
        if dones.any():
            final = _rows(info["final_info"], self.num_envs)
            for b in np.flatnonzero(dones):
                self.reset_infos[b] = infos[b]
                infos[b] = final[b]
                infos[b]["terminal_observation"] = info["final_obs"][b]
        for row, t in zip(infos, (trunc & ~term).tolist(), strict=True):
            row["TimeLimit.truncated"] = t
        return obs, rew.astype(np.float32), dones, infos

    def close(self) -> None:
        self.venv.close()

    # ------------------------------------------------------------------ sub-env access
    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        return [getattr(self.views[i], attr_name) for i in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        idx = list(self._get_indices(indices))
        if attr_name in vars(self.views[0]):
            for i in idx:
                setattr(self.views[i], attr_name, value)
        elif sorted(idx) == list(range(self.num_envs)):
            setattr(self.venv, attr_name, value)
        else:
            raise ValueError(
                f"{attr_name!r} is shared by every sub-env of the native vector env; "
                "set it for all of them (indices=None)"
            )

    def env_method(
        self, method_name: str, *method_args, indices: VecEnvIndices = None, **method_kwargs
    ) -> list[Any]:
        return [
            getattr(self.views[i], method_name)(*method_args, **method_kwargs)
            for i in self._get_indices(indices)
        ]

    def env_is_wrapped(self, wrapper_class: type, indices: VecEnvIndices = None) -> list[bool]:
        return [False for _ in self._get_indices(indices)]

    def get_images(self) -> Sequence[np.ndarray | None]:
        return [None] * self.num_envs


def _rows(info: dict[str, Any], n: int, full: bool = False) -> list[dict[str, Any]]:
    """Per-env info dicts (Python scalars, as a single env reports them) of info columns;
    a row gets the keys whose ``_key`` mask is True for it (every key: ``full``, known
    from the native env, which reports every row on a step)."""
    keys = [k for k in info if k[0] != "_" and k not in ("final_obs", "final_info")]
    cols = [info[k].tolist() if info[k].ndim == 1 else list(info[k]) for k in keys]
    if full:
        return [dict(zip(keys, vals, strict=True)) for vals in zip(*cols, strict=True)]
    rows: list[dict[str, Any]] = [{} for _ in range(n)]
    for k, col in zip(keys, cols, strict=True):
        for b in np.flatnonzero(info["_" + k]).tolist():
            rows[b][k] = col[b]
    return rows


def make_training_env(
    env_id: str, n_envs: int, seed: int, hp: dict[str, Any], reference_rate: float | None = None
):
    """(VecEnv for training, the native vector env under it, the travel price wrapper or
    None). ``reference_rate``: the reference's travel per second, which a ``travel_price``
    entry needs (agents/travel_price.py)."""
    from stable_baselines3.common.vec_env import VecMonitor, VecNormalize

    base = NativeVecEnv(
        env_id,
        n_envs,
        scenario="random",
        reward=hp.get("train_reward"),
        plant_randomization=hp.get("plant_randomization"),
    )
    price = None
    venv = base
    if hp.get("travel_price") is not None:
        if reference_rate is None:
            raise ConfigError("travel_price needs the reference's travel rate")
        venv = price = VecTravelPrice(venv, base.venv, reference_rate, hp["travel_price"])
    if hp.get("residual_scale") is not None:
        venv = VecResidual(venv, base.venv, hp["residual_scale"], hp.get("residual_base"))
    if hp.get("max_move") is not None or hp.get("action_filter_s") is not None:
        venv = VecMoves(
            venv, base.venv, hp.get("max_move"), hp.get("action_filter_s"), hp.get("tied_valves")
        )
    if hp["env_wrapper"] is not None:
        venv = VecControllerMemory(venv, base.venv, **hp["env_wrapper"])
    if hp.get("action_repeat", 1) > 1:
        venv = VecRepeat(venv, hp["action_repeat"], incremental=hp.get("max_move") is not None)
    if hp.get("privileged_critic"):
        venv = VecPrivileged(venv, base.venv)
    venv = VecMonitor(venv)
    if hp["normalize"]:
        kw = hp["normalize"] if isinstance(hp["normalize"], dict) else {}
        venv = VecNormalize(venv, gamma=hp.get("gamma", 0.99), **kw)
    venv.seed(seed)
    return venv, base.venv, price
