"""The project's ``njit``: numba's, without one compilation per literal argument.

When compiled code calls a compiled function with a constant (``_s(P, 3, F_KA)``, a
named offset, ``True``), numba types that argument as ``Literal[int](3)`` and compiles a
specialisation of the callee for each distinct constant. Nothing here uses literal
values (no ``literally``, no indexing of heterogeneous tuples by an argument), so those
specialisations are the same machine code compiled again and again: BensonSubcritical's
per-section accessor was compiled 124 times on a cold start, and the plant took 47 s to
compile instead of 21 s (``benchmarks/cold_start.py``).

:func:`njit` takes numba's arguments and returns numba's dispatcher, whose calls from
compiled code are typed with the literal types widened (``types.unliteral``): one
specialisation per argument type. Calls from Python already behave this way.
"""

from __future__ import annotations

import numba
import numpy as np
from numba.core import types
from numba.core.dispatcher import Dispatcher


def _widen_literals(dispatcher: Dispatcher) -> Dispatcher:
    """``dispatcher``, typing calls from compiled code with unliteral argument types."""
    template = dispatcher.get_call_template  # numba's typing hook for calls from compiled code

    def get_call_template(args, kws):
        return template(tuple(types.unliteral(a) for a in args),
                        {k: types.unliteral(v) for k, v in kws.items()})  # fmt: skip

    dispatcher.get_call_template = get_call_template
    return dispatcher


def njit(*args, **kwargs):
    """``numba.njit`` (same arguments, bare or called) whose compiled callers pass no literals."""
    made = numba.njit(*args, **kwargs)
    if isinstance(made, Dispatcher):
        return _widen_literals(made)
    return lambda func: _widen_literals(made(func))


def entry_point(kernel: Dispatcher, args: tuple):
    """The compiled function ``kernel`` runs for arguments of the types of ``args``
    (compiled or loaded from the cache now, nothing executed).

    Calling it skips numba's dispatch on argument types: only for arguments that always
    have those types (an env core's own arrays), since it does not check them.
    """
    return kernel.compile(tuple(numba.typeof(a) for a in args))


def read_only(a: np.ndarray) -> np.ndarray:
    """A read-only view of ``a`` that sees later writes to ``a``.

    The plants' parameter arrays are read-only once packed, so kernels compile for
    read-only arrays. Calibration, which writes the array while it calls kernels,
    passes them this view: a writable array would compile every kernel a second time.
    """
    view = a.view()
    view.flags.writeable = False
    return view
