"""The stored tunings the ``<name>_tuned`` baselines read (baselines/tuning.py), for the tests
that run those rows on every plant: a plant the stored tunings have no entry for (one just
added, before ``python -m agents.baseline_tuning`` ran on it) is skipped there, the skip
naming the command that makes the tuning."""

from __future__ import annotations

import json

import pytest

import baselines
from baselines import tuning


def missing(name: str, env_id: str) -> str | None:
    """The command that makes the stored tuning the baseline row ``name`` reads on ``env_id``,
    if its controller's tuning file has no entry for ``env_id``; None if it has one or the
    row reads no stored tuning. A missing tuning file gives None too: the row then fails,
    as a file of the shipped tunings is lost, not a plant's tuning not yet made."""
    source = baselines.tuning_source(name)
    if source == name:
        return None
    f = tuning.path(source)
    if not f.is_file() or env_id in json.loads(f.read_text())["plants"]:
        return None
    return f"python -m agents.baseline_tuning {source} --env {env_id}"


def skip_without_tuning(name: str, env_id: str) -> None:
    """Skip the calling test if the row ``name`` reads a stored tuning ``env_id`` lacks."""
    command = missing(name, env_id)
    if command:
        pytest.skip(f"{env_id} has no stored tuning of {baselines.tuning_source(name)} "
                    f"(row {name}); tune it with {command}")  # fmt: skip
