"""The plants, one module or package each; :data:`PLANTS` maps every env id to its plant class.

Adding a plant = one module (or package) here plus one entry in :data:`PLANTS` (the id is
registered with Gymnasium by ``steamtemp_gym/__init__.py``). A large plant is a package
with one task per module (``supercritical_fsh/``, ``benson_subcritical/``,
``boiler_turbine_mimo/``, ``drum_boiler/``: ``params``, ``layout``, ``kernel``,
``steady_state``, ``calibration``, ``plant``), its ``__init__`` carrying the model's
description and re-exporting its names.

A plant's own named scenarios are data on its class: ``scenarios``, a mapping of name to
Scenario (``steamtemp_gym.scenarios.declare``; none by default). :func:`own_scenarios` reads
it, and ``steamtemp_gym.scenarios`` looks names up there, for the plant id it is given,
before its registry of shared named scenarios.
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping

from steamtemp_gym import scenarios
from steamtemp_gym.plants.base import Plant
from steamtemp_gym.scenarios import Scenario

#: env id -> "module:Class" of its plant (imported lazily).
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


def own_scenarios(plant_id: str) -> Mapping[str, Scenario]:
    """The named scenarios the plant of an env id declares (its class attribute
    ``scenarios``; none if it has none); ValueError listing the known ids otherwise."""
    return plant_class(plant_id).scenarios


scenarios.registry.use_plant_scenarios(own_scenarios)


def make(plant_id: str, **params) -> Plant:
    """A plant instance with parameter overrides (ValueError on unknown or impossible values)."""
    return plant_class(plant_id)(**params)
