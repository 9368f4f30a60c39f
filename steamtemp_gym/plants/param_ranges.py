"""Checks every plant's parameter dataclass runs on construction: declared types, finite
values, positive values where the plant requires them, and each value within its range.

A field's physical range is declared with the field, ``p_nom_MPa: float = ranged(24.8, 15.0,
31.0)``; a number without one must stay within :data:`DEFAULT_SPAN` of its default.
"""

from __future__ import annotations

import dataclasses
import typing
from typing import Any

import numpy as np

from steamtemp_gym.checks import is_finite, is_integer, is_real

#: Control interval and integrator sub-steps every plant accepts (s; count): beyond them a
#: step either loses the plant's dynamics or costs seconds.
DT_RANGE_S = (0.01, 60.0)
SUBSTEP_RANGE = (1, 50)
#: A parameter without a physical range of its own must stay within this factor of its
#: default (calibrated plants are not valid orders of magnitude away from their design).
DEFAULT_SPAN = 1e3
#: Ranges of the fields every plant has, unless the plant declares its own.
COMMON_RANGES = {"dt_s": DT_RANGE_S, "n_substeps": SUBSTEP_RANGE}


def ranged(default: float, lo: float, hi: float) -> Any:
    """A dataclass field with a default and the closed physical range [lo, hi] it must lie in."""
    if not lo <= default <= hi:
        raise ValueError(f"default {default!r} outside its own range [{lo}, {hi}]")
    return dataclasses.field(default=default, metadata={"range": (lo, hi)})


def field_range(f: dataclasses.Field) -> tuple[float, float] | None:
    """The declared range of a parameter field, or the common one of its name, or None."""
    return f.metadata.get("range", COMMON_RANGES.get(f.name))


def _check_type(cls_name: str, name: str, kind: Any, v: Any) -> None:
    """Raise ValueError unless v is a value of the declared field type (bool, int or float)."""
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
            f"{cls_name}.{name} must be of type {kind.__name__}, got {type(v).__name__} "
            f"{str(v)[:50]!r}"
        )


def validate_params(params: Any, positive: tuple[str, ...] = ()) -> None:
    """Raise ValueError naming the field for a value of the wrong type, non-finite,
    non-positive (``positive``) or outside its range.

    Ranges: the field's own (:func:`ranged`), :data:`COMMON_RANGES` for ``dt_s`` and
    ``n_substeps``, and for every other number a factor :data:`DEFAULT_SPAN` either side of
    its default (a default of 0: |value| <= DEFAULT_SPAN).
    """
    cls = type(params)
    name_cls = cls.__name__
    hints = typing.get_type_hints(cls)
    ranges = {}
    for f in dataclasses.fields(params):
        v = getattr(params, f.name)
        _check_type(name_cls, f.name, hints.get(f.name), v)
        if not is_real(v):
            continue
        if not is_finite(v):
            raise ValueError(f"{name_cls}.{f.name} must be finite, got {str(v)[:50]}")
        span = field_range(f)
        if span is not None:
            ranges[f.name] = span
        elif isinstance(f.default, (int, float)):
            d = abs(float(f.default))
            lo, hi = (d / DEFAULT_SPAN, d * DEFAULT_SPAN) if d > 0 else (0.0, DEFAULT_SPAN)
            if not lo <= abs(v) <= hi:
                raise ValueError(
                    f"{name_cls}.{f.name} = {v!r} is more than a factor {DEFAULT_SPAN:g} away "
                    f"from its default {f.default!r} (allowed |value| in [{lo:g}, {hi:g}])"
                )
    for name in positive:
        v = getattr(params, name)
        if not v > 0:
            raise ValueError(f"{name_cls}.{name} must be > 0, got {v!r}")
    for name, (lo, hi) in ranges.items():
        v = getattr(params, name)
        if not lo <= v <= hi:
            raise ValueError(
                f"{name_cls}.{name} = {v!r} is outside the physical range [{lo}, {hi}]"
            )
