"""Input checks shared by the options, parameters, scenarios, vector env and CLI: which
values count as numbers, and bounded excerpts of user input for error messages."""

from __future__ import annotations

import numbers
from typing import Any

import numpy as np


def is_real(value: Any) -> bool:
    """A real number (Python or numpy int or float), not a bool."""
    return isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))


def is_integer(value: Any) -> bool:
    """An integer (Python or numpy), not a bool."""
    return isinstance(value, numbers.Integral) and not isinstance(value, (bool, np.bool_))


def head(text: str, limit: int) -> str:
    """``text`` cut to ``limit`` characters, its start kept."""
    return text if len(text) <= limit else text[: limit - 3] + "..."


def tail(text: str, limit: int) -> str:
    """``text`` cut to ``limit`` characters, its end kept (the file name of a path)."""
    return text if len(text) <= limit else "..." + text[-(limit - 3) :]
