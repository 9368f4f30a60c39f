"""Named index slots for compiled code.

A plant packs its parameters, states and outputs into flat arrays; the kernels index
them by name through a module-level named tuple of consecutive integers,
``P[IP.tau_w]``, ``z[IZ.outlet_temp_C]``. numba reads such a tuple as a constant, so the
index compiles to the same machine code as a literal ``P[22]`` (a constant offset).
"""

from __future__ import annotations

from collections import namedtuple
from typing import Any


def slots(typename: str, *names: str, start: int = 0) -> Any:
    """A named tuple ``typename`` whose fields ``names`` hold start, start + 1, ..."""
    return namedtuple(typename, names)(*range(start, start + len(names)))


def blocks(typename: str, *sizes: tuple[str, int], start: int = 0) -> tuple[Any, int]:
    """Slots for consecutive blocks: (a named tuple of each block's first index, the index
    after the last block). ``sizes`` are (name, length) pairs in order."""
    offsets, at = [], start
    for _, n in sizes:
        offsets.append(at)
        at += n
    return namedtuple(typename, [name for name, _ in sizes])(*offsets), at
