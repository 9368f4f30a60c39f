"""Construction options shared by SteamTempEnv and SteamTempVectorEnv."""

from __future__ import annotations

from typing import Any

from steamtemp_gym import plants, scenarios
from steamtemp_gym.plants.base import Plant
from steamtemp_gym.rewards import RewardConfig

OPTIONS = ("scenario", "render_mode", "reward", "params")
RENDER_MODES = (None, "rgb_array")


def build(plant_id: str, options: dict[str, Any]) -> tuple[Plant, Any, RewardConfig, str | None]:
    """Validate the options of ``gym.make``: (plant, scenario or "random", reward, render_mode).

    Raises:
        ValueError: unknown option, scenario, render mode, reward key or plant parameter.
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
    spec = options.get("scenario", scenarios.RANDOM)
    scenario = scenarios.resolve(spec, plant_id)
    reward = RewardConfig.from_options(options.get("reward"))
    return plant, scenario, reward, render_mode
