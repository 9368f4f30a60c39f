"""The work of a leaderboard run in units: one policy on one env and scenario for the seeds
left to run, one batch of the vector env (:func:`run_unit`: a row per seed and the trace
kept for the plot); :func:`_units` lists what is left, the oracle's first.
"""

from __future__ import annotations

import importlib
import traceback
from dataclasses import dataclass
from typing import Any

import gymnasium as gym

from agents import specs
from agents.difficulty import FrozenValves
from agents.evaluation import run_batch, run_episode
from agents.leaderboard import summary
from agents.leaderboard.plan import REFERENCE, Plan
from agents.leaderboard.records import Key
from agents.oracle import Oracle
from steamtemp_gym.checks import head


def _make_policy(name: str, env_id: str, env):
    if name == REFERENCE:
        return FrozenValves(env)
    if name == summary.ONE:
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
    return sorted(out, key=lambda u: u.policy != summary.ONE)  # stable: run order otherwise


def _finished(row: dict | None) -> bool:
    return row is not None and not row.get("error")
