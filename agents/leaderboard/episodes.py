"""The work of a leaderboard run in units: one policy on one env and scenario for the seeds
left to run (a row per seed and the trace kept for the plot); :func:`pending` lists what is
left, the oracle's first. Units run in batches (:func:`batches`, :func:`run_units`): a
shipped policy's units of one env on the nominal plant whose scenarios last as long run
side by side in one vector env, a scenario per row, so the per-step work of the env loop
and of the policy is paid once for all of them. A policy that is not shipped acts from a
process of its own (agents/leaderboard/isolated.py).
"""

from __future__ import annotations

import importlib
import traceback
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np

from agents import specs
from agents.evaluation import run_batch, run_episode
from agents.leaderboard.isolated import PolicyFailed, PolicyProcess, PolicyTimeout, make_env
from agents.leaderboard.plan import Plan, episode_fingerprint
from agents.leaderboard.records import Key
from agents.oracle import DEFAULT_ENGINE
from steamtemp_gym import scenarios
from steamtemp_gym.checks import head


def make_policy(
    spec: specs.Spec,
    env_id: str,
    env: Any,
    scenario: Any,
    num_envs: int | None = None,
    imports: tuple[str, ...] = (),
    timeout: float | None = None,
    episodes: int = 1,
    oracle: str = DEFAULT_ENGINE,
) -> Any:
    """The policy of ``spec`` to act on ``env`` (of ``num_envs`` rows, None: a single env):
    one of this process (:attr:`agents.specs.Spec.own_process` false) built here on ``env``,
    any other a :class:`PolicyProcess` (commissioned on an env of its own made with
    ``scenario``; close it)."""
    if spec.own_process:
        return PolicyProcess(spec.name, env_id, scenario, num_envs, imports, timeout, episodes)
    return spec.make(env_id, env, oracle)


def close(policy: Any) -> None:
    """End a :class:`PolicyProcess` (nothing for a policy of this process)."""
    if isinstance(policy, PolicyProcess):
        policy.close()


@dataclass
class Unit:
    """One policy on one env and scenario for several seeds, the rows of the vector env that
    a batch of units runs (:func:`batches`)."""

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
    oracle: str = DEFAULT_ENGINE  # --oracle: the oracle's engine
    parsed: specs.Spec | None = None  # the policy's Spec (None: parsed from ``policy``)

    def __post_init__(self) -> None:
        if self.parsed is None:
            self.parsed = specs.parse(self.policy, references=True)


class RowScenarios(gym.vector.VectorWrapper):
    """A native vector env whose reset starts each row under a scenario of its own: a masked
    reset per scenario with the seeds given, so that row i is the single env of its
    scenario seeded with its seed, bit for bit (tests/test_leaderboard.py); autoresets
    return to the env's own scenario."""

    def __init__(self, env: Any, scenarios: list[Any]) -> None:
        super().__init__(env)
        if len(scenarios) != env.num_envs:
            raise ValueError(f"{len(scenarios)} scenarios for {env.num_envs} sub-envs")
        self.rows = scenarios

    def reset(self, *, seed: Any = None, options: dict | None = None):
        out = self.env.reset(seed=seed, options=options)
        for sc in {id(sc): sc for sc in self.rows}.values():
            mask = np.array([row is sc for row in self.rows])
            out = self.env.reset(seed=seed, options={"scenario": sc, "reset_mask": mask})
        return out


def _ok_row(u: Unit, seed: int, metrics: dict) -> dict:
    return {
        "env": u.env_id,
        "scenario": u.spec,
        "policy": u.policy,
        "seed": seed,
        "fingerprint": u.fingerprint,
        "metrics": metrics,
    }


def run_unit(u: Unit) -> tuple[list[dict], dict | None]:
    """Rows of one unit (one per seed, in order) and the trace of ``u.trace_seed``
    (:func:`run_units` of the unit alone)."""
    return run_units([u])[0]


def run_units(batch: list[Unit]) -> list[tuple[list[dict], dict | None]]:
    """Each unit's rows and trace (:func:`run_unit`), the units side by side in one vector
    env, with this process's BLAS and OpenMP thread pools limited to one thread: a policy's
    linear algebra then gives the same result bit for bit whatever the core count or
    ``OPENBLAS_NUM_THREADS`` (measured: mpc_evarx's returns on BoilerTurbineMIMO's
    ``slow_firing_lag_sensor`` differed in the ninth digit between one and two BLAS
    threads). The leaderboard's parallelism is across batches."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1):
        return _run_units(batch, batch[0].parsed.own_process)


#: Shipped policies whose rows are not independent of the rows solved before them in a
#: step: the EV-ARX MPCs solve each row's QP with OSQP, and OSQP's answer to the same
#: problem on a new solver can differ in the last bit with what the process solved before
#: (measured: 2.7e-16 on a first bias move, grown by the closed loop to 1e-4 of an episode's
#: return on BensonSubcritical). They run one scenario per batch, so that a row's
#: predecessors are always the same.
ALONE = ("mpc_evarx", "mpc_arx")


def batches(units: list[Unit]) -> list[list[Unit]]:
    """The units grouped to run side by side (:func:`run_units`): those of one shipped
    policy (not the oracle, nor :data:`ALONE`) on one env's nominal plant whose scenarios
    last equally long; every other unit alone. The order is that of each batch's first
    unit."""
    groups: dict[Any, list[Unit]] = {}
    for i, u in enumerate(units):
        together = (
            u.params is None
            and u.parsed.score_end != 1
            and u.policy not in ALONE
            and not u.parsed.own_process
            and not isinstance(u.scenario, str)
        )  # "random": lengths drawn per row
        key = (u.env_id, u.policy, u.scenario.duration_s) if together else i
        groups.setdefault(key, []).append(u)
    return list(groups.values())


def _run_units(batch: list[Unit], own: bool) -> list[tuple[list[dict], dict | None]]:
    """:func:`run_units` (its docstring); ``own``: whether the batch's policy runs in a
    process of its own, decided once for the batch and shared by both paths. Every seed of
    the batch is a row of one native vector env (:func:`_side_by_side`). If anything raises
    there, a batch of several units runs each unit on its own, and a unit each seed alone
    (:func:`_seed_by_seed`, identical results), so that only the episodes that fail are
    recorded as failed. A policy of a process of its own that does not answer in time fails
    every seed with the timeout (alone, each would take as long)."""
    for module in batch[0].imports:  # a spawned worker or a Ray task has not imported them
        importlib.import_module(module)
    try:
        return _side_by_side(batch, own)
    except PolicyTimeout as exc:
        return [
            (
                [_error_row((u.env_id, u.spec, u.policy, s), u.fingerprint, exc) for s in u.seeds],
                None,
            )
            for u in batch
        ]
    except Exception:  # noqa: BLE001 - isolate the failing units, then seeds, below
        if len(batch) > 1:
            return [out for u in batch for out in _run_units([u], own)]
        return [_seed_by_seed(batch[0], own)]


def _side_by_side(batch: list[Unit], own: bool) -> list[tuple[list[dict], dict | None]]:
    """Each unit's rows and trace, all seeds rows of one vector env (:func:`run_batch`),
    each row under its unit's scenario. The units share env, policy and plant (batches); a
    policy that is not shipped is built and acts in a process of its own on a
    commissioning env of its own (:class:`PolicyProcess`)."""
    u0 = batch[0]
    seeds = [s for u in batch for s in u.seeds]
    plant = {"params": u0.params} if u0.params else {}
    n = len(seeds)
    unit = make_env(u0.env_id, u0.scenario, n, **plant)
    if len(batch) > 1:
        unit = RowScenarios(unit, [u.scenario for u in batch for _ in u.seeds])
    # the nominal plant (a policy of its own process commissions on an env of its own)
    model = make_env(u0.env_id, u0.scenario, n) if plant and not own else unit
    policy = make_policy(
        u0.parsed, u0.env_id, model, u0.scenario, n, u0.imports, u0.timeout, n, u0.oracle
    )
    try:
        results = run_batch(unit, policy, seeds)
    finally:
        close(policy)
    out, i = [], 0
    for u in batch:
        mine, i = results[i : i + len(u.seeds)], i + len(u.seeds)
        rows = [_ok_row(u, s, r["metrics"]) for s, r in zip(u.seeds, mine, strict=True)]
        keep = mine[u.seeds.index(u.trace_seed)]["trace"] if u.trace_seed is not None else None
        out.append((rows, keep))
    return out


def _seed_by_seed(u: Unit, own: bool) -> tuple[list[dict], dict | None]:
    """Rows of a unit and the trace of ``u.trace_seed``, each seed alone in a single env
    (:func:`run_episode`); a seed that raises is a failed row."""
    trace = None
    plant = {"params": u.params} if u.params else {}
    env = make_env(u.env_id, u.scenario, **plant)
    model = make_env(u.env_id, u.scenario) if plant and not own else env
    try:
        policy = None if own else u.parsed.make(u.env_id, model, u.oracle)
    except Exception as exc:  # noqa: BLE001 - every seed of it fails alike
        policy = exc
    rows = []
    for seed in u.seeds:
        try:
            if isinstance(policy, Exception):
                raise policy
            # a policy of its own process: a new process for each episode (a failure ends it)
            alone = (
                policy
                if not own
                else make_policy(u.parsed, u.env_id, model, u.scenario, None, u.imports, u.timeout)
            )
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
    return {
        "env": env_id,
        "scenario": sc,
        "policy": name,
        "seed": seed,
        "fingerprint": fp,
        "metrics": None,
        "error": head(what, 1000),
        "traceback": tb[-4000:],
    }


def pending(plan: Plan, done: dict) -> list[Unit]:
    """What is left to run, one unit per env, scenario and policy; the oracle's first
    (they take the longest: the pool then ends with short units on every worker)."""
    out = []
    for env_id in plan.envs:
        for sc in plan.scenarios_of(env_id):
            params = plan.variants.get(env_id, {}).get(sc)
            for name in plan.policies_of(env_id, sc):
                fp = plan.fingerprints[env_id, sc, name]
                todo = [
                    s for s in plan.seeds if not _finished(done.get(((env_id, sc, name, s), fp)))
                ]
                if todo:
                    keep = plan.seeds[0] if plan.seeds[0] in todo and params is None else None
                    out.append(
                        Unit(
                            env_id,
                            sc,
                            plan.resolved[env_id, sc],
                            name,
                            todo,
                            fp,
                            keep,
                            plan.imports,
                            params,
                            plan.episode_timeout,
                            plan.oracle,
                            plan.spec(name),
                        )
                    )
    return sorted(out, key=lambda u: u.parsed.score_end != 1)  # stable: run order otherwise


def _finished(row: dict | None) -> bool:
    return row is not None and not row.get("error")


def score_ends(env_id: str, scenario: str, seeds: tuple[int, ...]) -> tuple[float, float]:
    """The mean returns of the score's 0 (``cascade_pi_ff``) and 1 (the oracle, replaying the
    stored optima) on ``env_id``'s ``scenario`` (a name as ``--scenarios`` takes it) over
    ``seeds``: their episodes run as a leaderboard run runs them, so these are its
    ``zero_return`` and ``one_return`` (agents/leaderboard/summary.py).

    Raises:
        RuntimeError: an episode failed (naming it and why).
    """
    sc = scenarios.resolve(scenario, env_id)
    means = []
    for name in (specs.ZERO, specs.ONE):
        spec = specs.parse(name, references=True)
        fp = episode_fingerprint(env_id, scenario, spec)
        rows = run_unit(Unit(env_id, scenario, sc, name, list(seeds), fp, None, parsed=spec))[0]
        failed = [r for r in rows if r.get("error")]
        if failed:
            raise RuntimeError(
                f"{name} on {env_id} {scenario} seed {failed[0]['seed']}: {failed[0]['error']}"
            )
        means.append(float(np.mean([r["metrics"]["return"] for r in rows])))
    return means[0], means[1]
