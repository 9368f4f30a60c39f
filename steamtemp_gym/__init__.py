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

from steamtemp_gym.catalog import PLANTS  # noqa: E402

#: Every registered env id, in the order of the reference documents.
ENV_IDS: tuple[str, ...] = tuple(PLANTS)

for _id in ENV_IDS:
    if _id not in gym.registry:
        gym.register(
            id=_id,
            entry_point="steamtemp_gym.envs.steam_temp_env:SteamTempEnv",
            vector_entry_point="steamtemp_gym.envs.vector_env:SteamTempVectorEnv",
            kwargs={"plant_id": _id},
        )

__all__ = ["ENV_IDS", "__version__"]
