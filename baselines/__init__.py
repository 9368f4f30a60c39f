"""Baseline controllers: one module each, a registry, the Policy protocol.

``baselines.make(name, env) -> Policy``; ``baselines.NAMES`` lists them. Adding a
controller = one module plus one entry in ``_REGISTRY``. Every baseline made here refuses
a non-finite or misshapen observation with a ``ValueError`` before its state changes
(``baselines.policy.checked``).
"""

from __future__ import annotations

import importlib
from typing import Any

from baselines.policy import Policy, checked

_REGISTRY: dict[str, str] = {
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
NAMES: tuple[str, ...] = tuple(_REGISTRY)


def make(name: str, env: Any, **kwargs: Any) -> Policy:
    """The baseline ``name`` for ``env``; ValueError listing the valid names otherwise."""
    try:
        path = _REGISTRY[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown baseline {name!r}; valid names: {list(NAMES)}") from None
    module, cls = path.split(":")
    return checked(getattr(importlib.import_module(module), cls)(env, **kwargs), env)


__all__ = ["NAMES", "Policy", "make"]
