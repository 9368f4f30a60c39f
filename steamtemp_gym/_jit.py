"""The project's ``njit``: numba's, without one compilation per literal argument.

When compiled code calls a compiled function with a constant (``section_param(P, 3, F_KA)``, a
named offset, ``True``), numba types that argument as ``Literal[int](3)`` and compiles a
specialisation of the callee for each distinct constant. Nothing here uses literal
values (no ``literally``, no indexing of heterogeneous tuples by an argument), so those
specialisations are the same machine code compiled again and again: BensonSubcritical's
per-section accessor was compiled 124 times on a cold start, and the plant took 47 s to
compile instead of 21 s (``benchmarks/cold_start.py``).

:func:`njit` takes numba's arguments and returns numba's dispatcher, whose calls from
compiled code are typed with the literal types widened (``types.unliteral``): one
specialisation per argument type. Calls from Python already behave this way.

This relies on numba internals (docs/architecture.md lists them, each with its test):
numba types a call from compiled code through the callee dispatcher's
``get_call_template(args, kws)``, looked up on the instance, which :func:`njit` replaces.
If numba's method is not there with those parameters, kernels are left as numba makes
them (correct, slower to compile) and :data:`WIDENING` is False. :func:`entry_point`
calls what ``Dispatcher.compile`` returns (numba's compiled entry point); if that is not
callable, it returns the dispatcher itself.
"""

from __future__ import annotations

import inspect
import logging

import numba
import numpy as np
from numba import types
from numba.core.dispatcher import Dispatcher

from steamtemp_gym import _cache

_HOOK = getattr(Dispatcher, "get_call_template", None)
#: whether calls from compiled code are typed with literals widened (module docstring)
WIDENING = _HOOK is not None and list(inspect.signature(_HOOK).parameters) == [
    "self",
    "args",
    "kws",
]
if not WIDENING:
    logging.getLogger("steamtemp_gym").warning(
        "steamtemp_gym: numba %s has no Dispatcher.get_call_template(args, kws); kernels "
        "compile once per literal argument (slower cold starts, same results)",
        numba.__version__,
    )


def _widen_literals(dispatcher: Dispatcher) -> Dispatcher:
    """``dispatcher``, typing calls from compiled code with unliteral argument types."""
    if not WIDENING:
        return dispatcher
    template = dispatcher.get_call_template  # numba's typing hook for calls from compiled code

    def get_call_template(args, kws):
        return template(
            tuple(types.unliteral(a) for a in args), {k: types.unliteral(v) for k, v in kws.items()}
        )

    dispatcher.get_call_template = get_call_template
    return dispatcher


def _define(args: tuple, kwargs: dict, func) -> Dispatcher:
    """numba's dispatcher of ``func`` with numba's ``args`` and ``kwargs``, its cache in
    this code version's folder (:func:`steamtemp_gym._cache.pointed`), literals widened."""
    with _cache.pointed() as cacheable:
        if kwargs.get("cache") and not cacheable:
            kwargs = {**kwargs, "cache": False}
        return _widen_literals(numba.njit(*args, **kwargs)(func))


def njit(*args, **kwargs):
    """``numba.njit`` (same arguments, bare or called) whose compiled callers pass no literals."""
    if len(args) == 1 and inspect.isfunction(args[0]):
        return _define((), kwargs, args[0])
    return lambda func: _define(args, kwargs, func)


def entry_point(kernel: Dispatcher, args: tuple):
    """The compiled function ``kernel`` runs for arguments of the types of ``args``
    (compiled or loaded from the cache now, nothing executed).

    Calling it skips numba's dispatch on argument types: only for arguments that always
    have those types (an env core's own arrays), since it does not check them.
    """
    compiled = kernel.compile(tuple(numba.typeof(a) for a in args))
    return compiled if callable(compiled) else kernel


def read_only(a: np.ndarray) -> np.ndarray:
    """A read-only view of ``a`` that sees later writes to ``a``.

    The plants' parameter arrays are read-only once packed, so kernels compile for
    read-only arrays. Calibration, which writes the array while it calls kernels,
    passes them this view: a writable array would compile every kernel a second time.
    """
    view = a.view()
    view.flags.writeable = False
    return view
