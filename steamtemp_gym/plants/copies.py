"""Parameter fields copied into the packed parameters P.

Most slots of a plant's P hold one field of its Params, as it is or in SI units. The
plant's layout declares them as a mapping ``COPIED`` of slot name (a field of ``IP``) to
the field: its name where the value is copied as it is, a :class:`Copy` where it is
converted, e.g. ``{"WNOM": "W_nom_kg_s", "PNOM": Copy("p_nom_MPa", scale=1e6),
"TGN": kelvin("Tg_nom_C")}``. :func:`write_copies` writes them into P; the plant's packing
writes the derived slots (products, calibration results, tables) itself.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, NamedTuple

import numpy as np

from steamtemp_gym.plants.base import K0


class Copy(NamedTuple):
    """A Params field in a P slot: its value times ``scale`` where a scale is given, plus
    ``offset`` where an offset is given (each only then, so no other arithmetic touches
    the value)."""

    field: str
    scale: float | None = None
    offset: float | None = None

    def value(self, params: Any) -> Any:
        """The slot's value for ``params``."""
        v = getattr(params, self.field)
        if self.scale is not None:
            v = v * self.scale
        if self.offset is not None:
            v = v + self.offset
        return v


def kelvin(field: str) -> Copy:
    """A temperature field in C, copied in kelvin (``value + K0``)."""
    return Copy(field, offset=K0)


def as_copy(spec: str | Copy) -> Copy:
    """A ``COPIED`` entry as a :class:`Copy` (a bare field name copies the value as it is)."""
    return spec if isinstance(spec, Copy) else Copy(spec)


def write_copies(P: np.ndarray, IP: Any, copied: Mapping[str, str | Copy], params: Any) -> None:
    """Write every copied slot of ``copied`` (slot name -> field) into P, indexed by ``IP``."""
    for slot, spec in copied.items():
        P[getattr(IP, slot)] = as_copy(spec).value(params)
