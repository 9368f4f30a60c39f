"""The stored optima: the score's 1 of every reference episode, as its command sequence.

For every plant, named and held-out scenario and default seed, the package stores the
clairvoyant optimum's command sequence (agents/optimum.py) beside a record of it
(``agents/leaderboard/optima/index.jsonl``): the episode, the row's noise key, a digest of
the scenario, the exact return, the score's 0 on the episode, the certificate, the warm
starts and every refinement step with its CPU time, and the episode's metrics. The oracle
(agents/oracle.py) takes a stored sequence only where replaying it on the episode gives
the stored return (:func:`replays`: bit for bit on the machine that stored it; within
:data:`REPLAY_RTOL` on another CPU, whose compiled kernels may differ in the
last digits): a change of the code that keeps every trajectory reuses the store without
recomputing anything, and one that moves the plant is caught by the replay, and that
episode is solved anew. The 1 is then the replay's own return on this machine.

``python -m agents.leaderboard.optima`` (re)computes the store.
"""

from __future__ import annotations

import contextlib
import fcntl
import functools
import hashlib
import json
import os
from pathlib import Path
from typing import Any

import numpy as np

#: The package's store.
STORE = Path(__file__).with_name("leaderboard") / "optima"
INDEX = "index.jsonl"
ACTIONS = "actions"
#: How far (relative) a replay's return may be from the stored one and still count: the
#: floating-point differences of compiled kernels between CPUs were measured at 1e-13 of a
#: return; any change of the plant's dynamics moves an episode's return by far more.
REPLAY_RTOL = 1e-9


def replays(replayed: float, stored: float) -> bool:
    """Whether a replay's return is the stored one (:data:`REPLAY_RTOL`)."""
    return abs(replayed - stored) <= REPLAY_RTOL * max(1.0, abs(stored))


def scenario_digest(scenario: Any) -> str:
    """A digest of a resolved Scenario (its fields, in their repr)."""
    return hashlib.sha256(repr(scenario).encode()).hexdigest()[:16]


def actions_digest(a: np.ndarray) -> str:
    """A digest of an actions array's bytes."""
    return hashlib.sha256(np.ascontiguousarray(a).tobytes()).hexdigest()[:16]


def file_name(env_id: str, scenario: str, seed: int) -> str:
    """The actions file of an episode: ``<plant>.<scenario>.<seed>.npy``."""
    return f"{env_id.split('/')[-1]}.{scenario.replace(':', '-')}.{seed}.npy"


def load(store: Path = STORE) -> dict[tuple[str, str, int], dict]:
    """The stored records by (env id, scenario, seed); the last record of an episode wins."""
    path = store / INDEX
    out: dict[tuple[str, str, int], dict] = {}
    if path.is_file():
        for line in path.read_text(encoding="utf-8").splitlines():
            if line.strip():
                r = json.loads(line)
                out[r["env"], r["scenario"], r["seed"]] = r
    return out


def actions(record: dict, store: Path = STORE) -> np.ndarray | None:
    """The stored actions (steps, n_u) float32 of a record, None if its file is missing or
    is not the one the record names (its digest)."""
    path = store / ACTIONS / record["actions_file"]
    if not path.is_file():
        return None
    a = np.load(path, allow_pickle=False)
    return a if actions_digest(a) == record["actions_sha"] else None


@functools.lru_cache(maxsize=4)
def _by_episode(store: Path, stamp: tuple) -> dict[tuple[str, str, int], dict]:
    return {(r["env"], r["scenario_digest"], r["noise_key"]): r for r in load(store).values()}


def find(env_id: str, scenario: Any, noise_key: int, store: Path = STORE) -> dict | None:
    """The stored record of the episode of ``env_id`` under the resolved ``scenario`` with
    the row's ``noise_key``, None if there is none."""
    path = store / INDEX
    stamp = (path.stat().st_mtime_ns, path.stat().st_size) if path.is_file() else ()
    return _by_episode(store, stamp).get((env_id, scenario_digest(scenario), int(noise_key)))


@contextlib.contextmanager
def locked(store: Path):
    """Hold the store's lock (writers of the index take it, so lines are never lost)."""
    store.mkdir(parents=True, exist_ok=True)
    with open(store / ".lock", "a") as f:
        fcntl.flock(f, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(f, fcntl.LOCK_UN)


def write(store: Path, line: str, file: str, a: np.ndarray) -> None:
    """Append an episode's record (``line``, its JSON) and write its actions to ``file``
    (the actions first: a record never names a file that is not there)."""
    (store / ACTIONS).mkdir(parents=True, exist_ok=True)
    tmp = store / ACTIONS / (file + ".tmp")
    with open(tmp, "wb") as f:
        np.save(f, a, allow_pickle=False)
    os.replace(tmp, store / ACTIONS / file)
    with locked(store), open(store / INDEX, "a", encoding="utf-8") as f:
        f.write(line + "\n")


def update(store: Path, key: tuple[str, str, int], fields: dict, dumps: Any) -> None:
    """Set ``fields`` in the stored record of episode ``key`` (env id, scenario, seed),
    rewriting the index with one line per episode in a stable order (``dumps``: the JSON
    writer of the records)."""
    with locked(store):
        records = load(store)
        records[key] = {**records[key], **fields}
        text = "".join(dumps(records[k], sort_keys=True) + "\n" for k in sorted(records, key=str))
        tmp = store / (INDEX + ".tmp")
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, store / INDEX)
