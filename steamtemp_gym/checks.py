"""Input checks shared by the options, parameters, scenarios, vector env and CLI: which
values count as numbers, and bounded excerpts of user input for error messages."""

from __future__ import annotations

import math
import numbers
from typing import Any

import numpy as np


def is_real(value: Any) -> bool:
    """A real number (Python or numpy int or float), not a bool."""
    return isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))


def is_integer(value: Any) -> bool:
    """An integer (Python or numpy), not a bool."""
    return isinstance(value, numbers.Integral) and not isinstance(value, (bool, np.bool_))


def is_finite(value: Any) -> bool:
    """Whether the real number ``value`` is finite as a float: False for NaN, infinities and
    integers beyond the float range (any ``numbers.Real``: int, float, Fraction, numpy)."""
    try:
        return math.isfinite(float(value))
    except OverflowError:
        return False


def key_list(keys: Any) -> list:
    """``keys`` (of a user's dict) sorted for a message: strings first, any mix of types."""
    return sorted(keys, key=lambda k: (not isinstance(k, str), type(k).__name__, str(k)))


def head(text: str, limit: int) -> str:
    """``text`` cut to ``limit`` characters, its start kept."""
    return text if len(text) <= limit else text[: limit - 3] + "..."


def tail(text: str, limit: int) -> str:
    """``text`` cut to ``limit`` characters, its end kept (the file name of a path)."""
    return text if len(text) <= limit else "..." + text[-(limit - 3) :]
