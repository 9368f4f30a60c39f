"""steamtemp-train: train a Stable-Baselines3 agent on one plant.

    steamtemp-train --env steamtemp/Cascade300MW-v0 --algo ppo [--timesteps N] [--seed 0]
        [--n-envs N] [--out DIR] [--hyperparams FILE] [--max-minutes M] [--tensorboard DIR]
    python -m agents.train --zoo [--env ID] [--algo A] [--hyperparams FILE] [--out DIR]
        [--runs K] [--resume] [--backend {local,ray}] [--address ADDRESS] [--jobs N]
        [--max-minutes M]
        # rebuild agents/zoo/ (or DIR): every shipped agent from its shipped YAML entry;
        # with --env/--algo, every YAML entry of that env/algo; with --hyperparams and
        # --algo, every entry of that file; with --runs K, K independent training runs of
        # each (run k: seed --seed + 1000 k); --resume skips the runs already in --out

Hyperparameters: RL Zoo's YAML format (``agents/hyperparams/<algo>.yml``, keyed by env
id; the same files work with ``python -m rl_zoo3.train --gym-packages steamtemp_gym
--conf-file agents/hyperparams/ppo.yml``). Keys with a meaning of their own:
``n_timesteps``, ``n_envs``, ``policy``, ``normalize`` (bool, a dict or RL Zoo's
"dict(...)" string of VecNormalize options), ``env_wrapper`` (RL Zoo's forms; here
agents.wrappers.ControllerMemory), ``policy_kwargs`` (a dict or RL Zoo's "dict(...)"
string), ``learning_rate`` (a number or "lin_<x>"), ``noise_type``/``noise_std``
(SAC/TD3 action noise), ``residual_scale``, ``max_move`` and ``train_reward`` (our
extensions, not RL Zoo's: train a residual on the industrial reference ``cascade_pi_ff``;
an incremental agent whose action is a valve move of at most ``max_move`` of stroke per
interval, agents/moves.py; reward options for the training envs only, e.g.
``{w_move: 1.0}`` to charge valve travel more while learning, steamtemp_gym/rewards.py;
``plant_randomization``: the training envs' option of that name, a plant drawn per episode,
docs/plant_uncertainty.md; ``travel_price``: the starting price of the valve-travel constraint,
agents/travel_price.py; such entries are not for RL Zoo). Every other key
must be an argument of the algorithm's constructor. All input is checked before training
starts. Validation, the leaderboard and every score use the env's default reward.

Training runs on the ``random`` scenario distribution through the native vector env
(agents.vec_env), with the controller memory and VecNormalize when configured. At every
sixteenth of the budget (and at a --max-minutes stop) the agent is evaluated
(agents.evaluation) on ``random`` validation episodes with seeds from
:data:`VALIDATION_SEED` (training envs use ``--seed`` + i: never the same draws; never the
leaderboard's scenarios) and runs the baseline tuner's commissioning checks
(agents.validation); the best one is kept: the highest validation return among the
checkpoints that pass their checks and stay within the tuned baselines' margin under the
leaderboard's valve-travel budget (mean travel at most
``agents.tuning_terms.TUNING_TRAVEL_BUDGET`` = 1.7 times ``cascade_pi_ff``'s on the same
validation episodes), or, if none does, one that passes its checks, then the one of least
travel (agents.validation.better_checkpoint). With ``--max-minutes`` the
agent is validated at every sixteenth of that time instead (and at the end of the step
budget, where that ends the run first); an entry's ``max_minutes`` is its
runs' budget where ``--max-minutes`` is not given. A budget is minutes of one core: the
run's CPU time (agents/run_clock.py), not the wall's. Output in ``--out``:
``<env>__<algo>.zip`` (the best SB3 model) and ``<env>__<algo>.json`` (env id, package
version, git revision, hyperparameters, seed, timesteps, CPU and wall time, the validation curve
and score, the normalization statistics and the wrapper config: everything
``agents.load`` needs).

Training runs (``--zoo --runs K``): run k of an agent is trained with seed
:func:`run_seed` (``--seed`` + :data:`RUN_SEED_STRIDE` k: its training envs draw seeds
``seed + 1000 k + i``, never another run's) into ``<env>__<algo>__run<k>.zip/.json``
(agents/files.py). The runs go one after another at nice 10 (``--backend local``), or
each as a Ray task of one CPU (``--backend ray``: a new local Ray with ``--jobs`` CPUs, or
the cluster at ``--address``); ``--max-minutes`` bounds each run.
"""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path
from typing import Any

import steamtemp_gym
from agents import ray_backend, shipped
from agents.train_config import ALGOS, HYPERPARAMS, ConfigError, algo_class, read_hyperparams
from agents.train_runs import (
    MAX_RUNS,
    RUN_SEED_STRIDE,
    ZOO,
    entries_of,
    finished,
    zoo_entries,
    zoo_env,
    zoo_jobs,
    zoo_run,
)
from agents.training import checked_run, train


def _run_count(text: str) -> int:
    """``--runs``: an integer from 1 to :data:`MAX_RUNS`."""
    try:
        k = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be an integer >= 1, got {text!r}") from None
    if not 1 <= k <= MAX_RUNS:
        raise argparse.ArgumentTypeError(f"must be an integer from 1 to {MAX_RUNS}, got {k}")
    return k


def make_parser() -> argparse.ArgumentParser:
    doc = __doc__ or ""
    ap = argparse.ArgumentParser(
        prog="steamtemp-train",
        description=doc.split("\n")[0],
        epilog=doc.split("\n", 2)[2],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ap.add_argument(
        "--env",
        help=f"env id, one of {list(steamtemp_gym.ENV_IDS)} (the name "
        "after 'steamtemp/' is enough)",
    )
    ap.add_argument("--algo", help=f"one of {list(ALGOS)}")
    ap.add_argument("--timesteps", type=int, default=None, help="default: n_timesteps of the YAML")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--n-envs", type=int, default=None, help="default: n_envs of the YAML")
    ap.add_argument(
        "--out", default=None, help="output directory (default: trained; with --zoo: agents/zoo/)"
    )
    ap.add_argument("--hyperparams", default=None, help="YAML file (default: the shipped one)")
    ap.add_argument(
        "--max-minutes",
        type=float,
        default=None,
        help="stop after this many minutes of one core, the run's CPU time (default: the "
        "YAML entry's max_minutes; with --zoo: of each run, 10 where the entry has none)",
    )
    ap.add_argument("--tensorboard", default=None, help="TensorBoard log directory")
    ap.add_argument(
        "--zoo",
        action="store_true",
        help="rebuild agents/zoo/ (or --out): every shipped agent from its YAML "
        "entry (or --hyperparams), or with --env/--algo every entry of "
        "those; one at a time, at nice 10 (--max-minutes each, default the "
        "entry's max_minutes or 10; "
        "--timesteps and --n-envs, when given, for each)",
    )
    ap.add_argument(
        "--runs",
        type=_run_count,
        default=None,
        metavar="K",
        help=f"with --zoo: K independent training runs per agent (1 to {MAX_RUNS}), "
        "written <env>__<algo>__run<k>; run k trains with seed --seed + "
        f"{RUN_SEED_STRIDE} k (default: one run, written <env>__<algo>)",
    )
    ap.add_argument(
        "--resume",
        action="store_true",
        help="with --zoo: skip the runs whose files are in --out already (a "
        "rebuild stopped part way goes on where it stopped)",
    )
    ap.add_argument(
        "--backend",
        choices=("local", "ray"),
        default="local",
        help="with --zoo: local trains the runs one after another; ray runs each "
        "as a Ray task of one CPU (needs the ray extra) (default: %(default)s)",
    )
    ap.add_argument(
        "--address",
        default=None,
        help="with --backend ray: an existing Ray cluster (e.g. ray://host:10001 "
        "or auto); default: start a local Ray with --jobs CPUs",
    )
    ap.add_argument(
        "--jobs",
        type=int,
        default=None,
        help="with --backend ray: CPUs of a new local Ray, so runs at a time "
        f"(default: the number of CPUs, {os.cpu_count() or 1})",
    )
    return ap


def _check_zoo_flags(ap: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """argparse errors for --runs, --backend, --address and --jobs out of place."""
    given = [
        f
        for f, v in (
            ("--runs", args.runs is not None),
            ("--backend", args.backend != "local"),
            ("--resume", args.resume),
            ("--address", args.address is not None),
            ("--jobs", args.jobs is not None),
        )
        if v
    ]
    if given and not args.zoo:
        ap.error(f"argument {given[0]}: only with --zoo")
    for flag, value in (("--address", args.address), ("--jobs", args.jobs)):
        if value is not None and args.backend != "ray":
            ap.error(f"argument {flag}: only with --backend ray")
    if args.jobs is not None and args.jobs < 1:
        ap.error(f"argument --jobs: must be >= 1, got {args.jobs}")
    if args.backend == "ray" and not ray_backend.installed():
        ap.error(f"argument --backend: ray is not installed; {ray_backend.INSTALL}")


def main(argv: list[str] | None = None) -> None:
    ap = make_parser()
    args = ap.parse_args(argv)
    _check_zoo_flags(ap, args)
    try:
        if args.zoo:
            if args.max_minutes is not None and args.max_minutes <= 0:
                raise ConfigError(f"--max-minutes must be > 0, got {args.max_minutes}")
            entries = zoo_entries()
            if args.hyperparams and not Path(args.hyperparams).is_file():
                raise ConfigError(f"--hyperparams {args.hyperparams}: no such file")
            if args.hyperparams and args.algo:  # the entries of that file
                algo_class(args.algo)  # a known algo, or the list of them
                entries = [(env_id, args.algo) for env_id in entries_of(Path(args.hyperparams))]
            elif not (args.env or args.algo):  # rebuild what ships (a residual ships only
                entries = [e for e in entries if e in set(shipped())]  # where it pays)
            env = zoo_env(args.env)
            entries = [
                (env_id, algo)
                for env_id, algo in entries
                if (not env or env_id == env) and (not args.algo or algo == args.algo)
            ]
            if not entries:
                where = args.hyperparams or "the shipped hyperparameter files"
                there = entries_of(Path(args.hyperparams)) if args.hyperparams else zoo_entries()
                raise ConfigError(
                    f"no entry for --env {args.env!r} and --algo {args.algo!r} in {where}; "
                    f"entries: {there}"
                )
            for env_id, algo in entries:  # every entry checked before the first run
                read_hyperparams(
                    Path(args.hyperparams or HYPERPARAMS / f"{algo}.yml"), env_id, algo
                )
            jobs = zoo_jobs(
                entries,
                Path(args.out or ZOO),
                args.seed,
                args.runs,
                args.max_minutes,
                timesteps=args.timesteps,
                n_envs=args.n_envs,
                hyperparams=args.hyperparams and Path(args.hyperparams).resolve(),
            )
            if args.resume:  # the runs whose files are there are done
                jobs = [j for j in jobs if not finished(j)]
            if args.backend == "ray":
                done = ray_backend.results(
                    zoo_run, jobs, args.jobs or os.cpu_count() or 1, args.address
                )
            else:
                done = ((job, zoo_run(job)) for job in jobs)
            for _, meta in done:
                print(_summary(meta), flush=True)
            return
        if not args.env or not args.algo:
            ap.error("--env and --algo are required (or --zoo)")
        out = Path(args.out or "trained")
        meta = train(
            checked_run(
                args.env,
                args.algo,
                args.hyperparams,
                args.timesteps,
                args.seed,
                args.n_envs,
                out,
                args.max_minutes,
                args.tensorboard,
            )
        )
    except ConfigError as exc:
        ap.error(str(exc))
    print(_summary(meta))


def _summary(meta: dict[str, Any]) -> str:
    keys = ("env_id", "algo", "run", "seed", "timesteps_trained", "cpu_time_s", "wall_time_s")
    return json.dumps({k: meta[k] for k in keys} | {"validation": meta["validation"]["best"]})


if __name__ == "__main__":
    main()
