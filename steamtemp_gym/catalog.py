"""The catalog of plants: every env id and the plant class that simulates it.

Adding a plant = its module or package in ``steamtemp_gym/plants`` plus one line in
:data:`PLANTS` (``steamtemp_gym/__init__.py`` registers the id with Gymnasium). The classes
are named by ``"module:Class"`` strings and imported on first use, as Gymnasium's entry
points are, so the modules below the plants (the scenarios, the env core) can ask for a
plant's declarations without importing any plant.
"""

from __future__ import annotations

import importlib
import re

#: env id -> "module:Class" of its plant.
PLANTS: dict[str, str] = {
    "steamtemp/SupercriticalFSH-v0": "steamtemp_gym.plants.supercritical_fsh:SupercriticalFSH",
    "steamtemp/BensonSubcritical-v0": "steamtemp_gym.plants.benson_subcritical:BensonSubcritical",
    "steamtemp/BoilerTurbineMIMO-v0": "steamtemp_gym.plants.boiler_turbine_mimo:BoilerTurbineMIMO",
    "steamtemp/DrumBoilerSH-v0": "steamtemp_gym.plants.drum_boiler:DrumBoilerSH",
    "steamtemp/Cascade300MW-v0": "steamtemp_gym.plants.cascade_300mw:Cascade300MW",
}


def add(plant_id: str, entry: str, base: type) -> None:
    """Add ``plant_id`` -> ``entry`` (``"module:Class"``) after checking that the id is new
    and of the form ``namespace/Name-vN`` and that the class is a subclass of ``base`` (the
    Plant class) of that id; ValueError otherwise, nothing added
    (``steamtemp_gym.register_plant``)."""
    valid = (
        re.fullmatch(r"[\w.-]+/[\w.-]+-v(0|[1-9]\d*)", plant_id)
        if isinstance(plant_id, str)
        else None
    )
    if not valid:
        raise ValueError(
            f"a plant id is namespace/Name-vN (N without leading zeros), got {str(plant_id)[:80]!r}"
        )
    if plant_id in PLANTS:
        raise ValueError(f"plant id {plant_id!r} is taken (by {PLANTS[plant_id]})")
    taken = _gymnasium_owner(plant_id)
    if taken:
        raise ValueError(f"plant id {plant_id!r} is taken in Gymnasium's registry ({taken})")
    module, _, name = entry.partition(":") if isinstance(entry, str) else ("", "", "")
    try:
        cls = getattr(importlib.import_module(module), name) if module and name else None
    except BaseException as exc:  # noqa: BLE001 - the module's own failure, SystemExit too
        if isinstance(exc, KeyboardInterrupt):
            raise
        raise ValueError(
            f"plant entry {str(entry)[:80]!r}: {type(exc).__name__}: {str(exc)[:300]}"
        ) from None
    is_plant = isinstance(cls, type) and issubclass(cls, base)
    if not is_plant or getattr(cls, "id", None) != plant_id:
        raise ValueError(
            f"plant entry {str(entry)[:80]!r} must name a subclass of Plant "
            f"whose id is {plant_id!r}"
        )
    try:
        cls.skeleton()
    except Exception as exc:  # noqa: BLE001 - a declaration it lacks or gets wrong
        raise ValueError(
            f"plant entry {str(entry)[:80]!r} is not a complete plant (its "
            f"declarations, docs/architecture.md): {type(exc).__name__}: "
            f"{str(exc)[:300]}"
        ) from None
    PLANTS[plant_id] = entry


def _gymnasium_owner(plant_id: str) -> str:
    """The entry point of an env in Gymnasium's registry that ``plant_id`` would replace or
    clash with (the same namespace, name and version as Gymnasium parses them, or a
    versioned id whose unversioned name is registered), "" if none."""
    import gymnasium as gym
    from gymnasium.envs.registration import parse_env_id

    ns, name, version = parse_env_id(plant_id)
    for key, spec in gym.envs.registry.items():
        other = parse_env_id(key)
        if other[:2] == (ns, name) and other[2] in (version, None):
            return f"{key}: {spec.entry_point}"
    return ""


def packaged(plant_id: str) -> bool:
    """Whether ``plant_id`` is one of this package's own plants (its class in
    ``steamtemp_gym.plants``), not one added with ``register_plant``."""
    return PLANTS.get(plant_id, "").startswith("steamtemp_gym.plants.")


def plant_class(plant_id: str) -> type:
    """The plant class (a subclass of ``steamtemp_gym.plants.Plant``) of an env id;
    ValueError listing the known ids otherwise."""
    try:
        path = PLANTS[plant_id]
    except (KeyError, TypeError):
        raise ValueError(f"unknown plant id {plant_id!r}; valid ids: {sorted(PLANTS)}") from None
    module, cls = path.split(":")
    return getattr(importlib.import_module(module), cls)
