"""The work of a leaderboard run in units: one policy on one env and scenario for the seeds
left to run, one batch of the vector env (:func:`run_unit`: a row per seed and the trace
kept for the plot); :func:`_units` lists what is left, the oracle's first. A policy that is
not shipped acts from a process of its own (agents/leaderboard/isolated.py).
"""

from __future__ import annotations

import importlib
import traceback
from dataclasses import dataclass
from typing import Any

from agents import specs
from agents.difficulty import FrozenValves
from agents.evaluation import run_batch, run_episode
from agents.leaderboard import summary
from agents.leaderboard.isolated import PolicyFailed, PolicyProcess, PolicyTimeout, make_env
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


def own_process(name: str) -> bool:
    """Whether the policy ``name`` runs in a process of its own: every one but the shipped
    baselines and trained agents and the references."""
    return name not in (REFERENCE, summary.ONE) and not specs.parse(name).shipped


def make_policy(name: str, env_id: str, env: Any, scenario: Any, num_envs: int | None = None,
                imports: tuple[str, ...] = (), timeout: float | None = None,
                episodes: int = 1) -> Any:  # fmt: skip
    """The policy ``name`` to act on ``env`` (of ``num_envs`` rows, None: a single env): a
    shipped one built here on ``env``, any other a :class:`PolicyProcess` (commissioned on
    an env of its own made with ``scenario``; close it)."""
    if own_process(name):
        return PolicyProcess(name, env_id, scenario, num_envs, imports, timeout, episodes)
    return _make_policy(name, env_id, env)


def close(policy: Any) -> None:
    """End a :class:`PolicyProcess` (nothing for a policy of this process)."""
    if isinstance(policy, PolicyProcess):
        policy.close()


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
    timeout: float | None = None  # --episode-timeout (s) of a policy in a process of its own


def _ok_row(u: Unit, seed: int, metrics: dict) -> dict:
    return {"env": u.env_id, "scenario": u.spec, "policy": u.policy, "seed": seed,
            "fingerprint": u.fingerprint, "metrics": metrics}  # fmt: skip


def run_unit(u: Unit) -> tuple[list[dict], dict | None]:
    """:func:`_run_unit` with this process's BLAS and OpenMP thread pools limited to one
    thread: a policy's linear algebra then gives the same result bit for bit whatever the
    core count or ``OPENBLAS_NUM_THREADS`` (measured: mpc_evarx's returns on
    BoilerTurbineMIMO's ``slow_firing_lag_sensor`` differed in the ninth digit between one
    and two BLAS threads). The leaderboard's parallelism is across units."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1):
        return _run_unit(u)


def _run_unit(u: Unit) -> tuple[list[dict], dict | None]:
    """Rows of a unit (one per seed, in order) and the trace of ``u.trace_seed``.

    The seeds run side by side in the native vector env (:func:`run_batch`); if anything
    raises there, each seed runs alone (:func:`run_episode`, identical results) so that
    only the episodes that fail are recorded as failed. A policy that is not shipped is
    built and acts in a process of its own on a commissioning env of its own
    (:class:`PolicyProcess`); when it does not answer in time every seed fails with the
    timeout (alone, each would take as long).
    """
    for module in u.imports:  # a spawned worker or a Ray task has not imported them
        importlib.import_module(module)
    trace = None
    plant = {"params": u.params} if u.params else {}
    n, own = len(u.seeds), own_process(u.policy)
    try:
        unit = make_env(u.env_id, u.scenario, n, **plant)
        # the nominal plant (a policy of its own process commissions on an env of its own)
        model = make_env(u.env_id, u.scenario, n) if plant and not own else unit
        policy = make_policy(u.policy, u.env_id, model, u.scenario, n, u.imports, u.timeout, n)
        try:
            results = run_batch(unit, policy, u.seeds)
        finally:
            close(policy)
    except PolicyTimeout as exc:
        return [_error_row((u.env_id, u.spec, u.policy, s), u.fingerprint, exc)
                for s in u.seeds], None  # fmt: skip
    except Exception:  # noqa: BLE001 - isolate the failing seeds below
        results = None
    if results is not None:
        rows = [_ok_row(u, s, r["metrics"]) for s, r in zip(u.seeds, results, strict=True)]
        if u.trace_seed is not None:
            trace = results[u.seeds.index(u.trace_seed)]["trace"]
        return rows, trace
    env = make_env(u.env_id, u.scenario, **plant)
    model = make_env(u.env_id, u.scenario) if plant and not own else env
    try:
        policy = None if own else _make_policy(u.policy, u.env_id, model)
    except Exception as exc:  # noqa: BLE001 - every seed of it fails alike
        policy = exc
    rows = []
    for seed in u.seeds:
        try:
            if isinstance(policy, Exception):
                raise policy
            # a policy of its own process: a new process for each episode (a failure ends it)
            alone = policy if not own else make_policy(u.policy, u.env_id, model, u.scenario,
                                                       None, u.imports, u.timeout)  # fmt: skip
            try:
                res = run_episode(env, alone, seed)
            finally:
                if own:
                    close(alone)
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
    what = f"{type(exc).__name__}: {exc}"
    if isinstance(exc, PolicyFailed):  # its message says what the policy's process did
        what = str(exc)
        if exc.remote_traceback:
            tb = f"{tb}\nin the policy's process:\n{exc.remote_traceback}"
    return {"env": env_id, "scenario": sc, "policy": name, "seed": seed, "fingerprint": fp,
            "metrics": None, "error": head(what, 1000),
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
                                    plan.imports, params, plan.episode_timeout))  # fmt: skip
    return sorted(out, key=lambda u: u.policy != summary.ONE)  # stable: run order otherwise


def _finished(row: dict | None) -> bool:
    return row is not None and not row.get("error")
