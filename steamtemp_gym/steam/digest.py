"""The digest that pins the steam tables: ``tables.py`` checks the data file against it at
import, and ``scripts/generate_steam_tables.py`` writes it after generating the file."""

from __future__ import annotations

import hashlib

import numpy as np


def tables_digest(data: dict[str, np.ndarray]) -> str:
    """SHA-256 over the array names, dtypes, shapes and bytes (file-format independent)."""
    h = hashlib.sha256()
    for key in sorted(data):
        a = np.ascontiguousarray(data[key])
        h.update(f"{key}|{a.dtype.str}|{a.shape}|".encode())
        h.update(a.tobytes())
    return h.hexdigest()
