"""The plants, one module or package each; the catalog (steamtemp_gym/catalog.py,
re-exported here as :data:`PLANTS` and :func:`plant_class`) maps every env id to its class.

Adding a plant = one module (or package) here plus one line in :data:`PLANTS`. A large
plant is a package with one task per module (``supercritical_fsh/``, ``benson_subcritical/``,
``boiler_turbine_mimo/``, ``drum_boiler/``: ``params``, ``layout``, ``kernel``,
``steady_state``, ``calibration``, ``plant``), its ``__init__`` carrying the model's
description and re-exporting its names.

A plant's own named scenarios are data on its class: ``scenarios``, a mapping of name to
Scenario (``steamtemp_gym.scenarios.declare``; none by default). :func:`own_scenarios` reads
it, and ``steamtemp_gym.scenarios`` looks names up there, for the plant id it is given,
before its registry of shared named scenarios.
"""

from __future__ import annotations

from collections.abc import Mapping

from steamtemp_gym.catalog import PLANTS, plant_class
from steamtemp_gym.plants.base import Plant
from steamtemp_gym.scenarios import Scenario


def own_scenarios(plant_id: str) -> Mapping[str, Scenario]:
    """The named scenarios the plant of an env id declares (its class attribute
    ``scenarios``; none if it has none); ValueError listing the known ids otherwise."""
    return plant_class(plant_id).scenarios


def make(plant_id: str, **params) -> Plant:
    """A plant instance with parameter overrides (ValueError on unknown or impossible values)."""
    return plant_class(plant_id)(**params)


__all__ = ["PLANTS", "Plant", "make", "own_scenarios", "plant_class"]
