"""SteamTempEnv: one Gymnasium env for every plant (a batch of one of envs/core.py).

Observation: the plant's measured signals (noisy where a thermocouple reads
them), the setpoint, the control error and the load demand, each normalized as
``env.unwrapped.signals`` describes. Action: valve/damper commands in [-1, 1]
(opening (a + 1)/2). Reward: rewards.py. ``terminated`` when the true outlet
temperature leaves the plant's trip band (``plant.trip_band_K`` around the
setpoint: superheater/turbine protection); ``truncated`` at the end of the
scenario. ``info`` carries physical values in engineering units and the constraint
cost of safe RL (``info["cost"]``, envs/cost.py).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from steamtemp_gym import scenarios as sc
from steamtemp_gym.checks import is_integer, key_list
from steamtemp_gym.envs import options as opts
from steamtemp_gym.envs import snapshot as snap_
from steamtemp_gym.envs.actions import check_action
from steamtemp_gym.envs.core import Core
from steamtemp_gym.envs.cost import cost_limit
from steamtemp_gym.envs.render import TrendDisplay, spray_range
from steamtemp_gym.signals import OBS_LIMIT


def draw_episode(
    rng: np.random.Generator, scenario: Any, duration_s: float
) -> tuple[sc.Scenario, int]:
    """The scenario and noise key of a new episode, drawn from one env's generator."""
    if scenario == sc.RANDOM:
        scenario = sc.random_scenario(rng, duration_s)
    key = int(rng.integers(0, 2**63 - 1, dtype=np.int64))
    return scenario, key


def scenario_option(
    options: dict | None, default: Any, plant_id: str, other: tuple[str, ...] = ()
) -> Any:
    """The scenario of a reset: ``options["scenario"]`` resolved, else ``default``.

    Raises:
        ValueError: an unknown option (``other`` are the caller's own) or scenario.
    """
    if options is not None and not isinstance(options, dict):
        raise ValueError(f"reset() options must be a dict or None, got {type(options).__name__}")
    unknown = key_list(set(options or {}) - {"scenario", *other})
    if unknown:
        raise ValueError(f"unknown reset option(s) {unknown}; valid: {['scenario', *other]}")
    if options and "scenario" in options:
        return sc.resolve(options["scenario"], plant_id)
    return default


def spaces(core: Core) -> tuple[gym.spaces.Box, gym.spaces.Box]:
    """Single-env observation and action spaces."""
    n_obs = core.obs.shape[1]
    obs_space = gym.spaces.Box(-OBS_LIMIT, OBS_LIMIT, shape=(n_obs,), dtype=np.float64)
    act_space = gym.spaces.Box(-1.0, 1.0, shape=(core.plant.n_u,), dtype=np.float32)
    return obs_space, act_space


class SteamTempEnv(gym.Env):
    """Superheated steam temperature control of one plant (see module docstring).

    Args:
        plant_id: Registered id whose plant to simulate.
        **options: ``scenario`` (a name, ``heldout:<name>``, a YAML path, a Scenario or
            "random": steamtemp_gym.scenarios.resolve; default "random"), ``render_mode``
            (None or "rgb_array"), ``reward`` (dict of RewardConfig overrides), ``params``
            (dict of plant parameter overrides), ``plant_randomization`` (True or
            ``{group: (lo, hi)}``: a plant drawn per episode from its seed,
            steamtemp_gym/plants/perturb.py; ``env.unwrapped.episode_plant`` is the
            current one).

    ``reset(options={"scenario": spec})`` runs that episode under ``spec`` (the same
    forms); later resets without it return to the env's own scenario.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}

    def __init__(self, plant_id: str, **options: Any) -> None:
        plant, self._scenario_spec, reward_cfg, self.render_mode = opts.build(plant_id, options)
        #: The plant parameters given in the ``params`` option (the rest are the defaults).
        self.params_overrides = dict(options.get("params") or {})
        self.plant = plant
        self.core = opts.make_core(plant, 1, reward_cfg, options)
        self.signals = self.core.signals
        self.observation_space, self.action_space = spaces(self.core)
        self._shape = (1, plant.n_u)
        self._display = None  # the trend display of render_mode="rgb_array" (envs/render.py)
        self._needs_reset = True

    @property
    def episode_plant(self) -> Any:
        """The plant of the current episode: :attr:`plant`, or with ``plant_randomization``
        the one drawn at the last reset."""
        return self.core.row_plant(0)

    @property
    def scenario(self) -> sc.Scenario | None:
        """The scenario of the current episode."""
        return self.core.scenario[0]

    @property
    def cost_limit(self) -> float:
        """The default limit of the current episode's summed ``info["cost"]``
        (envs/cost.py, docs/safe_rl.md).

        Raises:
            ValueError: no reset() yet.
        """
        if self.core.scenario[0] is None:
            raise ValueError("call reset() before cost_limit (it depends on the scenario)")
        return cost_limit(self.core.scenario[0], self.plant.dt_s)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start an episode (module docstring); all or nothing: if it cannot start (a
        ValueError: a scenario or drawn plant that cannot hold its start), the env, its
        episode and its generator are as before."""
        if seed is not None:  # the vector env's rule: an integer >= 0, numpy's too, no bool
            if not (is_integer(seed) and seed >= 0):
                raise ValueError(
                    f"seed must be None or a non-negative integer, got "
                    f"{str(seed)[:100]!r} ({type(seed).__name__})"
                )
            seed = int(seed)
        spec = scenario_option(options, self._scenario_spec, self.plant.id)
        rng, rng_seed = self._np_random, self._np_random_seed
        rng_state = None if rng is None else rng.bit_generator.state
        super().reset(seed=seed)
        try:
            scenario, key = draw_episode(self.np_random, spec, self.plant.default_duration_s)
            self.core.reset_rows([0], [(scenario, key)])
        except Exception:
            self._np_random, self._np_random_seed = rng, rng_seed
            if rng is not None:
                rng.bit_generator.state = rng_state
            raise
        self._needs_reset = False
        info = self._info()
        self._display = None
        if self.render_mode:
            title = f"{self.plant.id}  scenario: {getattr(scenario, 'name', '')}"
            names = tuple(
                (s.description or s.name).removesuffix(" command") for s in self.signals.action
            )
            self._display = TrendDisplay(
                title,
                scenario.duration_s,
                info,
                spray_range(self.plant),
                names,
                self.plant.secondary,
            )
        return self.core.obs[0].copy(), info

    def step(self, action):
        if self._needs_reset:
            raise RuntimeError("call reset() before step() (and after the episode ends)")
        self.core.step(check_action(action, self._shape, single=True))
        s = self.core.state
        r, terminated, truncated = s.reward.item(0), s.trip.item(0) != 0, s.truncated.item(0)
        self._needs_reset = terminated or truncated
        info = self._info()
        if self._display is not None:
            self._display.add(info)
        return s.obs[0].copy(), r, terminated, truncated, info

    def _info(self) -> dict[str, Any]:
        return self.core.info_row(0)

    def snapshot(self) -> snap_.Snapshot:
        """A copy of the episode's full state (envs/snapshot.py), to :meth:`restore` here
        later or into rows of the native vector env.

        Raises:
            ValueError: no reset() yet.
        """
        if self.core.scenario[0] is None:
            raise ValueError("call reset() before snapshot()")
        return snap_.take(
            self.core, np.zeros(1, dtype=np.int64), [self.np_random], np.array([self._needs_reset])
        )

    def restore(self, snapshot: snap_.Snapshot) -> np.ndarray:
        """Continue from ``snapshot`` (one row, of this plant and parameters): the episode
        goes on bit for bit as the snapshot's would. Returns its current observation.

        Raises:
            ValueError: a snapshot of another plant or parameter set, or of several rows;
                nothing is changed.
        """
        plan = snap_.check(self.core, snapshot, [0])
        rngs, waiting = [self._np_random], np.zeros(1, dtype=bool)
        snap_.put(self.core, snapshot, plan, rngs, waiting)
        self._np_random = rngs[0]
        self._needs_reset = bool(waiting[0])
        self._display = None
        return self.core.obs[0].copy()

    def render(self):
        if self.render_mode != "rgb_array":
            return None
        if self._display is None:
            raise RuntimeError("call reset() before render()")
        return self._display.frame()
