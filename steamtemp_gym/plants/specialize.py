"""Compiled, disk-cached copies of a kernel template, one per plant.

The shared kernels (the ROS2 step of plants/integrator.py) call plant functions
(``rhs``, ``outputs``, ...) that differ per plant. Numba cannot cache a closure over
compiled functions (the index key pickles them with a per-process id) nor a kernel
taking compiled functions as arguments (their addresses are "dynamic globals"), so
such kernels would compile again in every process (4 s per plant).

:func:`specialize` instead copies a plain Python template with the plant functions
bound as *globals* of the copy and a qualified name of its own, so numba compiles and
caches each copy like any module-level kernel (its cache index is named after the
copy, e.g. ``integrator._batched_step[SupercriticalFSH]``).

Numba keys that cache on the template's source file only; a change in a bound plant
function is caught by the cache directory's key over the package sources
(steamtemp_gym/_cache.py).
"""

from __future__ import annotations

import types
from collections.abc import Callable

from steamtemp_gym._jit import njit


def specialize(template: Callable, name: str, **bindings) -> Callable:
    """A cached compiled copy of ``template`` whose globals ``bindings`` are replaced.

    ``name`` must be unique per template and set of bindings (it names the cache).
    """
    missing = sorted(set(bindings) - set(template.__code__.co_names))
    if missing:
        raise ValueError(f"{template.__qualname__} does not use {missing}")
    scope = dict(template.__globals__)
    scope.update(bindings)
    copy = types.FunctionType(template.__code__, scope, template.__name__, template.__defaults__)
    copy.__qualname__ = f"{template.__qualname__}[{name}]"
    copy.__module__ = template.__module__
    copy.__doc__ = template.__doc__
    # nogil: threads may run a copy on blocks of a batch at once (plants/threads.py)
    return njit(cache=True, error_model="numpy", nogil=True)(copy)
