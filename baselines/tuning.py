"""Tunable knobs of the baseline controllers.

A tunable controller class lists its knobs in a class attribute ``KNOBS: tuple[Knob, ...]``
and its constructor accepts each knob's name as a keyword (a float; ``None`` = the
controller's default).
"""

from __future__ import annotations

import dataclasses
import math


@dataclasses.dataclass(frozen=True)
class Knob:
    """One tunable parameter: its keyword name and the search range [lo, hi].

    Attributes:
        name: The constructor keyword.
        lo: Lower end of the search range.
        hi: Upper end of the search range.
        log: Search on a log scale (the value must then be positive).
    """

    name: str
    lo: float
    hi: float
    log: bool = True

    def check(self, value: float | None, default: float) -> float:
        """``value`` as a float (``default`` for None).

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
