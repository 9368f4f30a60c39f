"""steamtemp-leaderboard: every policy on every env, scenario and seed.

Policies: by default the baselines (``baselines.NAMES``), the shipped trained agents
(``agents.shipped()``, named ``sb3:<algo>``) and two references that are listed but never
ranked: ``oracle`` (agents/oracle.py, the clairvoyant NMPC on the true plant, the 1 of
the normalized score; ``--no-oracle`` leaves it out, and the score with it) and
``frozen_valve``. The score's 0, ``cascade_pi_ff``, and the references join every run.
A shipped agent with several training runs in the zoo runs as one policy per run,
``sb3:<algo>@run<k>`` (``sb3:<algo>`` in ``--policies`` means all of them), and is
reported as one row over its runs (agents/leaderboard_report.py).
Model mismatch: when ``load_ramp_100_50`` is among the scenarios, every policy but the
references is also commissioned on the nominal plant and run unchanged on each perturbed
variant of the plant (rows ``mismatch:<variant>``, agents/leaderboard_mismatch.py): the
robustness column, kept out of the scores; ``--no-mismatch`` leaves them out.
``--policies`` also takes your own (agents/specs.py; examples/README.md): a trained
agent's files (``zoo:DIR``, or a path: a directory or model .zip written by
``steamtemp-train --out`` or an RL Zoo run) and ``module:callable``, a factory
``env -> Policy`` (``module`` a dotted name, with ``PYTHONPATH=.`` for the current
directory, or a .py file), scored like the shipped ones. ``--import MODULE`` imports a
module first (one that calls ``baselines.register`` or ``scenarios.register``).

Every flag is checked before anything runs: env ids, policies, scenarios (names and YAML
paths, resolved and built for each env with ``gym.make``), seeds and the output directory.
A bad value is an argparse error (usage, the flag, the valid choices; exit code 2) and nothing is
written (no output directory is created).

Where: ``--jobs`` local worker processes (default), or ``--backend ray``: one Ray task
per env, scenario and policy, on a new local Ray with ``--jobs`` CPUs or on an existing
cluster (``--ray-address``; the ``ray`` extra). The rows are the same either way.

Lists (``--envs``, ``--policies``, ``--scenarios``, ``--seeds``) are comma
separated; blanks around items and empty items are ignored; duplicates are dropped
(first occurrence kept, a note on stderr). Seeds are integers >= 0, or inclusive
ranges ``a-b`` (``0-4`` = ``0,1,2,3,4``), at most 10,000 in all.

Outputs in ``--out``:

- ``episodes.jsonl``: the record. One JSON object per line, appended, flushed and
  synced as each episode finishes (a crash or Ctrl-C loses nothing): ``env``,
  ``scenario`` (as given), ``policy``, ``seed``, ``fingerprint`` (a hash of the
  configuration: schema version, env id, the resolved scenario, policy name, the
  source of steamtemp_gym, baselines and agents/evaluation.py, and a trained agent's
  file), ``metrics`` (steamtemp_gym.metrics plus ``return`` and ``tripped``; a metric
  that does not apply, e.g. settling time without a setpoint step, is ``null``) and,
  for a failed episode, ``metrics: null``, ``error`` and ``traceback``.
- ``leaderboard.json``: the rows of this run's grid (env x scenario x policy x seed,
  in that order), rebuilt from ``episodes.jsonl`` at the end: the last line of each
  episode with the current fingerprint, without ``traceback``.
- ``leaderboard.md``: means over seeds per env, scenario and policy; failed episodes
  are listed below the tables.
- ``plots/``: one trend plot per env and scenario (the first seed; cascade_pi_ff, the oracle,
  cascade_pi and the plant's three best-ranked policies, every policy with
  ``--trend-all``), the scores (``scores.png``) and performance profiles (``profiles.png``).

All JSON is strict (no NaN or Infinity tokens).

An episode that raises (a policy error, a plant failure) is recorded as a row with
an ``error`` and the run goes on: a long run is not lost to one bad policy. At the end
the failures are listed and the exit code is 1.

Cost: the oracle's episodes are the long ones (it optimizes by rollouts of the plant at
every replanning instant); they are started first.

``--resume`` continues in an existing ``--out``: episodes already in
``episodes.jsonl`` with the same env, scenario, policy, seed and fingerprint and no
error are skipped; failed ones and ones whose configuration changed run again; the
outputs are rebuilt. A last line cut off by a crash is dropped. Without
``--resume`` an existing non-empty ``episodes.jsonl`` is an error (pass
``--resume``, choose another ``--out``, or move the file aside). ``--resume`` on a
new directory is an ordinary run.

One run at a time writes to an ``--out``: a second run started on it while the first
goes on is an argparse error (a lock on the directory). SIGTERM (``timeout``, CI runners,
schedulers) stops a run as Ctrl-C does (exit code 143 instead of 130), and the worker
processes end with it; they also end within a second of their parent's death by SIGKILL.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import hashlib
import importlib
import json
import logging
import math
import os
import re
import signal
import sys
import threading
import time
import traceback
from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import agents
import baselines
import steamtemp_gym
from agents import leaderboard_mismatch as mismatch
from agents import leaderboard_plots as plots
from agents import leaderboard_report as report
from agents import ray_backend, specs, stats
from agents.difficulty import FrozenValves
from agents.evaluation import metric_keys, run_batch, run_episode
from agents.oracle import Oracle
from steamtemp_gym import envs as envs_
from steamtemp_gym import plants, scenarios
from steamtemp_gym.checks import head, tail
from steamtemp_gym.scenarios import heldout

#: The named scenarios every plant has, then the held-out set (steamtemp_gym/scenarios/heldout).
NAMED_SCENARIOS = ("load_ramp_100_50", "load_ramp_50_100", "load_cycle", "setpoint_step",
                   "heat_imbalance_step", "load_following")  # fmt: skip
DEFAULT_SCENARIOS = NAMED_SCENARIOS + tuple(heldout.PREFIX + n for n in heldout.NAMES)
DEFAULT_SEEDS = "0-4"
#: The frozen-valve reference run on every plant (agents/difficulty.py).
REFERENCE = report.REFERENCE
#: Policies that join every run: the score's 0, its 1 and the frozen valve.
ALWAYS = (report.ZERO, report.ONE, REFERENCE)
#: Version of the row format of episodes.jsonl (part of the fingerprint).
SCHEMA = 2
EPISODES = "episodes.jsonl"
#: Upper bound on the number of seeds (a range such as ``0-1000000000`` is a typo).
MAX_SEEDS = 10_000
MAX_SEED = 2**63 - 1
#: Longest excerpt of an exception message quoted in an argparse error.
_EXCERPT = 400
_SEED_ITEM = re.compile(r"^(\d+)(?:-(\d+))?$")
Key = tuple[str, str, str, int]  # env, scenario, policy, seed


# --------------------------------------------------------------------------- plan
@dataclass
class Plan:
    """What a run does, checked before anything runs."""

    envs: list[str]
    scenarios: list[str]
    seeds: list[int]
    policies: dict[str, list[str]]  # env -> policy names available for it
    envs_made: dict[tuple[str, str], Any] = field(default_factory=dict)  # (env, scenario) -> env
    resolved: dict[tuple[str, str], Any] = field(default_factory=dict)  # -> Scenario
    fingerprints: dict[tuple[str, str, str], str] = field(default_factory=dict)
    imports: tuple[str, ...] = ()  # --import: modules every worker imports first
    travel_budget: float = stats.TRAVEL_BUDGET  # --travel-budget
    #: env -> mismatch label -> the variant's params (agents/leaderboard_mismatch.py)
    variants: dict[str, dict[str, dict]] = field(default_factory=dict)

    def scenarios_of(self, env_id: str) -> list[str]:
        """The run's scenarios on ``env_id``, then its mismatch labels."""
        return [*self.scenarios, *self.variants.get(env_id, {})]

    def policies_of(self, env_id: str, sc: str) -> list[str]:
        """The policies run on ``env_id`` under ``sc``: all but the references on a
        mismatch variant."""
        if sc in self.variants.get(env_id, {}):
            return [p for p in self.policies[env_id] if p not in report.REFERENCES]
        return self.policies[env_id]

    def grid(self) -> Iterable[Key]:
        """Every episode of the run, in run order."""
        for env_id in self.envs:
            for sc in self.scenarios_of(env_id):
                for name in self.policies_of(env_id, sc):
                    for seed in self.seeds:
                        yield env_id, sc, name, seed


def _items(ap: argparse.ArgumentParser, flag: str, text: str, key=None) -> list[str]:
    """Comma list: stripped, empty items ignored, duplicates dropped (first kept)."""
    items = [s.strip() for s in text.split(",")]
    items = [s for s in items if s]
    if not items:
        ap.error(f"argument {flag}: empty list {text!r}; give at least one comma-separated value")
    seen: dict[Any, str] = {}
    dups = []
    for s in items:
        k = key(s) if key else s
        if k in seen:
            dups.append(s)
        else:
            seen[k] = s
    if dups:
        print(f"note: {flag}: duplicates dropped: {dups}", file=sys.stderr)
    return list(seen.values())


def parse_seeds(ap: argparse.ArgumentParser, text: str) -> list[int]:
    """``--seeds``: integers >= 0 and inclusive ranges ``a-b``, comma separated, deduplicated."""
    seeds: list[int] = []
    for item in _items(ap, "--seeds", text):
        m = _SEED_ITEM.match(item)
        if not m:
            ap.error(
                f"argument --seeds: invalid seed {head(item, 40)!r}: seeds are integers >= 0 "
                "or inclusive ranges a-b, comma separated (e.g. '0,1,2' or '0-4')"
            )
        lo = int(m.group(1))
        hi = int(m.group(2)) if m.group(2) is not None else lo
        if hi < lo:
            ap.error(f"argument --seeds: empty range {item!r} (write a-b with a <= b)")
        if hi > MAX_SEED:
            ap.error(f"argument --seeds: seed {hi} is larger than {MAX_SEED}")
        if hi - lo + 1 + len(seeds) > MAX_SEEDS:
            ap.error(f"argument --seeds: more than {MAX_SEEDS} seeds ({item!r})")
        seeds.extend(range(lo, hi + 1))
    unique = list(dict.fromkeys(seeds))
    if len(unique) < len(seeds):
        dups = sorted(s for s, n in Counter(seeds).items() if n > 1)
        print(f"note: --seeds: duplicates dropped: {dups[:20]}", file=sys.stderr)
    return unique


def _available(env_id: str) -> list[str]:
    trained = [r for e, a in agents.shipped() if e == env_id
               for r in specs.training_runs(f"{specs.SB3_PREFIX}{a}", e)] if _sb3() else []
    return list(baselines.NAMES) + trained + [report.ONE, REFERENCE]


@functools.lru_cache(maxsize=1)
def _sb3() -> bool:
    """Whether the trained agents can run (the agents extra); a note on stderr if not."""
    import importlib.util

    if importlib.util.find_spec("stable_baselines3") is not None:
        return True
    if agents.shipped():
        print("note: the trained agents (sb3:*) are left out: they need the agents extra, "
              "pip install 'steamtemp-gym[agents]'", file=sys.stderr)  # fmt: skip
    return False


def _resolve(spec: str, env_id: str) -> Any:
    """A scenario name, ``heldout:<name>``, ``random`` or a YAML file as a Scenario (or
    ``random``): steamtemp_gym.scenarios.resolve, as gym.make takes them."""
    return scenarios.resolve(spec, env_id)


def _policies(ap: argparse.ArgumentParser, envs: list[str], text: str | None,
              oracle: bool = True) -> dict:  # fmt: skip
    """Policies per env; every requested name must parse (agents/specs.py) and be available
    for at least one env, and a factory's policy is built once on each env and checked.
    :data:`ALWAYS` joins every env (the oracle only with ``oracle``)."""
    always = [p for p in ALWAYS if oracle or p != report.ONE]
    if text is None:
        return {e: [p for p in _available(e) if oracle or p != report.ONE] for e in envs}
    names = _items(ap, "--policies", text)
    if not oracle and report.ONE in names:
        ap.error(f"argument --policies: {report.ONE} is listed but --no-oracle is given")
    parsed = {}
    for n in names:
        if n in (report.ONE, REFERENCE):
            continue
        try:
            parsed[n] = specs.parse(n)
        except ValueError as exc:
            ap.error(f"argument --policies: {head(str(exc), 1000)}")
        if parsed[n].kind in (specs.SHIPPED, specs.FILES) and not _sb3():
            ap.error(f"argument --policies: {head(n, 60)!r} is a trained agent: it needs the "
                     "agents extra, pip install 'steamtemp-gym[agents]'")  # fmt: skip

    def here(n: str, e: str) -> bool:
        return n not in parsed or parsed[n].available(e)

    nowhere = [n for n in names if not any(here(n, e) for e in envs)]
    if nowhere:
        ap.error(
            f"argument --policies: {[head(n, 60) for n in nowhere]} not available for envs "
            f"{envs}: only for {[sorted(parsed[n].envs) for n in nowhere]}"
        )
    out = {e: [n for n in names if here(n, e)] for e in envs}
    for e, pols in out.items():
        missing = [n for n in names if n not in pols]
        pols[:] = list(dict.fromkeys(r for n in pols for r in specs.training_runs(n, e)))
        if missing:
            print(f"note: {missing} not available for {e}; skipped there", file=sys.stderr)
        factories = [n for n in pols if n in parsed and parsed[n].kind == specs.FACTORY]
        env = gym.make(e) if factories else None
        for n in factories:
            try:
                parsed[n].make(e, env)
            except Exception as exc:  # noqa: BLE001 - any failure is a bad --policies value
                ap.error(f"argument --policies: {head(n, 60)!r} on {e}: "
                         f"{type(exc).__name__}: {head(str(exc), _EXCERPT)}")  # fmt: skip
        pols += [p for p in always if p not in pols]
    return out


def _env_id(name: str) -> str:
    """The id an --envs item names (with or without the namespace); itself if none."""
    try:
        return envs_.resolve_id(name)
    except ValueError:
        return name


def _scenario_key(spec: str) -> str:
    """Two spellings of one YAML file are one scenario."""
    if spec.endswith((".yaml", ".yml")):
        return os.path.realpath(spec)
    return spec


def _check_out(ap: argparse.ArgumentParser, out: Path, resume: bool) -> None:
    """The output directory can be created (or exists) and is writable; no stale record."""
    if out.exists() and not out.is_dir():
        ap.error(f"argument --out: {str(out)!r} exists and is not a directory")
    parent = out
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        ap.error(f"argument --out: {str(parent)!r} (in {str(out)!r}) is not a directory")
    if not os.access(parent, os.W_OK | os.X_OK):
        ap.error(f"argument --out: {str(out)!r} is not writable (no write access to {parent})")
    record = out / EPISODES
    if record.exists() and not record.is_file():
        ap.error(f"argument --out: {str(record)!r} is not a file")
    if not resume and record.is_file() and record.stat().st_size > 0:
        ap.error(
            f"argument --out: {str(record)!r} already holds episodes; pass --resume to "
            "continue that run, choose another --out, or move the file aside"
        )


def _source_digest() -> str:
    """Hash of the code that produces a row (physics, scenarios, metrics, baselines). The
    baselines' stored tunings are part of their rows' policy digests (agents/specs.py), so
    a new tuning reruns that controller's rows, not the oracle's or the agents'."""
    h = hashlib.sha256()
    roots = [Path(steamtemp_gym.__file__).parent, Path(baselines.__file__).parent]
    files = [f for r in roots for f in sorted(r.rglob("*.py"))]
    files += [Path(__file__).with_name(f) for f in ("evaluation.py", "difficulty.py", "oracle.py")]
    for f in files:
        h.update(f.read_bytes())
    return h.hexdigest()


def _policy_digest(env_id: str, name: str) -> str:
    """The policy's part of the fingerprint: the name, with the hash of a trained agent's
    files or of a factory's module (agents/specs.py)."""
    if name in (report.ONE, REFERENCE):
        return name
    return specs.parse(name).digest(env_id)


def fingerprint(env_id: str, scenario: Any, policy_digest: str, source_digest: str,
                params: dict | None = None) -> str:  # fmt: skip
    """Short hash of everything but the seed that decides an episode's result (``params``:
    a mismatch variant's plant parameters)."""
    sc = scenario.to_dict() if isinstance(scenario, scenarios.Scenario) else str(scenario)
    payload = {"schema": SCHEMA, "env": env_id, "scenario": sc, "policy": policy_digest,
               "source": source_digest}  # fmt: skip
    if params:
        payload["params"] = params
    text = json.dumps(payload, sort_keys=True, allow_nan=False, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def build_plan(ap: argparse.ArgumentParser, args: argparse.Namespace) -> Plan:
    """Check every flag (argparse errors, exit code 2) and build the envs; runs nothing."""
    imports = tuple(getattr(args, "modules", None) or ())
    for module in imports:  # first: they may register env ids, baselines and scenarios
        try:
            importlib.import_module(module)
        except Exception as exc:  # noqa: BLE001 - any failure is a bad --import value
            ap.error(f"argument --import: cannot import {head(module, 100)!r}: "
                     f"{type(exc).__name__}: {head(str(exc), _EXCERPT)}")  # fmt: skip
    envs = _items(ap, "--envs", args.envs, key=_env_id)
    unknown = [e for e in envs if _env_id(e) not in envs_.ids()]
    if unknown:
        ap.error(
            f"argument --envs: unknown {[head(e, 60) for e in unknown]}; "
            f"valid choices: {envs_.ids()} (the name after 'steamtemp/' is enough)"
        )
    envs = [_env_id(e) for e in envs]
    seeds = parse_seeds(ap, args.seeds)
    try:
        budget = float(args.travel_budget)
    except (TypeError, ValueError):
        budget = math.nan
    if not (math.isfinite(budget) and budget > 0.0):
        ap.error(f"argument --travel-budget: must be a finite number > 0 (a multiple of "
                 f"{report.ZERO}'s valve travel), got {head(str(args.travel_budget), 60)!r}")
    pols = _policies(ap, envs, args.policies, oracle=not args.no_oracle)
    scs = _items(ap, "--scenarios", args.scenarios, key=_scenario_key)
    if args.out is None or str(args.out).strip() == "":
        ap.error("argument --out: empty path")
    _check_out(ap, Path(args.out), args.resume)
    resolved = {}
    for env_id in envs:  # cheap pass first: names and YAML files
        for sc in scs:
            try:
                resolved[env_id, sc] = _resolve(sc, env_id)
            except Exception as exc:  # noqa: BLE001 - any failure is a bad --scenarios value
                ap.error(
                    f"argument --scenarios: {tail(sc, 80)!r} for {env_id}: "
                    f"{head(str(exc), 1000)}"  # the message lists every form
                )
    plan = Plan(envs=envs, scenarios=scs, seeds=seeds, policies=pols, resolved=resolved,
                imports=imports, travel_budget=budget)  # fmt: skip
    if not args.no_mismatch and mismatch.SCENARIO in scs:
        for env_id in envs:
            plan.variants[env_id] = mismatch.labels(env_id)
            for label in plan.variants[env_id]:
                resolved[env_id, label] = resolved[env_id, mismatch.SCENARIO]
    source = _source_digest()
    for env_id in envs:
        digests = {name: _policy_digest(env_id, name) for name in pols[env_id]}  # once per env
        for sc in scs:
            try:
                plan.envs_made[env_id, sc] = gym.make(env_id, scenario=resolved[env_id, sc])
            except Exception as exc:  # noqa: BLE001
                ap.error(
                    f"argument --scenarios: {tail(sc, 80)!r} for {env_id}: "
                    f"{type(exc).__name__}: {head(str(exc), _EXCERPT)}"
                )
        for sc in plan.scenarios_of(env_id):
            params = plan.variants.get(env_id, {}).get(sc)
            for name in plan.policies_of(env_id, sc):
                plan.fingerprints[env_id, sc, name] = fingerprint(
                    env_id, resolved[env_id, sc], digests[name], source, params
                )
    return plan


# --------------------------------------------------------------------------- record
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
    missing = [k for k in metric_keys(plants.plant_class(row["env"]).secondary)
               if k not in metrics]
    if missing:
        raise ValueError(f"metrics lack {missing[:5]}{' ...' if len(missing) > 5 else ''}")
    bad = [k for k, v in metrics.items() if v is not None and not isinstance(v, (int, float))]
    if bad:
        raise ValueError(f"metrics {bad[:5]} are not numbers")
    return row


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


def _latest(rows: list[dict]) -> dict[tuple[Key, str], dict]:
    """The last row of each (episode, fingerprint)."""
    out = {}
    for r in rows:
        out[(r["env"], r["scenario"], r["policy"], r["seed"]), r["fingerprint"]] = r
    return out


# --------------------------------------------------------------------------- episodes
def _make_policy(name: str, env_id: str, env):
    if name == REFERENCE:
        return FrozenValves(env)
    if name == report.ONE:
        return Oracle(env)
    return specs.parse(name).make(env_id, env)


@dataclass
class Unit:
    """One policy on one env and scenario for several seeds: one batch of the vector env."""

    env_id: str
    spec: str  # the scenario as given (row label)
    scenario: Any  # the resolved Scenario
    policy: str
    seeds: list[int]
    fingerprint: str
    trace_seed: int | None  # the seed whose trace is kept for the plot
    imports: tuple[str, ...] = ()  # modules to import first (--import)
    params: dict | None = None  # a mismatch variant's plant; the policy sees the nominal one


def _ok_row(u: Unit, seed: int, metrics: dict) -> dict:
    return {"env": u.env_id, "scenario": u.spec, "policy": u.policy, "seed": seed,
            "fingerprint": u.fingerprint, "metrics": metrics}  # fmt: skip


def run_unit(u: Unit) -> tuple[list[dict], dict | None]:
    """Rows of a unit (one per seed, in order) and the trace of ``u.trace_seed``.

    The seeds run side by side in the native vector env (:func:`run_batch`); if anything
    raises there, each seed runs alone (:func:`run_episode`, identical results) so that
    only the episodes that fail are recorded as failed.
    """
    for module in u.imports:  # a spawned worker or a Ray task has not imported them
        importlib.import_module(module)
    trace = None
    plant = {"params": u.params} if u.params else {}
    try:
        def venv(**kw: Any) -> Any:
            return gym.make_vec(u.env_id, num_envs=len(u.seeds), scenario=u.scenario,
                                vectorization_mode="vector_entry_point", **kw)  # fmt: skip

        unit = venv(**plant)
        model = venv() if plant else unit  # the plant the policy is commissioned on
        results = run_batch(unit, _make_policy(u.policy, u.env_id, model), u.seeds)
    except Exception:  # noqa: BLE001 - isolate the failing seeds below
        results = None
    if results is not None:
        rows = [_ok_row(u, s, r["metrics"]) for s, r in zip(u.seeds, results, strict=True)]
        if u.trace_seed is not None:
            trace = results[u.seeds.index(u.trace_seed)]["trace"]
        return rows, trace
    env = gym.make(u.env_id, scenario=u.scenario, **plant)
    try:
        model = gym.make(u.env_id, scenario=u.scenario) if plant else env
        policy = _make_policy(u.policy, u.env_id, model)
    except Exception as exc:  # noqa: BLE001 - every seed of it fails alike
        policy = exc
    rows = []
    for seed in u.seeds:
        try:
            if isinstance(policy, Exception):
                raise policy
            res = run_episode(env, policy, seed)
        except Exception as exc:  # noqa: BLE001 - recorded; the run goes on
            rows.append(_error_row((u.env_id, u.spec, u.policy, seed), u.fingerprint, exc))
            continue
        rows.append(_ok_row(u, seed, res["metrics"]))
        if seed == u.trace_seed:
            trace = res["trace"]
    return rows, trace


def _error_row(key: Key, fp: str, exc: BaseException) -> dict:
    env_id, sc, name, seed = key
    tb = "".join(traceback.format_exception(type(exc), exc, exc.__traceback__))
    return {"env": env_id, "scenario": sc, "policy": name, "seed": seed, "fingerprint": fp,
            "metrics": None, "error": head(f"{type(exc).__name__}: {exc}", 1000),
            "traceback": tb[-4000:]}  # fmt: skip


class Progress:
    """A progress bar with ETA over episodes on stderr (a line per 10 % when not a tty)."""

    def __init__(self, total: int, stream=sys.stderr) -> None:
        self.total, self.done, self.stream = total, 0, stream
        self.t0 = time.time()
        self.tty = stream.isatty()
        self.last_pct = -10

    def update(self, n: int) -> None:
        self.done += n
        el = time.time() - self.t0
        eta = el / self.done * (self.total - self.done) if self.done else 0.0
        pct = 100 * self.done / max(self.total, 1)
        bar = "#" * int(pct / 4) + "." * (25 - int(pct / 4))
        text = (f"[{bar}] {self.done}/{self.total} episodes {pct:3.0f} %  "
                f"elapsed {_mmss(el)}  ETA {_mmss(eta)}")  # fmt: skip
        if self.tty:
            end = "\n" if self.done >= self.total else ""
            print("\r" + text, end=end, file=self.stream, flush=True)
        elif pct >= self.last_pct + 10 or self.done >= self.total:
            self.last_pct = pct
            print(text, file=self.stream, flush=True)


def _mmss(s: float) -> str:
    return f"{int(s // 60)}:{int(s % 60):02d}"


def _units(plan: Plan, done: dict) -> list[Unit]:
    """What is left to run, one unit per env, scenario and policy; the oracle's first
    (they take the longest: the pool then ends with short units on every worker)."""
    out = []
    for env_id in plan.envs:
        for sc in plan.scenarios_of(env_id):
            params = plan.variants.get(env_id, {}).get(sc)
            for name in plan.policies_of(env_id, sc):
                fp = plan.fingerprints[env_id, sc, name]
                todo = [s for s in plan.seeds
                        if not _finished(done.get(((env_id, sc, name, s), fp)))]  # fmt: skip
                if todo:
                    keep = plan.seeds[0] if plan.seeds[0] in todo and params is None else None
                    out.append(Unit(env_id, sc, plan.resolved[env_id, sc], name, todo, fp, keep,
                                    plan.imports, params))  # fmt: skip
    return sorted(out, key=lambda u: u.policy != report.ONE)  # stable: run order otherwise


def _finished(row: dict | None) -> bool:
    return row is not None and not row.get("error")


def _pool(jobs: int):
    """A process pool: fork where available (workers start with the compiled kernels),
    but spawn once torch is loaded here: a child forked after torch started its thread
    pools deadlocks in its first torch operation (seen in the test suite, loading a PPO
    agent in a worker). Spawned workers load the kernels from the disk cache."""
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor

    fork = "fork" in mp.get_all_start_methods() and "torch" not in sys.modules
    return ProcessPoolExecutor(max_workers=jobs, mp_context=mp.get_context(
        "fork" if fork else "spawn"), initializer=_worker_start,
        initargs=(os.getpid(),))  # fmt: skip


#: How often a pool worker checks that the process that started it is alive (s).
PARENT_POLL_S = 0.5


def _worker_start(parent: int) -> None:
    """In a pool worker: SIGTERM ends it (not the handler a forked worker inherits), and it
    ends itself within :data:`PARENT_POLL_S` of its parent's death, SIGKILL included."""
    signal.signal(signal.SIGTERM, signal.SIG_DFL)

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(PARENT_POLL_S)
        os._exit(1)

    threading.Thread(target=watch, name="parent-watch", daemon=True).start()


def _local_results(units: list[Unit], jobs: int):
    """(unit, run_unit's result) as they finish, in ``jobs`` local processes."""
    if jobs <= 1 or len(units) <= 1:
        for u in units:
            yield u, run_unit(u)
        return
    import multiprocessing as mp
    from concurrent.futures import as_completed

    with _pool(jobs) as pool:
        futures = {pool.submit(run_unit, u): u for u in units}
        try:
            for fut in as_completed(futures):
                yield futures[fut], fut.result()
        except BaseException:
            for f in futures:
                f.cancel()
            for worker in mp.active_children():  # the pool's: stop their units now
                worker.terminate()
            raise


def _ray_results(units: list[Unit], jobs: int, address: str | None):
    """(unit, run_unit's result) as they finish, each unit a Ray task (one CPU): on a new
    local Ray with ``jobs`` CPUs, or on the cluster at ``address``."""
    return ray_backend.results(run_unit, units, jobs, address)


def _execute(plan: Plan, units: list[Unit], jobs: int, record: Record, on_trace,
             backend: str = "local", address: str | None = None) -> int:  # fmt: skip
    """Run the units (in ``jobs`` processes or as Ray tasks), appending rows as they
    finish. Failed count."""
    progress = Progress(sum(len(u.seeds) for u in units))
    failed = 0
    results = (_ray_results(units, jobs, address) if backend == "ray"
               else _local_results(units, jobs))  # fmt: skip
    for u, (rows, trace) in results:
        for row in rows:
            record.write(row)
            if row.get("error"):
                failed += 1
                print(f"\nFAILED {u.env_id} {u.spec} {u.policy} seed {row['seed']}: "
                      f"{row['error']}", file=sys.stderr)  # fmt: skip
        on_trace(u, trace)
        progress.update(len(rows))
    return failed


# --------------------------------------------------------------------------- outputs
def _plot_path(out: Path, env_id: str, scenario: str) -> Path:
    stem = Path(scenario).stem if _is_file(scenario) else scenario.replace(":", "_")
    return out / "plots" / f"{env_id.split('/')[-1]}__{stem}.png"


def _is_file(spec: str) -> bool:
    return spec.lower().endswith((".yaml", ".yml"))


class Plots:
    """Trend plots per env and scenario, drawn for a plant as soon as all its episodes have
    finished (the policies shown depend on the plant's scores: plots.trend_policies). A
    trained agent with several training runs is shown by its first run."""

    def __init__(self, out: Path, plan: Plan, units: list[Unit], every: bool = False) -> None:
        self.out, self.plan, self.every = out, plan, every
        self.pending = Counter(u.env_id for u in units)
        self.traces: dict[tuple[str, str], dict[str, dict]] = {}
        self.trace_run: dict[tuple[str, str, str], int] = {}  # the run of a trace kept

    def add(self, u: Unit, trace: dict | None) -> None:
        name, run = specs.split_run(u.policy)
        key = (u.env_id, u.spec, name)
        if trace is not None and (run or 0) <= self.trace_run.get(key, run or 0):
            self.trace_run[key] = run or 0
            self.traces.setdefault((u.env_id, u.spec), {})[name] = trace
        self.pending[u.env_id] -= 1
        if self.pending[u.env_id] == 0:
            for sc in self.plan.scenarios:
                self.draw(u.env_id, sc)

    def shown(self, env_id: str) -> tuple[list[str], dict[str, str]]:
        """The policies a plant's trends show and their legend notes (rank and score)."""
        rows = [r for r in _grid_rows(self.out, self.plan) if r["env"] == env_id]
        ok = [r for r in rows if not r.get("error")]
        plant = (report.summarize(ok, _run_info(self.plan, [env_id]))[0]["plants"][env_id]
                 if ok else {})  # fmt: skip
        names = plots.trend_policies(plant, report.agent_names(self.plan.policies[env_id]),
                                     self.every)  # fmt: skip
        notes = {}
        for name in names:
            e = plant.get("policies", {}).get(name, {})
            iqm = e.get("normalized_score", {}).get("iqm", {}).get("value")
            if iqm is not None:
                notes[name] = (f"#{e['rank']}, " if "rank" in e else "") + f"score {iqm:.2f}"
        return names, notes

    def draw(self, env_id: str, sc: str) -> None:
        """The trend plot of one env and scenario (traces missing after a resume re-run)."""
        traces = self.traces.pop((env_id, sc), {})
        seed = self.plan.seeds[0]
        env = self.plan.envs_made[env_id, sc]
        names, notes = self.shown(env_id)
        for name in names:
            if name not in traces:
                try:
                    runs = [r for r in self.plan.policies[env_id]
                            if specs.split_run(r)[0] == name]  # fmt: skip
                    pol = _make_policy(runs[0] if runs else name, env_id, env)
                    traces[name] = run_episode(env, pol, seed)["trace"]
                except Exception as exc:  # noqa: BLE001 - that episode is in the record
                    print(f"note: no trace of {name} seed {seed} for the plot: {exc}",
                          file=sys.stderr)  # fmt: skip
        order = [n for n in names if n in traces]
        if order:
            title = (self.plan.resolved[env_id, sc].name if _is_file(sc) else sc)
            plots.trend(_plot_path(self.out, env_id, sc), env, env_id, title,
                        {n: traces[n] for n in order}, seed,
                        colors=plots.policy_colors(names), notes=notes)  # fmt: skip

    def missing(self) -> list[tuple[str, str]]:
        """Groups without a plot file (after a resume with nothing left to run)."""
        groups = [(e, s) for e in self.plan.envs for s in self.plan.scenarios]
        return [g for g in groups
                if g[0] not in self.pending and not _plot_path(self.out, *g).exists()]  # fmt: skip


def _grid_rows(out: Path, plan: Plan) -> list[dict]:
    """The rows of the run's grid from episodes.jsonl: the last line of each episode with
    the current fingerprint, without its traceback."""
    latest = _latest(read_record(out / EPISODES))
    rows = []
    for key in plan.grid():
        r = latest.get((key, plan.fingerprints[key[:3]]))
        if r is not None:
            rows.append({k: v for k, v in r.items() if k != "traceback"})
    return rows


def _run_info(plan: Plan, envs: list[str] | None = None) -> dict[str, Any]:
    """leaderboard.json's ``run``: what ran, with the statistics' settings."""
    return {"envs": envs or plan.envs, "scenarios": plan.scenarios, "policies": plan.policies,
            "seeds": plan.seeds, "steamtemp_gym_version": steamtemp_gym.__version__,
            "n_bootstrap": stats.N_BOOTSTRAP, "confidence": stats.CONFIDENCE,
            "reference": report.REFERENCE, "versus": report.VERSUS,
            "travel_budget": plan.travel_budget,
            "mismatch": {e: [v.removeprefix(mismatch.PREFIX) for v in plan.variants.get(e, {})]
                         for e in envs or plan.envs if plan.variants.get(e)}}  # fmt: skip


def _rebuild(out: Path, plan: Plan, figures: bool = True) -> tuple[list[dict], dict | None]:
    """leaderboard.json, leaderboard.md and the summary figures from episodes.jsonl."""
    rows = _grid_rows(out, plan)
    run = _run_info(plan)
    summary, norm = (None, {})
    if any(not r.get("error") for r in rows):
        summary, norm = report.summarize(rows, run)
    doc = dict(summary or {"schema_version": report.SCHEMA_VERSION, "run": run, "plants": {},
                           "ranking": []})  # fmt: skip
    doc["episodes"] = rows
    (out / "leaderboard.json").write_text(dumps(doc, indent=1) + "\n")
    (out / "leaderboard.md").write_text(report.markdown(doc, rows))
    if figures and summary is not None:
        (out / "plots").mkdir(parents=True, exist_ok=True)
        plots.bars(out / "plots" / "scores.png", summary)
        if any(norm.values()):
            plots.profiles(out / "plots" / "profiles.png", norm, len(plan.seeds),
                           order=plots.figure_order(summary), highlight={
                               e: plots.trend_policies(summary["plants"][e],
                                                       report.agent_names(plan.policies[e]))
                               for e in summary["plants"]})  # fmt: skip
    return rows, summary


#: --out directories this process locked (resolved path -> descriptor)
_LOCKS: dict[str, int] = {}


def _lock_out(out: Path) -> int | None:
    """An exclusive lock on the directory ``out``, held until this process ends or runs
    again on it (a run in this process has ended by then), as its descriptor; None if
    another process holds it. No lock (-1) where there is no flock."""
    try:
        import fcntl
    except ImportError:  # not a POSIX system
        return -1
    key = os.path.realpath(out)
    if key in _LOCKS:
        os.close(_LOCKS.pop(key))
    fd = os.open(out, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        os.close(fd)
        return None
    _LOCKS[key] = fd
    return fd


class Terminated(KeyboardInterrupt):
    """SIGTERM (``timeout``, CI runners, schedulers): the run stops as on Ctrl-C."""


def _on_sigterm(signum: int, frame: Any) -> None:
    raise Terminated


@contextlib.contextmanager
def _sigterm_stops():
    """SIGTERM raises :class:`Terminated` in this block (the handler before is restored)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    before = signal.signal(signal.SIGTERM, _on_sigterm)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, before)


def make_parser() -> argparse.ArgumentParser:
    """The CLI's argument parser."""
    doc = __doc__ or ""
    ap = argparse.ArgumentParser(
        prog="steamtemp-leaderboard",
        description=doc.split("\n")[0],
        epilog=doc.split("\n", 2)[2],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ap.add_argument("--envs", default=",".join(steamtemp_gym.ENV_IDS),
                    help="comma list of env ids, with or without the steamtemp/ namespace "
                    "(default: all: %(default)s)")  # fmt: skip
    ap.add_argument("--policies", default=None,
                    help="comma list of baseline names, sb3:<algo>, zoo:DIR or paths to a "
                    "trained agent's files, and module:callable factories (default: every "
                    "baseline of baselines.NAMES and every shipped agent sb3:<algo> of "
                    "agents.shipped(); cascade_pi_ff, oracle and frozen_valve are always "
                    "added)")  # fmt: skip
    ap.add_argument("--import", dest="modules", action="append", default=[], metavar="MODULE",
                    help="import this module first, in every worker too (one that registers "
                    "baselines, scenarios or env variants; repeatable)")  # fmt: skip
    ap.add_argument("--no-oracle", action="store_true",
                    help="leave the oracle out (its episodes are the run's longest); the "
                    "normalized score is then not computed (default: off)")  # fmt: skip
    ap.add_argument("--no-mismatch", action="store_true",
                    help="leave out the model-mismatch episodes (every policy but the "
                    "references, commissioned on the nominal plant, on each variant of "
                    "perturb.MISMATCH under load_ramp_100_50; run when load_ramp_100_50 is "
                    "among --scenarios) and the robustness column (default: off)")  # fmt: skip
    ap.add_argument("--travel-budget", type=str, default=str(stats.TRAVEL_BUDGET),
                    metavar="X", help="a policy is admissible on a plant when its mean valve "
                    "travel there is at most X times cascade_pi_ff's and it never trips; "
                    "rankings list admissible policies first (default: %(default)s)")  # fmt: skip
    ap.add_argument("--scenarios", default=",".join(DEFAULT_SCENARIOS),
                    help="comma list of scenario names, heldout:<name>, random (the seeded "
                    "training distribution) or YAML paths, as gym.make(..., scenario=...) "
                    "takes them (default: %(default)s)")  # fmt: skip
    ap.add_argument("--seeds", default=DEFAULT_SEEDS,
                    help="integers >= 0 or ranges a-b (default: %(default)s)")  # fmt: skip
    ap.add_argument("--out", default="leaderboard_out",
                    help="output directory (default: %(default)s)")  # fmt: skip
    ap.add_argument("--trend-all", action="store_true",
                    help="trend plots show every policy (default: cascade_pi_ff, the oracle, "
                    "cascade_pi and the plant's three best-ranked policies)")  # fmt: skip
    ap.add_argument("--resume", action="store_true",
                    help="continue in --out: skip the episodes already in its episodes.jsonl "
                    "(default: off)")  # fmt: skip
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1,
                    help="worker processes (CPUs of a new local Ray); 1 runs in this "
                    "process (default: the number of CPUs, %(default)s)")  # fmt: skip
    ap.add_argument("--backend", choices=("local", "ray"), default="local",
                    help="local: a process pool; ray: one Ray task per env, scenario and "
                    "policy (needs the ray extra: pip install 'steamtemp-gym[ray]'); rows "
                    "are the same (default: %(default)s)")  # fmt: skip
    ap.add_argument("--ray-address", default=None, metavar="ADDRESS",
                    help="with --backend ray: an existing Ray cluster (e.g. ray://host:10001 "
                    "or auto); default: start a local Ray with --jobs CPUs")  # fmt: skip
    return ap


class _Stderr(logging.StreamHandler):
    """A handler writing to whatever ``sys.stderr`` is when a line is logged (a stream
    bound once would outlive a caller's redirection of stderr and write to a closed file)."""

    @property
    def stream(self):  # type: ignore[override]
        return sys.stderr

    @stream.setter
    def stream(self, value) -> None:
        pass


def _show_library_log() -> None:
    """steamtemp_gym's INFO lines (e.g. the notice while kernels compile) on stderr."""
    log = logging.getLogger("steamtemp_gym")
    if not log.handlers:
        handler = _Stderr()
        handler.setFormatter(logging.Formatter("%(message)s"))  # lines name steamtemp_gym
        log.addHandler(handler)
    log.setLevel(logging.INFO)


def main(argv: list[str] | None = None) -> None:
    """Run the leaderboard (see the module docstring)."""
    _show_library_log()
    ap = make_parser()
    args = ap.parse_args(argv)
    if args.jobs < 1:
        ap.error(f"argument --jobs: must be >= 1, got {args.jobs}")
    if args.ray_address is not None and args.backend != "ray":
        ap.error("argument --ray-address: only with --backend ray")
    if args.backend == "ray" and not ray_backend.installed():
        ap.error(f"argument --backend: ray is not installed; {ray_backend.INSTALL}")
    plan = build_plan(ap, args)
    out = Path(args.out)
    try:
        out.mkdir(parents=True, exist_ok=True)
        lock = _lock_out(out)
    except OSError as exc:
        ap.error(f"argument --out: cannot write {str(out)!r}: {exc.strerror or exc}")
    if lock is None:
        ap.error(f"argument --out: {str(out)!r} is in use by another steamtemp-leaderboard "
                 "run; wait for it to end or choose another --out")  # fmt: skip
    try:
        done = _latest(read_record(out / EPISODES)) if args.resume else {}
    except (OSError, ValueError) as exc:
        ap.error(f"argument --resume: {head(str(exc), _EXCERPT)}")
    try:
        record = Record(out / EPISODES)
    except OSError as exc:
        ap.error(f"argument --out: cannot write {str(out)!r}: {exc.strerror or exc}")
    t0 = time.time()
    units = _units(plan, done)
    figures = Plots(out, plan, units, every=args.trend_all)
    try:
        with _sigterm_stops():
            _execute(plan, units, args.jobs, record, figures.add, args.backend,
                     args.ray_address)  # fmt: skip
            for key in figures.missing():
                figures.draw(*key)
    except KeyboardInterrupt as exc:
        record.close()
        _rebuild(out, plan, figures=False)
        print(f"\ninterrupted: finished episodes are in {out / EPISODES}; "
              "run the same command with --resume to continue", file=sys.stderr)  # fmt: skip
        raise SystemExit(143 if isinstance(exc, Terminated) else 130) from None
    record.close()
    rows, summary = _rebuild(out, plan)
    if summary is not None:
        print(report.console(summary))
    bad = [r for r in rows if r.get("error")]
    n_run = sum(len(u.seeds) for u in units)
    print(f"wrote {out / 'leaderboard.json'}, {out / 'leaderboard.md'} and plots/ "
          f"({len(rows)} episodes, {n_run} run now, {time.time() - t0:.0f} s)")  # fmt: skip
    if bad:
        print(f"{len(bad)} of {len(rows)} episodes failed:", file=sys.stderr)
        for r in bad[:10]:
            print(f"  {r['env']} {r['scenario']} {r['policy']} seed {r['seed']}: {r['error']}",
                  file=sys.stderr)  # fmt: skip
        print("fix the cause and run the same command with --resume to run only those again",
              file=sys.stderr)  # fmt: skip
        raise SystemExit(1)


if __name__ == "__main__":
    main()
