"""steamtemp_gym._jit: one compilation per argument type, not per literal value; the numba
internals it relies on (docs/architecture.md), each checked to be in effect."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from numba.core import types
from numba.core.dispatcher import Dispatcher

from steamtemp_gym import _jit
from steamtemp_gym._jit import entry_point, njit, read_only


@njit(cache=False)
def _pick(a, k):
    return a[k]


@njit(cache=False)
def _callers(a):
    return _pick(a, 0) + _pick(a, 1) + _pick(a, 2) + _pick(a, 1)


def test_calls_with_constants_compile_one_specialisation():
    """The literal-widening patch is in effect: a kernel called from compiled code with the
    constants 0, 1 and 2 is compiled once, for int64 (numba alone compiles it three times,
    once per Literal[int])."""
    assert _jit.WIDENING, "numba's Dispatcher.get_call_template(args, kws) is gone"
    assert _callers(np.arange(3.0)) == 4.0
    assert _pick.signatures == [(types.Array(types.float64, 1, "C"), types.int64)]


def test_entry_point_is_numbas_compiled_function():
    """What Dispatcher.compile returns is numba's compiled entry point: callable, not the
    dispatcher, and computes what the dispatcher computes."""
    a = np.arange(4.0)
    call = entry_point(_pick, (a, 2))
    assert call is not _pick and callable(call)
    assert call(a, 2) == _pick(a, 2) == 2.0


def test_bare_and_called_forms_and_explicit_signatures():
    @njit
    def bare(x):
        return x + 1

    @njit("float64(float64)", cache=False)
    def typed(x):
        return x * 2.0

    assert bare(1) == 2 and typed(2.0) == 4.0
    assert isinstance(bare, Dispatcher) and isinstance(typed, Dispatcher)


def test_read_only_view_sees_writes_and_refuses_its_own():
    a = np.zeros(3)
    v = read_only(a)
    a[1] = 5.0
    assert v[1] == 5.0
    with pytest.raises(ValueError):
        v[0] = 1.0


_SCRIPT = """
import gc
import gymnasium as gym
from numba.core import types
from numba.core.dispatcher import Dispatcher
import steamtemp_gym

def canonical(sig):
    out = []
    for t in sig:
        t = types.unliteral(t)
        if isinstance(t, types.Array):
            t = t.copy(layout="C", readonly=False)
        out.append(t)
    return tuple(out)

for env_id in steamtemp_gym.ENV_IDS:
    env = gym.make(env_id)
    env.reset(seed=0)
    env.step(env.action_space.sample())
seen = 0
for obj in gc.get_objects():
    try:
        if not (isinstance(obj, Dispatcher) and obj.py_func.__module__.startswith("steamtemp_gym")):
            continue
    except ReferenceError:  # a dead weak proxy among the collected objects
        continue
    seen += 1
    sigs = obj.signatures
    if len({canonical(s) for s in sigs}) != len(sigs) or any(
            isinstance(t, types.Literal) for s in sigs for t in s):
        print("twice:", obj.py_func.__qualname__, sigs)
print("kernels:", seen)
"""


def test_no_kernel_compiles_twice_for_one_argument_type():
    """In a fresh process that makes, resets and steps every plant (calibration
    included), no project kernel holds two specialisations that differ only in a literal
    value, array mutability or layout: each would be a whole compilation on a cold start."""
    out = subprocess.run(
        [sys.executable, "-c", _SCRIPT], capture_output=True, text=True, check=True
    ).stdout
    assert "twice:" not in out, out
    assert int(out.split("kernels:")[1]) > 100
