"""steamtemp_gym: Gymnasium environments for superheated steam temperature control.

``import steamtemp_gym`` registers one id per plant in the ``steamtemp``
namespace (see :data:`ENV_IDS`); ``gym.make(id, scenario=..., ...)`` builds a
SteamTempEnv, ``gym.make_vec(id, num_envs=N, vectorization_mode="vector_entry_point")``
the native batched env. See README.md and docs/architecture.md.

Kernels compile on first use and are cached on disk (``CACHE_DIR``, set by
``$STEAMTEMP_GYM_CACHE_DIR``; steamtemp_gym/_cache.py).
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

import gymnasium as gym

from steamtemp_gym import _cache

try:
    __version__ = version("steamtemp-gym")
except PackageNotFoundError:  # running from a source tree
    __version__ = "0.0.0+src"

#: the folder of this code version's compiled kernels (steamtemp_gym/_cache.py)
CACHE_DIR = _cache.configure(__version__)
_cache.announce_compiles()

from steamtemp_gym import catalog  # noqa: E402
from steamtemp_gym.plants.base import Plant  # noqa: E402

#: Every registered env id: the catalog's plants in the order of the reference documents,
#: then those added with :func:`register_plant`.
ENV_IDS: tuple[str, ...] = tuple(catalog.PLANTS)


def _register(plant_id: str) -> None:
    if plant_id not in gym.registry:
        gym.register(
            id=plant_id,
            entry_point="steamtemp_gym.envs.steam_temp_env:SteamTempEnv",
            vector_entry_point="steamtemp_gym.envs.vector_env:SteamTempVectorEnv",
            kwargs={"plant_id": plant_id},
        )


def register_plant(plant_id: str, entry: str) -> None:
    """Add a plant of your own: ``entry`` (``"module:Class"``, a subclass of
    ``steamtemp_gym.plants.Plant`` whose ``id`` is ``plant_id``) enters the catalog,
    :data:`ENV_IDS` and Gymnasium's registry, as the package's own plants do. The
    registry-wide checks then cover it (docs/architecture.md, "Adding a plant").

    Raises:
        ValueError: an id that is taken or not of the form ``namespace/Name-vN``, an entry
            that cannot be imported or is no such class; nothing is registered.
    """
    global ENV_IDS
    catalog.add(plant_id, entry, Plant)
    try:
        _register(plant_id)
    except Exception as exc:  # noqa: BLE001 - Gymnasium's refusal: the catalog as before
        del catalog.PLANTS[plant_id]
        raise ValueError(f"plant id {plant_id!r}: Gymnasium refuses it: {exc}") from None
    ENV_IDS = tuple(catalog.PLANTS)


for _id in ENV_IDS:
    _register(_id)

__all__ = ["ENV_IDS", "__version__", "register_plant"]
