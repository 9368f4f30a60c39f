"""Tunable parameters of the baselines and the values the benchmark's tuning stored.

A tunable controller class declares its parameters as ``KNOBS``, a tuple of :class:`Knob`,
and takes each knob's name as a keyword argument of its constructor (``None``: the
controller's default, the paper's published value where the paper gives one). Every
tunable baseline is searched on equal terms by ``python -m agents.baseline_tuning``: the
same search, the same budget of training episodes, the same objective (the leaderboard's
normalized score on episodes of the ``random`` training distribution, never a named or
held-out scenario) and the same valve-travel budget. The result is one JSON file per
controller, ``baselines/tuned/<name>.json``, read back here by :func:`stored`.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

#: Folder of the stored tunings (one ``<name>.json`` per controller).
TUNED = Path(__file__).with_name("tuned")


@dataclass(frozen=True)
class Knob:
    """One tunable parameter and the box it is searched in.

    Attributes:
        name: The constructor keyword.
        lo: Smallest value searched.
        hi: Largest value searched.
        log: Search on a logarithmic scale (``lo`` > 0), else linear.
    """

    name: str
    lo: float
    hi: float
    log: bool = True

    def __post_init__(self) -> None:
        if not (isinstance(self.name, str) and self.name.isidentifier()):
            raise ValueError(f"knob name must be an identifier, got {self.name!r}")
        if not (math.isfinite(self.lo) and math.isfinite(self.hi) and self.lo < self.hi):
            raise ValueError(f"knob {self.name!r}: need finite lo < hi, got {self.lo}, {self.hi}")
        if self.log and self.lo <= 0.0:
            raise ValueError(f"knob {self.name!r}: a log-scale knob needs lo > 0, got {self.lo}")

    def check(self, value: float | None, default: float) -> float:
        """``value`` as a float (``default`` for None): a controller's constructor reads its
        knob arguments through this.

        Raises:
            ValueError: a value that is not a finite number, or not positive for a log knob.
        """
        if value is None:
            return float(default)
        try:
            v = float(value)
        except (TypeError, ValueError):
            raise ValueError(f"knob {self.name} must be a number, got {value!r}") from None
        if not math.isfinite(v) or (self.log and v <= 0.0):
            kind = "a positive finite number" if self.log else "a finite number"
            raise ValueError(f"knob {self.name} must be {kind}, got {value!r}")
        return v

    def to_unit(self, value: float) -> float:
        """``value`` as a coordinate of the unit interval (0 at ``lo``, 1 at ``hi``)."""
        v = min(max(float(value), self.lo), self.hi)
        if self.log:
            return math.log(v / self.lo) / math.log(self.hi / self.lo)
        return (v - self.lo) / (self.hi - self.lo)

    def from_unit(self, x: float) -> float:
        """The value at unit coordinate ``x`` (clipped to [0, 1])."""
        x = min(max(float(x), 0.0), 1.0)
        if self.log:
            return float(self.lo * (self.hi / self.lo) ** x)
        return float(self.lo + x * (self.hi - self.lo))


def knobs(factory: Any) -> tuple[Knob, ...]:
    """The ``KNOBS`` of a controller class (empty if it has none)."""
    out = tuple(getattr(factory, "KNOBS", ()))
    if not all(isinstance(k, Knob) for k in out):
        raise ValueError(f"{getattr(factory, '__name__', factory)!r}.KNOBS must hold Knob entries")
    return out


def path(name: str) -> Path:
    """The stored tuning file of controller ``name``."""
    return TUNED / f"{name}.json"


def stored(name: str, env_id: str) -> dict[str, float]:
    """The knob values the benchmark's tuning chose for controller ``name`` on ``env_id``.

    Raises:
        ValueError: no stored tuning of ``name``, or none for ``env_id``; the message names
            the command that makes it.
    """
    f = path(name)
    command = f"python -m agents.baseline_tuning {name} --env {env_id}"
    if not f.is_file():
        raise ValueError(f"no stored tuning of {name!r} ({f} is missing); run: {command}")
    plants = json.loads(f.read_text())["plants"]
    if env_id not in plants:
        raise ValueError(
            f"the stored tuning of {name!r} has no entry for {env_id!r} "
            f"(it has {sorted(plants)}); run: {command}"
        )
    return {k: float(v) for k, v in plants[env_id]["knobs"].items()}


def stored_or(name: str, env_id: str, start: dict[str, float]) -> dict[str, float]:
    """The stored tuning of ``name`` on ``env_id`` over ``start``, or ``start`` where there is
    none (the default of controllers whose sources publish no values)."""
    try:
        return {**start, **stored(name, env_id)}
    except ValueError:
        return dict(start)


__all__ = ["TUNED", "Knob", "knobs", "path", "stored", "stored_or"]
