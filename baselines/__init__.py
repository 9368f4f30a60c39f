"""Baseline controllers: one module each, a registry, the Policy protocol.

``baselines.make(name, env) -> Policy``; ``baselines.NAMES`` lists them. A controller of
your own joins them with ``baselines.register(name, factory)``: ``baselines.make``, the
leaderboard's ``--policies`` and ``steamtemp-check --policy`` then know the name (on the
command line, ``--import MODULE`` imports the module that registers it). Every baseline
made here refuses a non-finite or misshapen observation with a ``ValueError`` before its
state changes (``baselines.policy.checked``).
"""

from __future__ import annotations

import importlib
import re
from collections.abc import Callable
from typing import Any

from baselines import tuning
from baselines.policy import Policy, checked


class Tuned:
    """The row ``<name>_tuned``: controller ``name`` with the knob values the benchmark's
    common tuning stored for the env's plant (baselines/tuning.py), for controllers whose
    paper gives its own parameters (those stay the default of ``name``)."""

    def __init__(self, name: str) -> None:
        self.name = name

    def __call__(self, env: Any, **kwargs: Any) -> Any:
        values = tuning.stored(self.name, env.unwrapped.plant.id)
        return factory(self.name)(env, **{**values, **kwargs})


#: Every baseline by name: its factory, or a ``module:attr`` reference imported on first use
#: (register() adds to it).
REGISTRY: dict[str, str | Callable[..., Any]] = {
    "cascade_pi": "baselines.cascade_pi:CascadePI",
    "cascade_pi_ff": "baselines.cascade_pi:CascadePIFF",
    "fao_sf": "baselines.fao:FaoSF",
    "fao_fac": "baselines.fao:FaoFAC",
    "fuzzy_p2id": "baselines.fuzzy_p2id:FuzzyP2ID",
    "neuro_pid_mee": "baselines.neuro_pid:NeuroPIDMEE",
    "neuro_pid_mse": "baselines.neuro_pid:NeuroPIDMSE",
    "lqi": "baselines.lqi:LQI",
    "mpc_evarx": "baselines.mpc_evarx:MPCEVARX",
    "mpc_arx": "baselines.mpc_evarx:MPCARX",
    "mpc_linear": "baselines.mpc_linear:MPCLinear",
}
#: Rows of the benchmark's common tuning for controllers whose own parameters are published
#: (SIMC for the cascades): ``<name>_tuned`` (baselines/tuning.py).
TUNED_ROWS = ("cascade_pi", "cascade_pi_ff", "fao_sf", "fao_fac", "neuro_pid_mee", "neuro_pid_mse")
REGISTRY.update({f"{n}_tuned": Tuned(n) for n in TUNED_ROWS})
#: The industrial reference: the cascade as a commissioned unit runs it (load-scheduled
#: gains, load feed-forward). The leaderboard's score 0, the unit of the valve-travel
#: budget, the base a residual agent corrects.
INDUSTRIAL_REFERENCE = "cascade_pi_ff"
#: The shipped controllers (register() cannot replace them).
SHIPPED: tuple[str, ...] = tuple(REGISTRY)
NAMES: tuple[str, ...] = SHIPPED
#: A registered name: a letter, then letters, digits, ``_``, ``-`` or ``.`` (no ``:`` or
#: ``,``, which the command lines read as a module path and a list separator).
_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_.\-]{0,99}$")
_REF = re.compile(r"^[A-Za-z_][\w.]*:[A-Za-z_][\w.]*$")


def register(name: str, factory: Callable[..., Policy] | str) -> None:
    """Add a controller: ``baselines.make(name, env, **kwargs)`` then returns
    ``factory(env, **kwargs)``, and ``NAMES`` ends with ``name``.

    Args:
        name: A letter, then up to 99 letters, digits, ``_``, ``-`` or ``.``.
        factory: A class or function ``factory(env, **kwargs) -> Policy`` (``env`` a single
            or a vector env), or a ``"module:callable"`` string imported at the first make.

    Registering a name again with the same factory does nothing.

    Raises:
        ValueError: a bad name, a shipped name, a name registered with another factory, or a
            factory that is neither callable nor a ``"module:callable"`` string; nothing is
            registered then.
    """
    global NAMES
    if not isinstance(name, str) or not _NAME.match(name):
        raise ValueError(
            f"baseline name must be a letter followed by up to 99 letters, digits, "
            f"'_', '-' or '.', got {name!r}"
        )
    if not (callable(factory) or (isinstance(factory, str) and _REF.match(factory))):
        raise ValueError(
            f"factory of {name!r} must be callable (env -> Policy) or a "
            f"'module:callable' string, got {factory!r}"
        )
    if name in SHIPPED:
        raise ValueError(f"{name!r} is a shipped baseline; register under another name")
    old = REGISTRY.get(name)
    if old is not None and old != factory:
        raise ValueError(f"baseline {name!r} is already registered (with {old!r})")
    REGISTRY[name] = factory
    NAMES = tuple(REGISTRY)


def factory(name: str) -> Callable[..., Any]:
    """The class or function behind the baseline ``name`` (imported on first use)."""
    try:
        ref = REGISTRY[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown baseline {name!r}; valid names: {list(NAMES)}") from None
    if isinstance(ref, str):
        module, attr = ref.split(":")
        ref = importlib.import_module(module)
        for part in attr.split("."):
            ref = getattr(ref, part)
    return ref


def tuning_source(name: str) -> str:
    """The controller whose stored tuning (baselines/tuning.py) the row ``name`` reads: the
    base controller of a ``<base>_tuned`` row, else ``name`` itself."""
    ref = REGISTRY.get(name)
    return ref.name if isinstance(ref, Tuned) else name


def make(name: str, env: Any, **kwargs: Any) -> Policy:
    """The baseline ``name`` for ``env``; ValueError listing the valid names otherwise."""
    return checked(factory(name)(env, **kwargs), env)


__all__ = [
    "NAMES",
    "REGISTRY",
    "SHIPPED",
    "Policy",
    "Tuned",
    "factory",
    "make",
    "register",
    "tuning_source",
]
