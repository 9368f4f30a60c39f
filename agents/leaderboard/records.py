"""episodes.jsonl, the record of a leaderboard run: strict JSON rows, appended and synced as
each episode finishes; reading it back repairs the end a crash may leave (a last line cut off
mid-write). The row format is described in agents/leaderboard/cli.py and
docs/leaderboard_outputs.md.
"""

from __future__ import annotations

import json
import math
import os
import sys
from pathlib import Path
from typing import Any

import numpy as np

from agents.evaluation import metric_keys
from steamtemp_gym import plants
from steamtemp_gym.checks import head

#: Version of the row format of episodes.jsonl (part of the fingerprint).
SCHEMA = 2
EPISODES = "episodes.jsonl"
Key = tuple[str, str, str, int]  # env, scenario, policy, seed


def strict(obj: Any) -> Any:
    """A JSON-ready copy: numpy scalars to Python, non-finite floats to None."""
    if isinstance(obj, dict):
        return {str(k): strict(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [strict(v) for v in obj]
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        v = float(obj)
        return v if math.isfinite(v) else None
    return obj


def dumps(obj: Any, **kw: Any) -> str:
    """Strict JSON (no NaN/Infinity tokens)."""
    return json.dumps(strict(obj), allow_nan=False, **kw)


def read_record(path: Path) -> list[dict]:
    """Rows of an episodes.jsonl, repairing the end a crash may leave.

    A last line cut off mid-write is removed from the file (and a complete last line
    without its newline gets one), so rows appended next start on a line of their own.

    Raises:
        ValueError: a line other than the last is not an episode row (the file was edited).
    """
    if not path.is_file():
        return []
    data = path.read_bytes()
    lines = data.split(b"\n")
    rows = []
    for i, line in enumerate(lines):
        if not line.strip():
            continue
        try:
            rows.append(_row(line))
        except ValueError as exc:
            if i < len(lines) - 1:  # followed by a newline: not a crash mid-write
                raise ValueError(
                    f"{path} line {i + 1} is not an episode row ({head(str(exc), 80)}): "
                    f"{head(line.decode(errors='replace'), 80)!r}; fix or move the file"
                ) from None
            with path.open("r+b") as f:
                f.truncate(len(data) - len(line))
            print(f"note: dropped the incomplete last line of {path}", file=sys.stderr)
            return rows
    if data and not data.endswith(b"\n"):
        with path.open("ab") as f:
            f.write(b"\n")
    return rows


def _row(line: bytes) -> dict:
    """One episodes.jsonl line as a row (strict JSON, the key fields present; a finished
    episode of a known env has every metric, each a number or null)."""
    row = json.loads(line, parse_constant=_reject_constant)
    need = {"env", "scenario", "policy", "seed", "fingerprint"}
    if not isinstance(row, dict) or not need <= set(row):
        raise ValueError(f"not an object with the fields {sorted(need)}")
    if row.get("error") or row["env"] not in plants.PLANTS:
        return row
    metrics = row.get("metrics")
    if not isinstance(metrics, dict):
        raise ValueError("a finished episode's metrics must be an object")
    missing = [k for k in metric_keys(plants.plant_class(row["env"]).secondary) if k not in metrics]
    if missing:
        raise ValueError(f"metrics lack {missing[:5]}{' ...' if len(missing) > 5 else ''}")
    bad = [k for k, v in metrics.items() if v is not None and not _metric_value(v)]
    if bad:
        raise ValueError(
            f"metrics {bad[:5]} are not numbers an episode gives (a bool, or "
            f"beyond {METRIC_BOUND:g} in magnitude)"
        )
    return row


#: No metric of an episode is larger in magnitude (a return is at most the trip penalty,
#: 1e6, plus 1e4 per step at the largest reward weights).
METRIC_BOUND = 1e15


def _metric_value(v: object) -> bool:
    """Whether ``v`` is a number an episode's metric can take (not a bool, not beyond
    :data:`METRIC_BOUND`)."""
    return isinstance(v, (int, float)) and not isinstance(v, bool) and abs(v) <= METRIC_BOUND


def _reject_constant(name: str) -> None:
    raise ValueError(f"non-strict JSON token {name}")


class Record:
    """The append-only episodes.jsonl."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.f = path.open("a", encoding="utf-8")

    def write(self, row: dict) -> None:
        """Append one row and push it to disk."""
        self.f.write(dumps(row) + "\n")
        self.f.flush()
        os.fsync(self.f.fileno())

    def close(self) -> None:
        self.f.close()


def latest_rows(rows: list[dict]) -> dict[tuple[Key, str], dict]:
    """The last row of each (episode, fingerprint)."""
    out = {}
    for r in rows:
        out[(r["env"], r["scenario"], r["policy"], r["seed"]), r["fingerprint"]] = r
    return out
