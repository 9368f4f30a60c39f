"""The catalog of plants: every env id and the plant class that simulates it.

Adding a plant = its module or package in ``steamtemp_gym/plants`` plus one line in
:data:`PLANTS` (``steamtemp_gym/__init__.py`` registers the id with Gymnasium). The classes
are named by ``"module:Class"`` strings and imported on first use, as Gymnasium's entry
points are, so the modules below the plants (the scenarios, the env core) can ask for a
plant's declarations without importing any plant.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from steamtemp_gym.plants.base import Plant

#: env id -> "module:Class" of its plant.
PLANTS: dict[str, str] = {
    "steamtemp/SupercriticalFSH-v0": "steamtemp_gym.plants.supercritical_fsh:SupercriticalFSH",
    "steamtemp/BensonSubcritical-v0": "steamtemp_gym.plants.benson_subcritical:BensonSubcritical",
    "steamtemp/BoilerTurbineMIMO-v0": "steamtemp_gym.plants.boiler_turbine_mimo:BoilerTurbineMIMO",
    "steamtemp/DrumBoilerSH-v0": "steamtemp_gym.plants.drum_boiler:DrumBoilerSH",
    "steamtemp/Cascade300MW-v0": "steamtemp_gym.plants.cascade_300mw:Cascade300MW",
}


def plant_class(plant_id: str) -> type[Plant]:
    """The plant class of an env id; ValueError listing the known ids otherwise."""
    try:
        path = PLANTS[plant_id]
    except (KeyError, TypeError):
        raise ValueError(f"unknown plant id {plant_id!r}; valid ids: {sorted(PLANTS)}") from None
    module, cls = path.split(":")
    return getattr(importlib.import_module(module), cls)
