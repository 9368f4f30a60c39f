"""Stored reference episodes: the score's two ends shipped with the package.

Every normalized score needs the episodes of ``cascade_pi_ff`` (its 0) and of the oracle (its
1) on the same plant, scenario and seed, and the oracle's episodes are most of a run's
time. As D4RL and Minari ship ``ref_min_score`` / ``ref_max_score``, the package ships
those episodes' rows (``references.jsonl``: the rows of episodes.jsonl, metrics and all)
and the trace of each first seed the trend plots draw (``references.npz``), for every plant,
named and held-out scenario and default seed. Each row carries its fingerprint
(agents/leaderboard/plan.py): the provenance digest of exactly what it depends on (the
plant's package with the code all plants share, the evaluation, the policy's own code; the
scenario; the row format). The leaderboard takes a stored row where its fingerprint is the
run's and runs the episode where it is not (it says how many of each); with
``--recompute-references`` it runs them all.

Regenerate the files from a run that ran the references (``steamtemp-leaderboard`` writes
their rows to ``episodes.jsonl`` and their first seed's traces to ``reference_traces.npz``)::

    python -m agents.leaderboard.references --from leaderboard_out

tests/test_references.py recomputes one scenario per plant and checks the stored metrics
bit for bit.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from agents.leaderboard import summary
from agents.leaderboard.records import EPISODES, Key, dumps, read_record
from steamtemp_gym import scenarios

#: The policies whose episodes are stored: the score's 0 and its 1.
POLICIES = (summary.ZERO, summary.ONE)
#: The package data (next to this module).
ROWS = Path(__file__).with_name("references.jsonl")
TRACES = Path(__file__).with_name("references.npz")
#: The traces of a run's reference episodes (the first seed of each plant and scenario).
RUN_TRACES = "reference_traces.npz"
_SEP = "|"


def _trace_key(key: Key, fingerprint: str) -> str:
    env_id, sc, name, seed = key
    return _SEP.join((env_id, sc, name, str(seed), fingerprint))


def load(path: Path = ROWS) -> dict[tuple[Key, str], dict]:
    """The stored rows by (episode, fingerprint)."""
    if not path.is_file():
        return {}
    out = {}
    for r in read_record(path):
        if r.get("policy") in POLICIES and not r.get("error"):
            out[(r["env"], r["scenario"], r["policy"], r["seed"]), r["fingerprint"]] = r
    return out


def matching(plan: Any, stored: dict[tuple[Key, str], dict] | None = None
             ) -> tuple[list[dict], int]:  # fmt: skip
    """(rows, stale): the stored rows of the reference episodes ``plan`` runs whose
    fingerprint is the plan's, and how many of its reference episodes have none."""
    stored = load() if stored is None else stored
    rows, stale = [], 0
    for key in plan.grid():
        env_id, sc, name, _ = key
        if name not in POLICIES:
            continue
        row = stored.get((key, plan.fingerprints[env_id, sc, name]))
        if row is None:
            stale += 1
        else:
            rows.append(row)
    return rows, stale


def returns(env_id: str, scenario: str, policy: str, seeds: list[int],
            stored: dict[tuple[Key, str], dict] | None = None) -> tuple[np.ndarray, int]:
    """(returns, taken): the episode returns of ``policy`` (``cascade_pi_ff`` or ``oracle``)
    on ``env_id``'s ``scenario`` for ``seeds``, in order, as a leaderboard run gets them: the
    stored row where its fingerprint is the current code's, else the episode run now as the
    leaderboard runs it (agents/leaderboard/episodes.py); ``taken``: how many were stored.

    Raises:
        ValueError: a policy that is not one of :data:`POLICIES`.
        RuntimeError: an episode run now failed (naming it and why).
    """
    if policy not in POLICIES:
        raise ValueError(f"stored references are of {POLICIES}, not {policy!r}")
    from agents.leaderboard import episodes, plan

    fp = plan.episode_fingerprint(env_id, scenario, policy)
    stored = load() if stored is None else stored
    rows = {s: stored.get(((env_id, scenario, policy, s), fp)) for s in seeds}
    missing = [s for s in seeds if rows[s] is None]
    if missing:
        unit = episodes.Unit(env_id, scenario, scenarios.resolve(scenario, env_id), policy,
                             missing, fp, None)  # fmt: skip
        for row in episodes.run_unit(unit)[0]:
            if row.get("error"):
                raise RuntimeError(f"{policy} on {env_id} {scenario} seed {row['seed']}: "
                                   f"{row['error']}")  # fmt: skip
            rows[row["seed"]] = row
    return np.array([rows[s]["metrics"]["return"] for s in seeds]), len(seeds) - len(missing)


def trace(key: Key, fingerprint: str, path: Path = TRACES) -> dict[str, np.ndarray] | None:
    """The stored trace of one reference episode, None if there is none."""
    if not path.is_file():
        return None
    prefix = _trace_key(key, fingerprint) + _SEP
    with np.load(path) as z:
        found = {k[len(prefix) :]: z[k] for k in z.files if k.startswith(prefix)}
    return found or None


def save_traces(path: Path, traces: dict[tuple[Key, str], dict]) -> None:
    """Write traces {(episode, fingerprint): trace} to a compressed npz (float32 and the
    integer and boolean arrays as they are)."""
    arrays = {}
    for (key, fp), tr in traces.items():
        for name, v in tr.items():
            a = np.asarray(v)
            arrays[_trace_key(key, fp) + _SEP + name] = (
                a.astype(np.float32) if a.dtype.kind == "f" else a)  # fmt: skip
    tmp = path.with_name(path.name + ".tmp.npz")
    np.savez_compressed(tmp, **arrays)
    tmp.replace(path)


def read_traces(path: Path) -> dict[tuple[Key, str], dict]:
    out: dict[tuple[Key, str], dict] = {}
    if not path.is_file():
        return out
    with np.load(path) as z:
        for k in z.files:
            env_id, sc, name, seed, fp, channel = k.split(_SEP)
            out.setdefault(((env_id, sc, name, int(seed)), fp), {})[channel] = z[k]
    return out


def regenerate(run: Path, rows_path: Path = ROWS, traces_path: Path = TRACES) -> tuple[int, int]:
    """Merge a run's reference rows and traces into the stored files (a newer row of the
    same episode replaces the stored one); returns (rows, traces) written."""
    merged = {k[0]: r for k, r in load(rows_path).items()}
    for r in read_record(run / EPISODES):
        if r.get("policy") in POLICIES and not r.get("error") and r.get("metrics"):
            merged[r["env"], r["scenario"], r["policy"], r["seed"]] = r
    fps = {k: r["fingerprint"] for k, r in merged.items()}
    lines = [dumps(merged[k], sort_keys=True) for k in sorted(merged, key=str)]
    rows_path.write_text("".join(line + "\n" for line in lines), encoding="utf-8")
    traces = {k: v for k, v in read_traces(traces_path).items() if fps.get(k[0]) == k[1]}
    traces.update({k: v for k, v in read_traces(run / RUN_TRACES).items()
                   if fps.get(k[0]) == k[1]})  # fmt: skip
    save_traces(traces_path, traces)
    return len(lines), len(traces)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m agents.leaderboard.references",
                                 description=(__doc__ or "").split("\n")[0])  # fmt: skip
    ap.add_argument("--from", dest="run", required=True, metavar="OUT",
                    help="the --out directory of a steamtemp-leaderboard run that ran the "
                    "reference episodes")  # fmt: skip
    args = ap.parse_args(argv)
    run = Path(args.run)
    if not (run / EPISODES).is_file():
        ap.error(f"argument --from: no {EPISODES} in {str(run)!r}")
    n_rows, n_traces = regenerate(run)
    print(json.dumps({"rows": n_rows, "traces": n_traces, "file": str(ROWS)}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
