"""Commissioning results kept on disk, computed once per version of the code.

A baseline commissions itself on the plant it will run on: step tests, identification, a
design per load (the cascades' SIMC tunings and feed-forward, the EV-ARX models, the MPC's
and the LQI's designs, the FAO observers, the neuro-PID's commissioning gains), 0.1-5 s of
CPU each. A function decorated with :func:`commissioned` is memoized in the process
(``functools.lru_cache``) and on disk, so that the leaderboard's workers, the test suite's
processes and later runs read what one process computed instead of commissioning again.

The results live in ``<cache>/commissioning-<key>/`` beside the compiled kernels
(steamtemp_gym/_cache.py: ``$STEAMTEMP_GYM_CACHE_DIR``, by default
``~/.cache/steamtemp_gym``). The key hashes the code of steamtemp_gym and baselines (their
syntax trees without docstrings, and the steam tables) and the versions of numpy, scipy
and numba: any change of code gives a new folder, so a stored result is what this code
computes, to the bit (pickle keeps arrays exact). Folders of other versions are pruned
like the kernels'. Where the cache cannot be written, results are computed in each process
as before.

The decorated function must be a pure function of its arguments: strings, numbers, None,
tuples of these, or classes (keyed by their qualified names). It runs with the BLAS and
OpenMP thread pools limited to one thread, as the leaderboard's episodes do: the
identification of the EV-ARX models (a Gauss-Newton fit on large normal equations) ends
about 2e-9 apart in its coefficients on one BLAS thread and on two, and the stored result
must not depend on which process computed it first.
"""

from __future__ import annotations

import functools
import hashlib
import os
import pickle
from pathlib import Path
from typing import Any

import numpy as np
import scipy

import steamtemp_gym
from steamtemp_gym import _cache, provenance

#: The packages whose code a commissioning result depends on.
_ROOTS = (Path(steamtemp_gym.__file__).resolve().parent, Path(__file__).resolve().parent)


@functools.cache
def folder() -> Path | None:
    """This code version's folder of commissioning results (None: not writable)."""
    versions = (f"numpy {np.__version__}", f"scipy {scipy.__version__}")
    return _cache.versioned_folder(
        "commissioning", list(_ROOTS), *versions, suffixes=(".py", ".npz")
    )


def _key(value: Any) -> str:
    """A stable text of one argument (TypeError for a type the key does not cover)."""
    if isinstance(value, type):
        return f"<class {value.__module__}.{value.__qualname__}>"
    if isinstance(value, tuple):
        return "(" + ",".join(_key(v) for v in value) + ")"
    if value is None or isinstance(value, str | bool | int | float):
        return repr(value)
    raise TypeError(f"a commissioning result cannot be keyed by a {type(value).__name__}")


def _one_thread(fn, args: tuple, kwargs: dict) -> Any:
    """``fn(*args, **kwargs)`` with this process's BLAS and OpenMP pools at one thread."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1):
        return fn(*args, **kwargs)


def commissioned(maxsize: int = 16):
    """Decorator: memoize a commissioning function in the process and on disk (module
    docstring)."""

    def wrap(fn):
        name = f"{fn.__module__}.{fn.__qualname__}"

        @functools.lru_cache(maxsize=maxsize)
        @functools.wraps(fn)
        def memo(*args: Any, **kwargs: Any) -> Any:
            where = folder()
            if where is None:
                return _one_thread(fn, args, kwargs)
            text = name + _key(args) + _key(tuple(sorted(kwargs.items())))
            # a plant registered from outside the package: its code is in no folder's key
            outside = [provenance.outside_plant_files(a) for a in args]
            text += "".join(provenance.digest(files) for files in outside if files)
            path = where / f"{name}-{hashlib.sha256(text.encode()).hexdigest()[:24]}.pkl"
            try:
                with open(path, "rb") as f:
                    return pickle.load(f)
            except (OSError, EOFError, pickle.UnpicklingError):
                pass
            result = _one_thread(fn, args, kwargs)
            tmp = path.with_name(f"{path.name}.{os.getpid()}")
            try:
                with open(tmp, "wb") as f:
                    pickle.dump(result, f, protocol=pickle.HIGHEST_PROTOCOL)
                tmp.replace(path)  # atomic: a reader sees the whole file or none
            except OSError:
                tmp.unlink(missing_ok=True)
            return result

        return memo

    return wrap
