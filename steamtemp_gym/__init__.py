"""steamtemp_gym: Gymnasium environments for superheated steam temperature control.

``import steamtemp_gym`` registers one id per plant in the ``steamtemp``
namespace (see :data:`ENV_IDS`); ``gym.make(id, scenario=..., ...)`` builds a
SteamTempEnv, ``gym.make_vec(id, num_envs=N, vectorization_mode="vector_entry_point")``
the native batched env. See README.md and ../shared/DESIGN.md.
"""

from __future__ import annotations

import hashlib
import os
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import gymnasium as gym
import numba


def _numba_cache_dir() -> str:
    """A numba cache directory keyed by a hash of this package's sources.

    Numba invalidates a cached kernel only when its own file changes, not when a
    function it calls (in another module) does; keying the cache on every source
    file makes stale kernels impossible after an edit or upgrade.
    """
    digest = hashlib.sha256()
    for f in sorted(Path(__file__).parent.rglob("*.py")):
        digest.update(f.read_bytes())
    base = os.environ.get("NUMBA_CACHE_DIR") or str(Path.home() / ".cache" / "steamtemp_gym")
    return str(Path(base) / f"numba-{digest.hexdigest()[:16]}")


numba.config.CACHE_DIR = _numba_cache_dir()

from steamtemp_gym.plants import PLANTS  # noqa: E402

try:
    __version__ = version("steamtemp-gym")
except PackageNotFoundError:  # running from a source tree
    __version__ = "0.0.0+src"

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
