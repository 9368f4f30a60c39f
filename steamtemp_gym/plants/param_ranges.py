"""Checks every plant's parameter dataclass runs on construction: declared types, finite
values, positive values where the plant requires them, and each value within its range.

A field's physical range is declared with the field, ``p_nom_MPa: float = ranged(24.8, 15.0,
31.0)`` (steamtemp_gym/checks.py, which checks types, finite values and ranges for every
configuration); a number without one must stay within :data:`DEFAULT_SPAN` of its default.
"""

from __future__ import annotations

import dataclasses
from typing import Any

from steamtemp_gym.checks import check_fields, is_real, ranged

#: Control interval and integrator sub-steps every plant accepts (s; count): beyond them a
#: step either loses the plant's dynamics or costs seconds.
DT_RANGE_S = (0.01, 60.0)
SUBSTEP_RANGE = (1, 50)
#: A parameter without a physical range of its own must stay within this factor of its
#: default (calibrated plants are not valid orders of magnitude away from their design).
DEFAULT_SPAN = 1e3
#: Ranges of the fields every plant has, unless the plant declares its own.
COMMON_RANGES = {"dt_s": DT_RANGE_S, "n_substeps": SUBSTEP_RANGE}


def field_range(f: dataclasses.Field) -> tuple[float, float] | None:
    """The declared range of a parameter field, or the common one of its name, or None."""
    return f.metadata.get("range", COMMON_RANGES.get(f.name))


def validate_params(params: Any, positive: tuple[str, ...] = ()) -> None:
    """Raise ValueError naming the field for a value of the wrong type, non-finite,
    non-positive (``positive``) or outside its range.

    Ranges: the field's own (:func:`ranged`), :data:`COMMON_RANGES` for ``dt_s`` and
    ``n_substeps``, and for every other number a factor :data:`DEFAULT_SPAN` either side of
    its default (a default of 0: |value| <= DEFAULT_SPAN).
    """
    name_cls = type(params).__name__
    check_fields(params, name_cls + ".{name}", "physical range", COMMON_RANGES)
    for f in dataclasses.fields(params):
        v = getattr(params, f.name)
        if not is_real(v) or field_range(f) is not None or not isinstance(f.default, (int, float)):
            continue
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


__all__ = [
    "COMMON_RANGES",
    "DEFAULT_SPAN",
    "DT_RANGE_S",
    "SUBSTEP_RANGE",
    "field_range",
    "ranged",
    "validate_params",
]
