"""Construction options shared by SteamTempEnv and SteamTempVectorEnv."""

from __future__ import annotations

from typing import Any

from steamtemp_gym import plants, scenarios
from steamtemp_gym.envs.core import Core
from steamtemp_gym.envs.plant_rows import PlantRowsCore
from steamtemp_gym.plants import perturb
from steamtemp_gym.plants.base import Plant
from steamtemp_gym.rewards import RewardConfig

OPTIONS = ("scenario", "render_mode", "reward", "params", "plant_randomization")
RENDER_MODES = (None, "rgb_array")


def build(plant_id: str, options: dict[str, Any]) -> tuple[Plant, Any, RewardConfig, str | None]:
    """Validate the options of ``gym.make``: (plant, scenario or "random", reward, render_mode).

    Raises:
        ValueError: unknown option, scenario, render mode, reward key, plant parameter or
            ``plant_randomization`` value.
    """
    unknown = sorted(set(options) - set(OPTIONS))
    if unknown:
        raise ValueError(
            f"unknown option(s) {unknown} for {plant_id}; valid options: {list(OPTIONS)}"
        )
    render_mode = options.get("render_mode")
    if render_mode not in RENDER_MODES:
        raise ValueError(f"unknown render_mode {render_mode!r}; valid: {list(RENDER_MODES)}")
    params = options.get("params") or {}
    if not isinstance(params, dict):
        raise ValueError(f"params must be a dict of plant parameters, got {type(params).__name__}")
    names = [k for k in params if not isinstance(k, str)]
    if names:
        raise ValueError(f"plant parameter names must be strings, got {names[0]!r}")
    plant = plants.make(plant_id, **params)
    randomization(plant_id, options)
    spec = options.get("scenario", scenarios.RANDOM)
    scenario = scenarios.resolve(spec, plant_id)
    reward = RewardConfig.from_options(options.get("reward"))
    return plant, scenario, reward, render_mode


def randomization(plant_id: str, options: dict[str, Any]) -> dict[str, tuple[float, float]] | None:
    """The factor range per parameter group of the ``plant_randomization`` option, or None
    without it (steamtemp_gym/plants/perturb.py).

    Raises:
        ValueError: a bad value (unknown group, a range not 0 < lo <= hi, not numbers).
    """
    return perturb.parse(plant_id, options.get("plant_randomization"))


def make_core(plant: Plant, batch: int, reward: RewardConfig, options: dict[str, Any]) -> Any:
    """The env's core: a Core, or with ``plant_randomization`` a PlantRowsCore drawing each
    row's plant at its resets (envs/plant_rows.py)."""
    ranges = randomization(plant.id, options)
    if ranges is None:
        return Core(plant, batch, reward)
    return PlantRowsCore(plant, batch, reward, ranges, options.get("params") or {})
