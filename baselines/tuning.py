"""Tunable constants of the baselines: a controller class lists its knobs in ``KNOBS`` and
its constructor takes each knob's name as a keyword (a float; ``None`` = the default)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Knob:
    """One tunable constant: its keyword ``name`` and its search range [lo, hi] (searched
    on a log scale where ``log``)."""

    name: str
    lo: float
    hi: float
    log: bool = True

    def __post_init__(self) -> None:
        if not (self.lo < self.hi) or (self.log and self.lo <= 0.0):
            raise ValueError(f"knob {self.name!r}: need lo < hi (and lo > 0 on a log scale), "
                             f"got [{self.lo}, {self.hi}]")  # fmt: skip

    def value(self, given: float | None, default: float) -> float:
        """``given`` checked against the range, or ``default`` where it is None."""
        if given is None:
            return float(default)
        x = float(given)
        if not (self.lo <= x <= self.hi):
            raise ValueError(f"{self.name}={given!r} is outside [{self.lo}, {self.hi}]")
        return x
