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
    if not isinstance(plant_id, str) or not re.fullmatch(r"[\w.-]+/[\w.-]+-v\d+", plant_id):
        raise ValueError(f"a plant id is namespace/Name-vN, got {str(plant_id)[:80]!r}")
    if plant_id in PLANTS:
        raise ValueError(f"plant id {plant_id!r} is taken (by {PLANTS[plant_id]})")
    module, _, name = entry.partition(":") if isinstance(entry, str) else ("", "", "")
    try:
        cls = getattr(importlib.import_module(module), name) if module and name else None
    except (ImportError, AttributeError) as exc:
        raise ValueError(f"plant entry {entry!r}: {exc}") from None
    is_plant = isinstance(cls, type) and issubclass(cls, base)
    if not is_plant or getattr(cls, "id", None) != plant_id:
        raise ValueError(f"plant entry {str(entry)[:80]!r} must name a subclass of Plant "
                         f"whose id is {plant_id!r}")  # fmt: skip
    PLANTS[plant_id] = entry


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
