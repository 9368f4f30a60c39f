"""The registry of named scenarios, and :func:`resolve`, which turns any scenario argument
into a Scenario.

For a plant id, names are looked up first in the named scenarios the plant declares (the
``scenarios`` attribute of its class, found through the catalog of plants,
steamtemp_gym/catalog.py, which imports a plant only when asked for it), then
in the registry (:func:`register`), which holds the scenarios shared by every plant
(``library.py``) and those users register.

``resolve`` takes a name, ``heldout:<name>``, ``"random"``, a :class:`Scenario` or a file: any
``os.PathLike`` is a file (it must end in ``.yaml`` or ``.yml``), and so is a ``str``
ending in ``.yaml`` / ``.yml``.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence

from steamtemp_gym import catalog
from steamtemp_gym.scenarios.model import Scenario, clip, describe, excerpt
from steamtemp_gym.scenarios.yaml_loader import as_path, load_yaml

#: The name of the seeded training distribution (steamtemp_gym/scenarios/distribution.py).
RANDOM = "random"
#: How a held-out scenario is named: ``heldout:mill_trip`` (steamtemp_gym/scenarios/heldout).
HELDOUT_PREFIX = "heldout:"

_REGISTRY: dict[str, tuple[Scenario, tuple[str, ...] | None]] = {}


def _own(plant_id: str | None) -> Mapping[str, Scenario]:
    """The named scenarios ``plant_id`` declares (none for None)."""
    return {} if plant_id is None else catalog.plant_class(plant_id).scenarios


def check_name(name: str) -> None:
    """Raise ValueError unless the command lines can spell ``name`` as a scenario name: not
    ``random``, ``heldout:...``, a ``.yaml``/``.yml`` ending or a name with a comma."""
    if name == RANDOM:
        raise ValueError(f"{RANDOM!r} is reserved for the seeded training distribution")
    if name.startswith(HELDOUT_PREFIX) or name.lower().endswith((".yaml", ".yml")) or "," in name:
        raise ValueError(
            f"scenario name {excerpt(name)} would read as a held-out scenario, "
            "a file or a list; choose another name"
        )


def register(scenario: Scenario, plants: Sequence[str] | None = None) -> Scenario:
    """Register a named scenario, for every plant or only for the given plant ids.

    ``gym.make(id, scenario=name)``, ``reset(options={"scenario": name})``, the
    leaderboard's ``--scenarios`` and :func:`names` then know it (on the command line,
    ``--import MODULE`` imports the module that registers it). The scenario is used as
    given: the named scenarios' disturbances (:data:`NAMED_DISTURBANCES`) are not added.
    Registering the same scenario again does nothing.

    Raises:
        ValueError: not a Scenario, bad ``plants``, a name the command lines cannot spell
            (``random``, ``heldout:...``, a ``.yaml``/``.yml`` ending, a comma) or a name
            registered with another scenario; nothing is registered then.
    """
    if not isinstance(scenario, Scenario):
        raise ValueError(f"register() needs a Scenario, got {describe(scenario)}")
    if plants is not None and (
        isinstance(plants, str)
        or not isinstance(plants, Sequence)
        or not all(isinstance(p, str) for p in plants)
    ):
        raise ValueError(f"register() 'plants' must be a list of plant ids, got {describe(plants)}")
    name = scenario.name
    check_name(name)
    entry = (scenario, tuple(plants) if plants is not None else None)
    old = _REGISTRY.get(name)
    if old is not None and (old[0].to_dict() != scenario.to_dict() or old[1] != entry[1]):
        raise ValueError(
            f"scenario {excerpt(name)} is already registered (with another "
            "schedule or other plants); choose another name"
        )
    _REGISTRY[name] = entry
    return scenario


def names(plant_id: str | None = None) -> list[str]:
    """Names of the named scenarios valid for ``plant_id`` (the plant's own and the registered
    ones; every registered one if None), sorted, plus ``random``."""
    own = _own(plant_id)
    out = [
        n for n, (_, pl) in _REGISTRY.items() if pl is None or plant_id is None or plant_id in pl
    ]
    return sorted({*own, *out}) + [RANDOM]


def get(name: str, plant_id: str | None = None) -> Scenario:
    """A named scenario: the plant's own of that name, else the registered one valid for
    ``plant_id``; ValueError listing the valid names otherwise."""
    own = _own(plant_id)
    if isinstance(name, str) and name in own:
        return own[name]
    entry = _REGISTRY.get(name) if isinstance(name, str) else None
    if entry is None or (
        plant_id is not None and entry[1] is not None and plant_id not in entry[1]
    ):
        raise ValueError(f"unknown scenario {excerpt(name)}; {forms(plant_id)}")
    return entry[0]


def forms(plant_id: str | None = None) -> str:
    """Every way to name a scenario (for error messages and help texts)."""
    from steamtemp_gym.scenarios import heldout  # a circle at the top: heldout imports this package

    named = [n for n in names(plant_id) if n != RANDOM]
    return (
        f"valid names: {named}, {HELDOUT_PREFIX}<name> of the held-out set "
        f"{[HELDOUT_PREFIX + n for n in heldout.NAMES]}, {RANDOM!r} (the seeded training "
        "distribution), or a YAML file (a path ending in .yaml or .yml)"
    )


def resolve(spec: str | os.PathLike[str] | Scenario, plant_id: str | None = None) -> Scenario | str:
    """Turn a scenario argument into a Scenario or ``"random"``.

    ``spec`` is a Scenario; a file (any ``os.PathLike``, or a ``str`` ending in ``.yaml`` or
    ``.yml``, suffix case ignored), which must end in ``.yaml`` / ``.yml``; ``"random"``;
    ``heldout:<name>``, a held-out scenario (steamtemp_gym/scenarios/heldout); or the name
    of a named scenario valid for ``plant_id`` (:func:`get`). The same names work in ``gym.make``,
    ``reset(options={"scenario": ...})``, the leaderboard's ``--scenarios`` and
    ``steamtemp-check --scenario``.

    Raises:
        ValueError: naming the file or listing the valid names.
    """
    if isinstance(spec, Scenario):
        return spec
    if isinstance(spec, os.PathLike):
        path = as_path(spec)
        if path.suffix.lower() not in (".yaml", ".yml"):
            raise ValueError(
                f"scenario file {clip(str(path), 200)!r} must end in .yaml or .yml "
                "(a path is always read as a file, never as a scenario name)"
            )
        return load_yaml(path)
    if isinstance(spec, str):
        if spec.lower().endswith((".yaml", ".yml")):
            return load_yaml(spec)
        if spec == RANDOM:
            return RANDOM
        if spec.startswith(HELDOUT_PREFIX):
            from steamtemp_gym.scenarios import (
                heldout,
            )  # a circle at the top: heldout imports this package

            if spec[len(HELDOUT_PREFIX) :] not in heldout.NAMES:
                raise ValueError(f"unknown held-out scenario {excerpt(spec)}; {forms(plant_id)}")
            return heldout.load(spec)
        try:
            return get(spec, plant_id)
        except ValueError as exc:
            if len(spec) < 4096 and os.path.isfile(spec):
                raise ValueError(
                    f"{exc} (a file {clip(spec, 200)!r} exists, but scenario files must end "
                    "in .yaml or .yml)"
                ) from None
            raise
    raise ValueError(
        "scenario must be a name, 'random', a YAML file (str or os.PathLike) or a Scenario, "
        f"got {describe(spec)}"
    )
