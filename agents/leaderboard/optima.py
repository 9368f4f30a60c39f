"""(Re)compute the stored optima (agents/optima.py), the score's 1 of every reference
episode: resumable, each episode written as it ends::

    python -m agents.leaderboard.optima --jobs 2          # every reference episode
    python -m agents.leaderboard.optima --backend ray     # one Ray task per episode
    python -m agents.leaderboard.optima --envs BensonSubcritical-v0 --seeds 0

Episodes run seed by seed across every plant and scenario, so a partial store covers every
plant. ``--certify`` recomputes the certificates of the stored episodes
(agents/optimum/certificate.py: ``certify``) and ``--check`` runs the independent check
(``independent_check``) on them, each writing its result into the episode's record
(resumable: ``--again`` checks the episodes checked before too).
"""

from __future__ import annotations

import argparse
import functools
import os
import sys
import time
from pathlib import Path

import numpy as np

from agents import optima
from agents.leaderboard import plan as plan_
from agents.leaderboard.records import dumps
from steamtemp_gym import scenarios


def episodes(envs: list[str], names: list[str], seeds: list[int]) -> list[tuple[str, str, int]]:
    """(env id, scenario, seed) in the order they are solved: seed by seed, then plant and
    scenario."""
    return [(e, s, seed) for seed in seeds for e in envs for s in names]


def solve_episode(item: tuple[str, str, int]) -> tuple[dict, np.ndarray] | str:
    """The optimum of one episode (agents/optimum.py: warm starts by the receding-horizon
    CEM and the incumbents, two refined paths, the certificate) and its record, on one
    thread; the return is checked by a replay of the actions in a fresh env, as the
    leaderboard runs it. A failure is returned as its traceback."""
    import traceback

    try:
        return _solve_one_thread(item)
    except Exception:  # noqa: BLE001 - reported by the caller; the other episodes go on
        return traceback.format_exc()


def _solve_one_thread(item: tuple[str, str, int]) -> tuple[dict, np.ndarray]:
    from threadpoolctl import threadpool_limits

    from steamtemp_gym.plants.threads import set_threads

    set_threads(1)
    with threadpool_limits(limits=1):
        return _solve(item)


def _solve(item: tuple[str, str, int]) -> tuple[dict, np.ndarray]:
    import gymnasium as gym

    from agents import optimum
    from agents.evaluation import run_episode
    from agents.oracle import Oracle, Replay
    from steamtemp_gym.envs.snapshot import env_core

    env_id, name, seed = item
    scenario = scenarios.resolve(name, env_id)
    t0 = time.process_time()
    env = gym.make(env_id, scenario=scenario)
    obs, _ = env.reset(seed=seed)
    core = env_core(env)
    cem = Oracle(env, engine="cem")
    cem.predict(obs)
    c = cem.committed[0]
    warm_cpu = time.process_time() - t0
    ep = optimum.episode(core)
    out = optimum.solve(ep, c.sequences, c.returns, zero=c.returns["cascade_pi_ff"])
    a = out["actions"]
    replayed = run_episode(gym.make(env_id, scenario=scenario), Replay(a), seed)
    R = float(replayed["metrics"]["return"])
    if R != out["return"]:
        raise RuntimeError(
            f"{env_id} {name} seed {seed}: the replay returned {R!r}, the "
            f"optimizer's rollout {out['return']!r}"
        )
    record = {
        "env": env_id,
        "scenario": name,
        "seed": seed,
        "noise_key": int(core.noise_keys()[0]),
        "scenario_digest": optima.scenario_digest(core.scenario[0]),  # "random": the drawn one
        "return": R,
        "zero": out["zero"],
        "tripped": out["tripped"],
        "warm_starts": c.returns,
        "certificate": out["certificate"],
        "paths": out["paths"],
        "cpu_s": time.process_time() - t0,
        "warm_start_cpu_s": warm_cpu,
        "actions_file": optima.file_name(env_id, name, seed),
        "actions_sha": optima.actions_digest(a),
        "metrics": replayed["metrics"],
    }
    return record, a


def assess(
    item: tuple[str, str, int], check: bool = False, store: Path = optima.STORE
) -> dict | str:
    """The certificate of a stored episode's optimum with the current code (and, with
    ``check``, the independent check's gain), on one thread: the fields to set in its
    record. A failure is returned as its traceback."""
    import traceback

    import gymnasium as gym
    from threadpoolctl import threadpool_limits

    from agents import optimum
    from agents.optimum import search
    from steamtemp_gym.envs.snapshot import env_core
    from steamtemp_gym.plants.threads import set_threads

    set_threads(1)
    try:
        with threadpool_limits(limits=1):
            r = optima.load(store)[item]
            env = gym.make(r["env"], scenario=scenarios.resolve(r["scenario"], r["env"]))
            env.reset(seed=r["seed"])
            ep = optimum.episode(env_core(env))
            a = optima.actions(r, store)
            U = (a.astype(np.float64) + 1.0) / 2.0
            best = max(r["paths"], key=lambda p: p["final"])["start"]
            t0 = time.process_time()
            cert = optimum.certify(
                ep,
                U,
                r["return"],
                r["zero"],
                r["paths"],
                best,
                search.smoothing(search.CONTINUATION[-1]),
                search.LEVEL_SMOOTHING,
            )
            out = {"certificate": {**cert, "cpu_s": time.process_time() - t0}}
            if check:
                t0 = time.process_time()
                gain, log = optimum.independent_check(ep, a)
                out["independent_check"] = {
                    "gain": gain,
                    "share": gain / cert["headroom"],
                    "levels": log,
                    "cpu_s": time.process_time() - t0,
                }
            return out
    except Exception:  # noqa: BLE001 - reported by the caller
        return traceback.format_exc()


def _results(items: list, jobs: int, backend: str, fn=None):
    fn = fn or solve_episode
    if backend == "ray":
        from agents import ray_backend

        yield from ray_backend.results(fn, items, jobs)
    elif jobs <= 1:
        for it in items:
            yield it, fn(it)
    else:
        import multiprocessing as mp
        from concurrent.futures import ProcessPoolExecutor, as_completed

        from agents.leaderboard.isolated import watch_parent

        context = mp.get_context("spawn")  # a worker ends with this process (watch_parent)
        with ProcessPoolExecutor(
            jobs, mp_context=context, initializer=watch_parent, initargs=(os.getpid(),)
        ) as pool:
            futures = {pool.submit(fn, it): it for it in items}
            for f in as_completed(futures):
                yield futures[f], f.result()


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m agents.leaderboard.optima", description=(__doc__ or "").split("\n")[0]
    )
    ap.add_argument("--envs", default=None, help="comma-separated env ids (default: all)")
    ap.add_argument("--scenarios", default=",".join(plan_.DEFAULT_SCENARIOS))
    ap.add_argument("--seeds", default=plan_.DEFAULT_SEEDS)
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--backend", choices=("process", "ray"), default="process")
    ap.add_argument(
        "--store", type=Path, default=optima.STORE, help="the store (default: the package's)"
    )
    ap.add_argument("--limit", type=int, default=None, help="solve at most this many episodes")
    ap.add_argument(
        "--certify",
        action="store_true",
        help="recompute the certificates of the stored episodes instead",
    )
    ap.add_argument(
        "--check",
        action="store_true",
        help="with --certify: also run the independent check on them (resumable: episodes "
        "whose record holds a check are passed over unless --again)",
    )
    ap.add_argument("--again", action="store_true", help="with --check: check every episode again")
    args = ap.parse_args(argv)
    import steamtemp_gym

    envs = (
        [e if "/" in e else f"steamtemp/{e}" for e in args.envs.split(",")]
        if args.envs
        else list(steamtemp_gym.ENV_IDS)
    )
    unknown = [e for e in envs if e not in steamtemp_gym.ENV_IDS]
    if unknown:
        ap.error(f"argument --envs: unknown env id(s) {unknown}")
    if args.jobs < 1:
        ap.error(f"argument --jobs: must be >= 1, got {args.jobs}")
    seeds = plan_.parse_seeds(ap, args.seeds)
    names = [s.strip() for s in args.scenarios.split(",") if s.strip()]
    done = optima.load(args.store)
    if args.check and not args.certify:
        ap.error("argument --check: only with --certify")
    if args.again and not args.check:
        ap.error("argument --again: only with --check")
    if args.certify:
        items = [it for it in episodes(envs, names, seeds) if it in done]
        if args.check and not args.again:
            checked = [it for it in items if "independent_check" in done[it]]
            items = [it for it in items if it not in checked]
            print(
                f"optima: {len(items)} episode(s) to check, {len(checked)} checked before "
                "(--again checks them too)",
                file=sys.stderr,
            )
        return _certify(args, items)
    todo = [it for it in episodes(envs, names, seeds) if it not in done]
    if args.limit is not None:
        todo = todo[: args.limit]
    print(f"optima: {len(todo)} episode(s) to solve, {len(done)} stored", file=sys.stderr)
    t0 = time.time()
    failed = 0
    for n, (item, result) in enumerate(_results(todo, args.jobs, args.backend), 1):
        if isinstance(result, str):
            failed += 1
            print(f"[{n}/{len(todo)}] {item}: FAILED\n{result}", file=sys.stderr, flush=True)
            continue
        record, a = result
        optima.write(args.store, dumps(record, sort_keys=True), record["actions_file"], a)
        print(
            f"[{n}/{len(todo)} {time.time() - t0:7.0f} s] {_describe(item, record)}",
            file=sys.stderr,
            flush=True,
        )
    return 1 if failed else 0


def _describe(item: tuple[str, str, int], record: dict) -> str:
    """One line on a solved episode: its return, the CEM's and the 0, CPU, certificate."""
    c = record["certificate"]
    return (
        f"{item[0].split('/')[-1]} {item[1]} seed {item[2]}: R1 {record['return']:.4f} "
        f"(CEM {record['warm_starts']['cem']:.4f}, zero {record['zero']:.4f}), "
        f"{record['cpu_s']:.0f} s of CPU; certificate {'holds' if c['holds'] else 'FAILS'} "
        f"(step {c['step_gain']:.1e}, refinement {c['last_refinement']:.1e}, "
        f"starts {c['starts_agree']:.1e})"
    )


def _certify(args: argparse.Namespace, items: list) -> int:
    """--certify: each stored episode's certificate (and --check) into its record."""
    if args.limit is not None:
        items = items[: args.limit]
    fn = functools.partial(assess, check=args.check, store=args.store)
    failed = 0
    for n, (item, out) in enumerate(_results(items, args.jobs, args.backend, fn), 1):
        if isinstance(out, str):
            failed += 1
            print(f"[{n}/{len(items)}] {item}: FAILED\n{out}", file=sys.stderr, flush=True)
            continue
        optima.update(args.store, item, out, dumps)
        c, ic = out["certificate"], out.get("independent_check")
        print(
            f"[{n}/{len(items)}] {item[0].split('/')[-1]} {item[1]} seed {item[2]}: "
            f"certificate {'holds' if c['holds'] else 'FAILS'} (step {c['step_gain']:.2e}, "
            f"refinement {c['last_refinement']:.2e}, starts {c['starts_agree']})"
            + (f", independent check {ic['share']:.2e}" if ic else ""),
            file=sys.stderr,
            flush=True,
        )
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
