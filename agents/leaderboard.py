"""steamtemp-leaderboard: every policy on every env, scenario and seed.

Policies: the baselines (``baselines.NAMES``) and the shipped trained agents
(``agents.shipped()``, named ``sb3:<algo>``). Every flag is checked before anything
runs: env ids, policies, scenarios (names and YAML paths, resolved and built for each
env with ``gym.make``), seeds and the output directory. A bad value is an
argparse error (usage, the flag, the valid choices; exit code 2) and nothing is
written (no output directory is created).

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
- ``plots/``: one trend plot per env and scenario (all policies, the first seed without an error).

All JSON is strict (no NaN or Infinity tokens).

An episode that raises (a policy error, a plant failure) is recorded as a row with
an ``error`` and the run goes on: a 3-hour leaderboard is not lost to one bad
policy. At the end the failures are listed and the exit code is 1.

``--resume`` continues in an existing ``--out``: episodes already in
``episodes.jsonl`` with the same env, scenario, policy, seed and fingerprint and no
error are skipped; failed ones and ones whose configuration changed run again; the
outputs are rebuilt. A last line cut off by a crash is dropped. Without
``--resume`` an existing non-empty ``episodes.jsonl`` is an error (pass
``--resume``, choose another ``--out``, or move the file aside). ``--resume`` on a
new directory is an ordinary run.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import os
import re
import sys
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
from agents.evaluation import run_episode
from steamtemp_gym import scenarios
from steamtemp_gym.checks import head, tail

DEFAULT_SCENARIOS = ("load_ramp_100_50", "load_ramp_50_100", "setpoint_step",
                     "heat_imbalance_step", "load_following")  # fmt: skip
TABLE_METRICS = ("iae_K_s", "max_abs_dev_K", "time_outside_5K_s", "settling_time_s",
                 "spray_used_kg", "valve_travel", "valve_reversals", "return")  # fmt: skip
#: Version of the row format of episodes.jsonl and leaderboard.json (part of the fingerprint).
SCHEMA = 1
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
    fingerprints: dict[tuple[str, str, str], str] = field(default_factory=dict)

    def grid(self) -> Iterable[Key]:
        """Every episode of the run, in run order."""
        for env_id in self.envs:
            for sc in self.scenarios:
                for name in self.policies[env_id]:
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
    return list(baselines.NAMES) + [f"sb3:{a}" for e, a in agents.shipped() if e == env_id]


def _policies(ap: argparse.ArgumentParser, envs: list[str], text: str | None) -> dict:
    """Policies per env; every requested name must be available for at least one env."""
    if text is None:
        return {e: _available(e) for e in envs}
    names = _items(ap, "--policies", text)
    everywhere = sorted({p for e in envs for p in _available(e)})
    unknown = [n for n in names if n not in everywhere]
    if unknown:
        ap.error(
            f"argument --policies: unknown {[head(n, 60) for n in unknown]} for envs "
            f"{envs}; valid choices: {everywhere}"
        )
    out = {e: [n for n in names if n in _available(e)] for e in envs}
    for e, pols in out.items():
        missing = [n for n in names if n not in pols]
        if missing:
            print(f"note: {missing} not available for {e}; skipped there", file=sys.stderr)
    return out


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
    """Hash of the code that produces a row (physics, scenarios, metrics, baselines)."""
    h = hashlib.sha256()
    roots = [Path(steamtemp_gym.__file__).parent, Path(baselines.__file__).parent]
    files = [f for r in roots for f in sorted(r.rglob("*.py"))]
    files.append(Path(__file__).with_name("evaluation.py"))
    for f in files:
        h.update(f.read_bytes())
    return h.hexdigest()


def _policy_digest(env_id: str, name: str) -> str:
    if not name.startswith("sb3:"):
        return name
    path = agents.ZOO / f"{env_id.replace('/', '__')}__{name[4:]}.zip"
    return name + ":" + hashlib.sha256(path.read_bytes()).hexdigest()


def fingerprint(env_id: str, scenario: Any, policy_digest: str, source_digest: str) -> str:
    """Short hash of everything but the seed that decides an episode's result."""
    sc = scenario.to_dict() if isinstance(scenario, scenarios.Scenario) else str(scenario)
    payload = {"schema": SCHEMA, "env": env_id, "scenario": sc, "policy": policy_digest,
               "source": source_digest}  # fmt: skip
    text = json.dumps(payload, sort_keys=True, allow_nan=False, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def build_plan(ap: argparse.ArgumentParser, args: argparse.Namespace) -> Plan:
    """Check every flag (argparse errors, exit code 2) and build the envs; runs nothing."""
    envs = _items(ap, "--envs", args.envs)
    unknown = [e for e in envs if e not in steamtemp_gym.ENV_IDS]
    if unknown:
        ap.error(
            f"argument --envs: unknown {[head(e, 60) for e in unknown]}; "
            f"valid choices: {list(steamtemp_gym.ENV_IDS)}"
        )
    seeds = parse_seeds(ap, args.seeds)
    pols = _policies(ap, envs, args.policies)
    scs = _items(ap, "--scenarios", args.scenarios, key=_scenario_key)
    if args.out is None or str(args.out).strip() == "":
        ap.error("argument --out: empty path")
    _check_out(ap, Path(args.out), args.resume)
    resolved = {}
    for env_id in envs:  # cheap pass first: names and YAML files
        for sc in scs:
            try:
                resolved[env_id, sc] = scenarios.resolve(sc, env_id)
            except Exception as exc:  # noqa: BLE001 - any failure is a bad --scenarios value
                ap.error(
                    f"argument --scenarios: {tail(sc, 80)!r} for {env_id}: "
                    f"{head(str(exc), _EXCERPT)}"
                )
    plan = Plan(envs=envs, scenarios=scs, seeds=seeds, policies=pols)
    source = _source_digest()
    for env_id in envs:
        for sc in scs:
            try:
                plan.envs_made[env_id, sc] = gym.make(env_id, scenario=resolved[env_id, sc])
            except Exception as exc:  # noqa: BLE001
                ap.error(
                    f"argument --scenarios: {tail(sc, 80)!r} for {env_id}: "
                    f"{type(exc).__name__}: {head(str(exc), _EXCERPT)}"
                )
            for name in pols[env_id]:
                plan.fingerprints[env_id, sc, name] = fingerprint(
                    env_id, resolved[env_id, sc], _policy_digest(env_id, name), source
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
    """One episodes.jsonl line as a row (strict JSON, the key fields present)."""
    row = json.loads(line, parse_constant=_reject_constant)
    need = {"env", "scenario", "policy", "seed", "fingerprint"}
    if not isinstance(row, dict) or not need <= set(row):
        raise ValueError(f"not an object with the fields {sorted(need)}")
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


# --------------------------------------------------------------------------- outputs
def _make_policy(name: str, env_id: str, env):
    if name.startswith("sb3:"):
        return agents.load(env_id, name[4:])
    return baselines.make(name, env)


def _plot_path(out: Path, env_id: str, scenario: str) -> Path:
    return out / "plots" / f"{env_id.split('/')[-1]}__{Path(scenario).stem}.png"


def _plot(
    out: Path, env_id: str, scenario: str, traces: dict[str, dict], secondary: tuple = ()
) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = 2 + len(secondary)
    fig, axes = plt.subplots(n, 1, figsize=(9, 3 + 1.5 * n), sharex=True,
                             gridspec_kw={"height_ratios": [2] + [1] * (n - 1)})  # fmt: skip
    ax1, ax2 = axes[0], axes[-1]
    for ax, (name, sp2) in zip(axes[1:-1], secondary, strict=True):
        for band, alpha in ((5, 0.2), (8, 0.1)):
            ax.axhspan(sp2 - band, sp2 + band, color="tab:green", alpha=alpha, lw=0)
        ax.axhline(sp2, color="k", ls="--", lw=1)
        for pname, tr in traces.items():
            ax.plot(tr["time_s"] / 60, tr[name], lw=1.2, label=pname)
        ax.set_ylabel(name.replace("_C", " [C]"))
        ax.grid(alpha=0.3)
    first = next(iter(traces.values()))
    t = first["time_s"] / 60
    sp = first["setpoint_C"]
    for band, alpha in ((5, 0.2), (8, 0.1)):
        ax1.fill_between(t, sp - band, sp + band, color="tab:green", alpha=alpha, lw=0)
    ax1.plot(t, sp, "k--", lw=1, label="setpoint")
    for name, tr in traces.items():
        ax1.plot(tr["time_s"] / 60, tr["outlet_temp_C"], lw=1.2, label=name)
        ax2.plot(
            tr["time_s"] / 60, 100 * np.atleast_2d(tr["spray_valve"].T).T[:, 0], lw=1, label=name
        )
    ax1.set_ylabel("main steam [C]")
    ax1.legend(fontsize=7)
    ax1.grid(alpha=0.3)
    ax1.set_title(f"{env_id} - {scenario}", fontsize=9)
    ax2b = ax2.twinx()
    ax2b.plot(t, 100 * first["load"], "tab:gray", lw=0.8)
    ax2b.set_ylabel("load [%]", color="tab:gray")
    ax2.set_ylabel("spray valve 1 [%]")
    ax2.set_xlabel("time [min]")
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    path = _plot_path(out, env_id, scenario)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=80)
    plt.close(fig)
    return path


def _mean(values: list[float | None]) -> float:
    """Mean over the finite values (None/NaN where a metric does not apply)."""
    v = np.asarray([np.nan if x is None else x for x in values], dtype=float)
    v = v[np.isfinite(v)]
    return float(v.mean()) if v.size else float("nan")


def _markdown(rows: list[dict]) -> str:
    lines = ["# steamtemp_gym leaderboard", "",
             "Means over seeds. IAE in K s, deviations in K, times in s, spray in kg; "
             "return is the "
             "default reward summed over the episode (higher is better).", ""]  # fmt: skip
    ok = [r for r in rows if not r.get("error")]
    keys = sorted({(r["env"], r["scenario"]) for r in ok})
    for env_id, sc in keys:
        lines += [f"## {env_id} - {sc}", "",
                  "| policy | " + " | ".join(TABLE_METRICS) + " | trips |",
                  "|---|" + "---|" * (len(TABLE_METRICS) + 1)]  # fmt: skip
        pols = sorted({r["policy"] for r in ok if r["env"] == env_id and r["scenario"] == sc})
        for p in pols:
            sel = [r for r in ok if (r["env"], r["scenario"], r["policy"]) == (env_id, sc, p)]
            vals = [_mean([r["metrics"].get(m) for r in sel]) for m in TABLE_METRICS]
            trips = int(sum(r["metrics"].get("tripped") or 0 for r in sel))
            lines.append(f"| {p} | " + " | ".join(f"{v:.4g}" for v in vals) + f" | {trips} |")
        lines.append("")
    failed = [r for r in rows if r.get("error")]
    if failed:
        lines += ["## Failed episodes", "", "| env | scenario | policy | seed | error |",
                  "|---|---|---|---|---|"]  # fmt: skip
        for r in failed:
            err = head(str(r["error"]), 160).replace("|", "\\|").replace("\n", " ")
            lines.append(f"| {r['env']} | {r['scenario']} | {r['policy']} | {r['seed']} | {err} |")
        lines.append("")
    return "\n".join(lines)


def _rebuild(out: Path, plan: Plan) -> list[dict]:
    """leaderboard.json and leaderboard.md from episodes.jsonl (this run's grid)."""
    latest = _latest(read_record(out / EPISODES))
    rows = []
    for key in plan.grid():
        r = latest.get((key, plan.fingerprints[key[:3]]))
        if r is not None:
            rows.append({k: v for k, v in r.items() if k != "traceback"})
    (out / "leaderboard.json").write_text(dumps(rows, indent=1) + "\n")
    (out / "leaderboard.md").write_text(_markdown(rows))
    return rows


# --------------------------------------------------------------------------- run
def _error_row(key: Key, fp: str, exc: BaseException) -> dict:
    env_id, sc, name, seed = key
    tb = "".join(traceback.format_exception(type(exc), exc, exc.__traceback__))
    print(f"FAILED {env_id} {sc} {name} seed {seed}: {type(exc).__name__}: {exc}",
          file=sys.stderr)  # fmt: skip
    return {"env": env_id, "scenario": sc, "policy": name, "seed": seed, "fingerprint": fp,
            "metrics": None, "error": head(f"{type(exc).__name__}: {exc}", 1000),
            "traceback": tb[-4000:]}  # fmt: skip


def _run_group(
    out: Path, plan: Plan, env_id: str, sc: str, record: Record, done: dict
) -> tuple[int, int]:
    """All policies and seeds of one env and scenario, then its plot. (ran, failed)."""
    env = plan.envs_made[env_id, sc]
    ran = failed = 0
    traces: dict[str, dict] = {}
    made: dict[str, Any] = {}
    first_ok: dict[str, int] = {}
    for name in plan.policies[env_id]:
        fp = plan.fingerprints[env_id, sc, name]
        last = None
        for seed in plan.seeds:
            prev = done.get(((env_id, sc, name, seed), fp))
            if prev is not None and not prev.get("error"):
                first_ok.setdefault(name, seed)
                continue
            try:
                if name not in made:
                    try:
                        made[name] = _make_policy(name, env_id, env)
                    except Exception as exc:  # noqa: BLE001 - every seed of it fails alike
                        made[name] = exc
                if isinstance(made[name], Exception):
                    raise made[name]
                res = run_episode(env, made[name], seed)
            except Exception as exc:  # noqa: BLE001 - recorded; the run goes on
                last = _error_row((env_id, sc, name, seed), fp, exc)
                failed += 1
            else:
                last = {"env": env_id, "scenario": sc, "policy": name, "seed": seed,
                        "fingerprint": fp, "metrics": res["metrics"]}  # fmt: skip
                if name not in first_ok:
                    first_ok[name] = seed
                    traces[name] = res["trace"]
            record.write(last)
            ran += 1
        if last is not None and last["metrics"] is not None:
            m = last["metrics"]
            print(
                f"{env_id:32s} {sc:22s} {name:14s} IAE {m['iae_K_s']:9.1f} K s  "
                f"max|dev| {m['max_abs_dev_K']:6.2f} K  return {m['return']:9.2f}",
                flush=True,
            )
        elif last is None:
            print(f"{env_id:32s} {sc:22s} {name:14s} done before (--resume)", flush=True)
    if not first_ok or (ran == 0 and _plot_path(out, env_id, sc).exists()):
        return ran, failed
    for name in plan.policies[env_id]:  # traces of episodes finished before a resume
        if name in first_ok and name not in traces:
            try:
                pol = made[name] if name in made else _make_policy(name, env_id, env)
                traces[name] = run_episode(env, pol, first_ok[name])["trace"]
            except Exception as exc:  # noqa: BLE001
                print(f"note: no trace of {name} for the plot: {exc}", file=sys.stderr)
    order = [n for n in plan.policies[env_id] if n in traces]
    if order:
        _plot(out, env_id, sc, {n: traces[n] for n in order}, env.unwrapped.plant.secondary)
    return ran, failed


def make_parser() -> argparse.ArgumentParser:
    """The CLI's argument parser."""
    doc = __doc__ or ""
    ap = argparse.ArgumentParser(
        prog="steamtemp-leaderboard",
        description=doc.split("\n")[0],
        epilog=doc.split("\n", 2)[2],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ap.add_argument(
        "--envs",
        default=",".join(steamtemp_gym.ENV_IDS),
        help="comma list of env ids (default: all)",
    )
    ap.add_argument("--policies", default=None, help="comma list (default: all available)")
    ap.add_argument(
        "--scenarios",
        default=",".join(DEFAULT_SCENARIOS),
        help="comma list of scenario names or YAML paths (default: %(default)s)",
    )
    ap.add_argument(
        "--seeds", default="0,1,2", help="integers >= 0 or ranges a-b (default: %(default)s)"
    )
    ap.add_argument(
        "--out", default="leaderboard_out", help="output directory (default: %(default)s)"
    )
    ap.add_argument(
        "--resume",
        action="store_true",
        help="continue in --out: skip the episodes already in its episodes.jsonl",
    )
    return ap


def main(argv: list[str] | None = None) -> None:
    """Run the leaderboard (see the module docstring)."""
    ap = make_parser()
    args = ap.parse_args(argv)
    plan = build_plan(ap, args)
    out = Path(args.out)
    try:
        done = _latest(read_record(out / EPISODES)) if args.resume else {}
    except (OSError, ValueError) as exc:
        ap.error(f"argument --resume: {head(str(exc), _EXCERPT)}")
    try:
        out.mkdir(parents=True, exist_ok=True)
        record = Record(out / EPISODES)
    except OSError as exc:
        ap.error(f"argument --out: cannot write {str(out)!r}: {exc.strerror or exc}")
    t0 = time.time()
    ran = failed = 0
    try:
        for env_id in plan.envs:
            for sc in plan.scenarios:
                r, f = _run_group(out, plan, env_id, sc, record, done)
                ran, failed = ran + r, failed + f
    except KeyboardInterrupt:
        record.close()
        _rebuild(out, plan)
        print(f"\ninterrupted: finished episodes are in {out / EPISODES}; "
              "run the same command with --resume to continue", file=sys.stderr)  # fmt: skip
        raise SystemExit(130) from None
    record.close()
    rows = _rebuild(out, plan)
    bad = [r for r in rows if r.get("error")]
    print(
        f"wrote {out / 'leaderboard.json'}, {out / 'leaderboard.md'} and plots/ "
        f"({len(rows)} episodes, {ran} run now, {time.time() - t0:.0f} s)"
    )
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
