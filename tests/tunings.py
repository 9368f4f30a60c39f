"""The stored tunings the ``<name>_tuned`` baselines read (baselines/tuning.py), for the tests
that run those rows on every plant: a plant the stored tunings have no entry for (one just
added, before ``python -m agents.baseline_tuning`` ran on it) is skipped there, the skip
naming the command that makes the tuning."""

from __future__ import annotations

import pytest

import baselines
from baselines import tuning


def missing(name: str, env_id: str) -> str | None:
    """Why the baseline row ``name`` has no stored tuning on ``env_id`` (``tuning.stored``'s
    message, naming the command that makes it); None if it has one or reads none. A missing
    tuning file gives None too: the row then fails, as a file of the shipped tunings is
    lost, not a plant's tuning not yet made."""
    source = baselines.tuning_source(name)
    if source == name or not tuning.path(source).is_file():
        return None
    try:
        tuning.stored(source, env_id)
    except ValueError as e:
        return str(e)
    return None


def skip_without_tuning(name: str, env_id: str) -> None:
    """Skip the calling test if the row ``name`` reads a stored tuning ``env_id`` lacks."""
    reason = missing(name, env_id)
    if reason:
        pytest.skip(f"row {name}: {reason}")
