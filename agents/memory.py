"""What the controller memory adds to an agent's observation (agents/wrappers.py: the
memory itself, its wrappers): :class:`MemoryConfig`, and the options an RL Zoo
``env_wrapper`` gives it (:func:`memory_options`). Without SB3 or torch, so that an agent's
files can be checked against an env (agents/files.py) before anything loads the model.
"""

from __future__ import annotations

import dataclasses
from typing import Any


@dataclasses.dataclass(frozen=True)
class MemoryConfig:
    """What the memory adds (module docstring); the defaults are the measured choice
    (docs/agents/observation.md, "Controller memory")."""

    integral: bool = True
    secondary_integral: bool = False
    integral_time_s: float = 60.0
    integral_limit_K: float = 40.0
    history: int = 4
    history_stride: int = 5
    history_signals: str = "error_valves"
    rates: bool = False
    rate_filter_s: float = 30.0

    def __post_init__(self) -> None:
        if self.history_signals not in HISTORY_SIGNALS:
            raise ValueError(
                f"history_signals must be one of {list(HISTORY_SIGNALS)}, got "
                f"{self.history_signals!r}"
            )
        for name in ("integral_time_s", "integral_limit_K", "rate_filter_s"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0):
                raise ValueError(f"{name} must be a positive number, got {v!r}")
        for name, lo in (("history", 0), ("history_stride", 1)):
            v = getattr(self, name)
            if not (isinstance(v, int) and not isinstance(v, bool) and v >= lo):
                raise ValueError(f"{name} must be an integer >= {lo}, got {v!r}")
        for name in ("integral", "secondary_integral", "rates"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"{name} must be true or false, got {getattr(self, name)!r}")
        if self.secondary_integral and not self.integral:
            raise ValueError("secondary_integral needs integral (the main-steam integral)")

    @classmethod
    def from_kwargs(cls, kwargs: dict[str, Any] | None) -> MemoryConfig:
        """A config from keyword arguments; ValueError naming unknown keys."""
        kwargs = dict(kwargs or {})
        valid = [f.name for f in dataclasses.fields(cls)]
        unknown = sorted(set(kwargs) - set(valid))
        if unknown:
            raise ValueError(f"unknown controller-memory option(s) {unknown}; valid: {valid}")
        return cls(**kwargs)

    def n_extra(self, n_valves: int, n_secondary: int, n_obs: int) -> int:
        """How many entries the memory adds for a plant with ``n_valves`` actuators,
        ``n_secondary`` secondary scored temperatures and ``n_obs`` observed signals."""
        n_int = int(self.integral) * (1 + (n_secondary if self.secondary_integral else 0))
        n_sample = n_obs if self.history_signals == "observation" else 1 + n_valves
        return n_int + self.history * n_sample + 2 * int(self.rates)


#: What the history samples: the error and the valve openings, or every observed signal
#: (the inner temperatures, load, flows and measured disturbances a controller acts on).
HISTORY_SIGNALS = ("error_valves", "observation")


#: The controller memory as an RL Zoo ``env_wrapper`` names it.
MEMORY_WRAPPER = "agents.wrappers.ControllerMemory"


def memory_options(value: Any) -> dict | None:
    """The controller-memory options of an RL Zoo ``env_wrapper`` value: a class name, a
    one-entry mapping {name: kwargs}, or a list of those (ValueError naming the problem)."""
    out = None
    for item in value if isinstance(value, list) else [value]:
        if isinstance(item, dict) and len(item) == 1:
            name, kwargs = next(iter(item.items()))
        else:
            name, kwargs = item, {}
        if name != MEMORY_WRAPPER or not isinstance(kwargs, (dict, type(None))):
            raise ValueError(f"env_wrapper: only {MEMORY_WRAPPER} is supported, got {item!r}")
        out = dict(kwargs or {})
        try:
            MemoryConfig.from_kwargs(out)  # checks the option names and values
        except ValueError as exc:
            raise ValueError(f"env_wrapper: {exc}") from None
    return out
