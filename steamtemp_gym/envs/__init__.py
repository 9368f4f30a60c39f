"""The generic environment, its native vector env, rendering and variant registration."""

from typing import Any

import steamtemp_gym
from steamtemp_gym.envs import options as opts
from steamtemp_gym.envs.steam_temp_env import SteamTempEnv
from steamtemp_gym.envs.vector_env import SteamTempVectorEnv

__all__ = ["SteamTempEnv", "SteamTempVectorEnv", "ids", "register_variant", "resolve_id"]


def ids() -> list[str]:
    """Every registered id built by SteamTempEnv: the suite's and registered variants."""
    import gymnasium as gym

    entry = gym.spec(steamtemp_gym.ENV_IDS[0]).entry_point
    return [i for i, spec in gym.registry.items() if spec.entry_point == entry]


def resolve_id(name: str) -> str:
    """The registered id ``name`` names: itself, or the one id of :func:`ids` whose name
    without its namespace it is (``Cascade300MW-v0`` for ``steamtemp/Cascade300MW-v0``).

    Raises:
        ValueError: no such id, or several with that name (listing them).
    """
    import gymnasium as gym

    if isinstance(name, str) and name in gym.registry:
        return name
    found = [i for i in ids() if isinstance(name, str) and i.split("/", 1)[-1] == name]
    if len(found) == 1:
        return found[0]
    if found:
        raise ValueError(f"env name {name!r} is ambiguous: {found}; give the full id")
    raise ValueError(
        f"unknown env id {str(name)[:100]!r}; valid ids: {', '.join(ids())} "
        "(the name after 'steamtemp/' is enough)"
    )


def register_variant(new_id: str, base_id: str, **options: Any) -> None:
    """Register ``new_id`` as the env of ``base_id`` with ``options`` as its defaults.

    ``options`` are those of ``gym.make`` (``params``, ``scenario``, ``reward``,
    ``render_mode``); ``params`` are merged over the base id's. The variant gets the base's
    single and native vector entry points, so ``gym.make``, ``gym.make_vec``, the baselines
    and ``steamtemp-check`` work on it. Options are validated now. Registering the same
    variant again is a no-op. Example (docs/checking.md)::

        register_variant("my/FSH12-v0", "steamtemp/SupercriticalFSH-v0",
                         params={"n_segments": 12})

    Raises:
        ValueError: unknown base id, a bad option or parameter (named), or ``new_id``
            already registered differently.
    """
    import copy

    import gymnasium as gym

    base = gym.registry.get(base_id)
    if base is None or "plant_id" not in base.kwargs:
        valid = [i for i, s in gym.registry.items() if "plant_id" in s.kwargs]
        raise ValueError(f"unknown base id {base_id!r}; valid ids: {valid}")
    kwargs = copy.deepcopy(base.kwargs)
    params = {**kwargs.get("params", {}), **(options.pop("params", None) or {})}
    kwargs.update(options)
    if params:
        kwargs["params"] = params
    opts.build(kwargs["plant_id"], {k: v for k, v in kwargs.items() if k != "plant_id"})
    old = gym.registry.get(new_id)
    if old is not None:
        if old.kwargs == kwargs and old.entry_point == base.entry_point:
            return
        raise ValueError(f"{new_id!r} is already registered (with {old.kwargs})")
    gym.register(
        new_id,
        entry_point=base.entry_point,
        vector_entry_point=base.vector_entry_point,
        kwargs=kwargs,
    )
