"""Input checks shared by the options, parameters, scenarios, vector env and CLI: which
values count as numbers, bounded excerpts of user input for error messages, and the one
way a configuration dataclass checks its fields (declared types, finite values, declared
ranges: :func:`ranged`, :func:`check_fields`)."""

from __future__ import annotations

import dataclasses
import math
import numbers
import typing
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


def ranged(default: float, lo: float, hi: float, above: bool = False) -> Any:
    """A dataclass field with a default and the closed range [lo, hi] its value must lie in
    (with ``above``, (lo, hi]: lo itself excluded, for a quantity that must be positive)."""
    if not (lo < default <= hi if above else lo <= default <= hi):
        raise ValueError(f"default {default!r} outside its own range [{lo}, {hi}]")
    meta = {"range": (lo, hi), "above": True} if above else {"range": (lo, hi)}
    return dataclasses.field(default=default, metadata=meta)


def check_type(subject: str, kind: Any, v: Any) -> None:
    """Raise ValueError unless ``v`` is a value of the declared type ``kind`` (bool, int or
    float: any real number but a bool); other types are not checked."""
    if kind is bool:
        ok = isinstance(v, (bool, np.bool_))
    elif kind is int:
        ok = is_integer(v)
    elif kind is float:
        ok = is_real(v)
    else:
        return
    if not ok:
        raise ValueError(
            f"{subject} must be of type {kind.__name__}, got {type(v).__name__} {str(v)[:50]!r}"
        )


def check_fields(
    obj: Any,
    subject: str,
    label: str = "range",
    ranges: dict[str, tuple[float, float]] | None = None,
) -> None:
    """Raise ValueError for the first field of the dataclass ``obj`` whose value is not of
    its annotated type, is a number that is not finite, or lies outside its range (the
    field's own, :func:`ranged`, else ``ranges[name]``). ``subject`` names a field in the
    message (``"reward option {name!r}"``), ``label`` its range (``"physical range"``)."""
    hints = typing.get_type_hints(type(obj))
    for f in dataclasses.fields(obj):
        v, who = getattr(obj, f.name), subject.format(name=f.name)
        check_type(who, hints.get(f.name), v)
        if not is_real(v):
            continue
        if not is_finite(v):
            raise ValueError(f"{who} must be finite, got {str(v)[:50]}")
        span = f.metadata.get("range", (ranges or {}).get(f.name))
        if span is None:
            continue
        lo, hi = span
        above = f.metadata.get("above", False)
        if not (lo < v <= hi if above else lo <= v <= hi):
            raise ValueError(
                f"{who} = {v!r} is outside the {label} {'(' if above else '['}{lo:g}, {hi:g}]"
            )
