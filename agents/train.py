"""steamtemp-train: train a Stable-Baselines3 agent on one plant.

    steamtemp-train --env steamtemp/Cascade300MW-v0 --algo ppo [--timesteps N] [--seed 0]
        [--n-envs N] [--out DIR] [--hyperparams FILE] [--max-minutes M] [--tensorboard DIR]
    python -m agents.train --zoo [--env ID] [--algo A] [--out DIR] [--runs K]
        [--backend {local,ray}] [--address ADDRESS] [--jobs N] [--max-minutes M]
        # rebuild agents/zoo/ (or DIR): every shipped agent from its shipped YAML entry;
        # with --env/--algo, every YAML entry of that env/algo; with --runs K, K
        # independent training runs of each (run k: seed --seed + 1000 k)

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
docs/robustness.md; such entries are not for RL Zoo). Every other key
must be an argument of the algorithm's constructor. All input is checked before training
starts. Validation, the leaderboard and every score use the env's default reward.

Training runs on the ``random`` scenario distribution through the native vector env
(agents.vec_env), with the controller memory and VecNormalize when configured. At every
eighth of the budget (and at a --max-minutes stop) the agent is evaluated (agents.evaluation) on
``random`` validation episodes with seeds from :data:`VALIDATION_SEED` (training envs
use ``--seed`` + i: never the same draws; never the leaderboard's scenarios); the best
one is kept: the highest validation return among the checkpoints within the leaderboard's
valve-travel budget (mean travel at most ``agents.stats.TRAVEL_BUDGET`` times
``cascade_pi_ff``'s on the same validation episodes), or, if none is, the one of least
travel. Output in ``--out``: ``<env>__<algo>.zip`` (the best SB3 model) and
``<env>__<algo>.json`` (env id, package version, git revision, hyperparameters, seed,
timesteps, wall time, the validation curve and score, the normalization statistics and
the wrapper config: everything ``agents.load`` needs).

Training runs (``--zoo --runs K``): run k of an agent is trained with seed
:func:`run_seed` (``--seed`` + :data:`RUN_SEED_STRIDE` k: its training envs draw seeds
``seed + 1000 k + i``, never another run's) into ``<env>__<algo>__run<k>.zip/.json``
(agents/files.py). The runs go one after another at nice 10 (``--backend local``), or
each as a Ray task of one CPU (``--backend ray``: a new local Ray with ``--jobs`` CPUs, or
the cluster at ``--address``); ``--max-minutes`` bounds each run.
"""

from __future__ import annotations

import argparse
import ast
import json
import os
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import yaml

import steamtemp_gym
from agents import ray_backend, shipped
from agents.files import steamtemp_paths, stem
from agents.moves import check_max_move
from agents.policy import model_class
from agents.wrappers import memory_options

#: Algorithm names: SB3's PPO, SAC, TD3, PPO as a residual on cascade_pi_ff (its own YAML
#: file, whose entries need ``residual_scale``) and sb3-contrib's RecurrentPPO (an LSTM
#: policy: the memory is learned instead of given by agents.wrappers).
ALGOS = ("ppo", "sac", "td3", "ppo_residual", "recurrentppo", "sac_caps")
HYPERPARAMS = Path(__file__).with_name("hyperparams")
ZOO = Path(__file__).with_name("zoo")
#: Seeds of the validation episodes (``random`` scenario); training uses --seed + i.
VALIDATION_SEED = 1_000_000
N_VALIDATION = 3
#: Where in the budget the agent is validated (and the best kept): every eighth.
EVAL_FRACTIONS = tuple(k / 8 for k in range(1, 9))
#: Run k of ``--zoo --runs K`` trains with seed ``--seed + RUN_SEED_STRIDE * k``: more than
#: any n_envs, so no two runs share a training env's seed.
RUN_SEED_STRIDE = 1000
#: Most runs per agent (run seeds stay far below VALIDATION_SEED).
MAX_RUNS = 100
#: RL Zoo keys with a meaning of their own (the rest go to the algorithm's constructor).
SPECIAL = ("n_timesteps", "n_envs", "policy", "normalize", "env_wrapper", "policy_kwargs",
           "noise_type", "noise_std", "residual_scale", "max_move", "train_reward",
           "plant_randomization")  # fmt: skip


class ConfigError(ValueError):
    """Bad training input (env, algo, YAML, hyperparameter keys)."""


def _algo_class(algo: str):
    if algo not in ALGOS:
        raise ConfigError(f"unknown algo {algo!r}; valid: {list(ALGOS)}")
    names = {"recurrentppo": "RecurrentPPO", "sac_caps": "SACCAPS"}
    try:
        return model_class(names.get(algo, algo.split("_")[0].upper()))
    except ValueError as exc:
        raise ConfigError(str(exc)) from None


def _literal(node: ast.AST) -> Any:
    """A literal, or a ``dict(key=literal, ...)`` call of literals (nested)."""
    if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "dict" and not node.args:
        return {kw.arg: _literal(kw.value) for kw in node.keywords}
    return ast.literal_eval(node)


def _dict_string(key: str, value: Any) -> dict:
    """RL Zoo's "dict(a=1, b=dict(c=[2]))" strings (literals only; no code is run)."""
    if isinstance(value, dict):
        return dict(value)
    try:
        out = _literal(ast.parse(str(value), mode="eval").body)
        if not isinstance(out, dict):
            raise ValueError
        return out
    except (SyntaxError, ValueError):
        raise ConfigError(
            f"{key} must be a mapping or a 'dict(key=literal, ...)' string, got {value!r}"
        ) from None


def read_hyperparams(path: Path, env_id: str, algo: str) -> dict[str, Any]:
    """The checked hyperparameters of env_id in an RL-Zoo YAML file.

    Raises:
        ConfigError: unreadable or malformed YAML, no entry for env_id, unknown keys.
    """
    cls = _algo_class(algo)
    try:
        doc = yaml.safe_load(Path(path).read_text(encoding="utf-8"))
    except (OSError, yaml.YAMLError) as exc:
        raise ConfigError(f"--hyperparams {path}: cannot read it as YAML: {exc}") from None
    if not isinstance(doc, dict):
        raise ConfigError(f"--hyperparams {path}: expected a mapping of env ids")
    if env_id not in doc:
        raise ConfigError(f"--hyperparams {path}: no entry for {env_id}; has {sorted(doc)}")
    hp = doc[env_id]
    if not isinstance(hp, dict):
        raise ConfigError(f"--hyperparams {path}: {env_id} must map to a mapping")
    import inspect

    ctor = set()
    for c in cls.__mro__:  # a subclass taking **kwargs (agents/caps.py) passes them on
        params = inspect.signature(c.__init__).parameters
        ctor |= {n for n, p in params.items() if p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)}
        if not any(p.kind == p.VAR_KEYWORD for p in params.values()):
            break
    ctor -= {"self", "env", "policy"}
    unknown = sorted(set(hp) - set(SPECIAL) - ctor)
    if unknown:
        raise ConfigError(
            f"--hyperparams {path}: unknown key(s) {unknown} for {algo}; valid: "
            f"{sorted(ctor | set(SPECIAL))}"
        )
    if ("residual_scale" in hp) != algo.endswith("_residual"):
        raise ConfigError(f"--hyperparams {path}: residual_scale is required for a *_residual "
                          f"algo and only there (algo {algo!r})")  # fmt: skip
    if "max_move" in hp:
        if "residual_scale" in hp:
            raise ConfigError(f"--hyperparams {path}: residual_scale and max_move exclude each "
                              "other (an agent is residual or incremental)")  # fmt: skip
        try:
            check_max_move(hp["max_move"])
        except ValueError as exc:
            raise ConfigError(f"--hyperparams {path}: {exc}") from None
    if "train_reward" in hp:
        from steamtemp_gym.rewards import RewardConfig

        try:
            RewardConfig.from_options(hp["train_reward"])
        except ValueError as exc:
            raise ConfigError(f"--hyperparams {path}: train_reward: {exc}") from None
    if "plant_randomization" in hp:
        from steamtemp_gym.plants import perturb

        try:
            perturb.parse(env_id, hp["plant_randomization"])
        except ValueError as exc:
            raise ConfigError(f"--hyperparams {path}: {exc}") from None
    hp = dict(hp)
    hp["policy_kwargs"] = _dict_string("policy_kwargs", hp.get("policy_kwargs", {}))
    norm = hp.get("normalize", False)
    hp["normalize"] = norm if isinstance(norm, bool) else _dict_string("normalize", norm)
    try:
        hp["env_wrapper"] = memory_options(hp["env_wrapper"]) if "env_wrapper" in hp else None
    except ValueError as exc:
        raise ConfigError(str(exc)) from None
    if hp.get("noise_type") not in (None, "normal"):
        raise ConfigError(f"noise_type: only 'normal' is supported, got {hp['noise_type']!r}")
    return hp


def _schedule(value: Any):
    if isinstance(value, str) and value.startswith("lin_"):
        v0 = float(value[4:])
        return lambda progress_remaining: progress_remaining * v0
    return value


def _git_revision() -> str:
    try:
        done = subprocess.run(["git", "rev-parse", "HEAD"], cwd=Path(__file__).parent,
                              capture_output=True, text=True, check=True)  # fmt: skip
        return done.stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def make_training_env(env_id: str, n_envs: int, seed: int, hp: dict[str, Any]):
    """(VecEnv for training, the native vector env under it)."""
    from stable_baselines3.common.vec_env import VecMonitor, VecNormalize

    from agents.moves import VecMoves
    from agents.vec_env import NativeVecEnv
    from agents.wrappers import VecControllerMemory, VecResidual

    base = NativeVecEnv(env_id, n_envs, scenario="random", reward=hp.get("train_reward"),
                        plant_randomization=hp.get("plant_randomization"))  # fmt: skip
    venv = base
    if hp.get("residual_scale") is not None:
        venv = VecResidual(venv, base.venv, hp["residual_scale"])
    if hp.get("max_move") is not None:
        venv = VecMoves(venv, base.venv, hp["max_move"])
    if hp["env_wrapper"] is not None:
        venv = VecControllerMemory(venv, base.venv, **hp["env_wrapper"])
    venv = VecMonitor(venv)
    if hp["normalize"]:
        kw = hp["normalize"] if isinstance(hp["normalize"], dict) else {}
        venv = VecNormalize(venv, gamma=hp.get("gamma", 0.99), **kw)
    venv.seed(seed)
    return venv, base.venv


def _shown_path(path: Path) -> str:
    """``path`` as recorded in the metadata: relative to the project for a shipped file (no
    machine's directory in the zoo's metadata), as given otherwise."""
    try:
        return Path(path).resolve().relative_to(HYPERPARAMS.parent.parent).as_posix()
    except ValueError:
        return str(path)


def _obs_stats(venv) -> dict[str, Any] | None:
    from stable_baselines3.common.vec_env import VecNormalize

    from agents.policy import frozen_stats

    return frozen_stats(venv) if isinstance(venv, VecNormalize) else None


def validate(env_id: str, policy, n: int = N_VALIDATION) -> dict[str, float]:
    """Mean return, IAE and valve travel of ``policy`` over the validation episodes (default
    reward), run as one batch in the native vector env by agents.evaluation.run_batch (row k
    is ``gym.make(env_id, scenario="random")`` reset with seed VALIDATION_SEED + k, bit for
    bit). ``policy``: a Policy, or a factory ``venv -> Policy``."""
    import gymnasium as gym

    from agents.evaluation import run_batch

    venv = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point",
                        scenario="random")  # fmt: skip
    if not hasattr(policy, "predict"):
        policy = policy(venv)
    runs = run_batch(venv, policy, [VALIDATION_SEED + k for k in range(n)])
    venv.close()
    return {key: float(np.mean([r["metrics"][key] for r in runs]))
            for key in ("return", "iae_K_s", "valve_travel")}  # fmt: skip


def better_checkpoint(new: dict[str, float], best: dict[str, float], budget: float) -> bool:
    """Whether validation result ``new`` beats ``best`` (both with ``return`` and
    ``travel_ratio``): within the travel budget first, then the higher return; outside it,
    the lower travel."""
    if not best:
        return True
    ok_new, ok_best = new["travel_ratio"] <= budget, best["travel_ratio"] <= budget
    if ok_new != ok_best:
        return ok_new
    return new["return"] > best["return"] if ok_new else new["travel_ratio"] < best["travel_ratio"]


def train(env_id: str, algo: str, hyperparams: Path | None = None, timesteps: int | None = None,
          seed: int = 0, n_envs: int | None = None, out: Path = Path("trained"),
          max_minutes: float | None = None, tensorboard: str | None = None,
          quiet: bool = False, run: int | None = None) -> dict[str, Any]:  # fmt: skip
    """Train one agent (module docstring); returns its metadata. Input is checked first.
    ``run``: the training run's index in the file names (None: names without one)."""
    from steamtemp_gym.envs import resolve_id

    try:
        env_id = resolve_id(env_id)  # the namespace may be left out
    except ValueError:
        pass  # refused below, with the valid ids
    if env_id not in steamtemp_gym.ENV_IDS:
        raise ConfigError(f"unknown env {env_id!r}; valid: {list(steamtemp_gym.ENV_IDS)}")
    cls = _algo_class(algo)
    path = Path(hyperparams) if hyperparams else HYPERPARAMS / f"{algo}.yml"
    hp = read_hyperparams(path, env_id, algo)
    total = int(timesteps if timesteps is not None else hp.get("n_timesteps", 100_000))
    n_envs = int(n_envs if n_envs is not None else hp.get("n_envs", 1))
    if total < 1 or n_envs < 1:
        raise ConfigError(f"timesteps and n_envs must be >= 1, got {total} and {n_envs}")
    if max_minutes is not None and max_minutes <= 0:
        raise ConfigError(f"--max-minutes must be > 0, got {max_minutes}")
    import torch
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.noise import NormalActionNoise

    from agents.policy import AgentPolicy

    torch.set_num_threads(1)  # one core per run (a shared machine; small networks)
    venv, native = make_training_env(env_id, n_envs, seed, hp)
    kwargs = {k: v for k, v in hp.items() if k not in SPECIAL}
    kwargs["learning_rate"] = _schedule(kwargs.get("learning_rate", 3e-4))
    if hp.get("noise_type") == "normal":
        n_u = venv.action_space.shape[0]
        kwargs["action_noise"] = NormalActionNoise(np.zeros(n_u), hp.get("noise_std", 0.1)
                                                   * np.ones(n_u))  # fmt: skip
    model = cls(hp.get("policy", "MlpPolicy"), venv, seed=seed, device="cpu", verbose=0,
                policy_kwargs=hp["policy_kwargs"] or None, tensorboard_log=tensorboard,
                **kwargs)  # fmt: skip
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    name = stem(env_id, algo, run)
    model_path, meta_path = steamtemp_paths(out, env_id, algo, run)
    import baselines
    from agents.stats import TRAVEL_BUDGET

    reference = validate(env_id, lambda v: baselines.make(baselines.INDUSTRIAL_REFERENCE, v))
    revision = _git_revision()  # the code this run trains with
    t0 = time.monotonic()
    curve: list[dict[str, Any]] = []
    best: dict[str, Any] = {}

    def snapshot_policy():
        return AgentPolicy(model, native, memory=hp["env_wrapper"], obs_norm=_obs_stats(venv),
                           residual_scale=hp.get("residual_scale"),
                           max_move=hp.get("max_move"))  # fmt: skip

    class Progress(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.marks = [int(f * total) for f in EVAL_FRACTIONS]
            self.last_line = 0.0

        def _on_step(self) -> bool:
            steps, wall = self.num_timesteps, time.monotonic() - t0
            if self.marks and steps >= self.marks[0]:
                self.marks.pop(0)
                self._evaluate(steps, wall)
            if not quiet and wall - self.last_line > 10.0:
                self.last_line = wall
                eta = wall / max(steps, 1) * (total - steps)
                last = f", validation return {curve[-1]['return']:.1f}" if curve else ""
                print(f"[{name}] {steps:,}/{total:,} steps ({100 * steps / total:.0f} %), "
                      f"{steps / max(wall, 1e-9):,.0f} steps/s, ETA {eta / 60:.1f} min{last}",
                      file=sys.stderr, flush=True)  # fmt: skip
            if max_minutes is not None and wall > 60.0 * max_minutes:
                self._evaluate(steps, wall)
                return False
            return True

        def _evaluate(self, steps: int, wall: float) -> None:
            score = validate(env_id, snapshot_policy())
            score["travel_ratio"] = score["valve_travel"] / reference["valve_travel"]
            curve.append({"timesteps": steps, "fraction": steps / total, "wall_s": wall, **score})
            if better_checkpoint(score, best, TRAVEL_BUDGET):
                best.update(score, timesteps=steps, obs_norm=_obs_stats(venv))
                model.save(model_path)

    model.learn(total_timesteps=total, callback=Progress(), progress_bar=False)
    if not curve:  # a budget below the first mark's granularity
        Progress()._evaluate(model.num_timesteps, time.monotonic() - t0)
    meta = {
        "env_id": env_id, "algo": algo, "sb3_class": cls.__name__,
        "package_version": steamtemp_gym.__version__, "git_revision": revision,
        "hyperparams_file": _shown_path(path),
        "hyperparameters": json.loads(json.dumps(hp, default=str)), "seed": seed, "run": run,
        "n_envs": n_envs, "timesteps_budget": total, "timesteps_trained": model.num_timesteps,
        "timesteps_of_best": best["timesteps"], "wall_time_s": time.monotonic() - t0,
        "validation": {"scenario": "random", "seeds": [VALIDATION_SEED + k
                       for k in range(N_VALIDATION)], "best": {k: best[k] for k in
                       ("return", "iae_K_s", "valve_travel", "travel_ratio")},
                       "reference": {"policy": baselines.INDUSTRIAL_REFERENCE, **reference},
                       "travel_budget": TRAVEL_BUDGET, "curve": curve},
        "normalization": best["obs_norm"], "memory": hp["env_wrapper"],
        "residual_scale": hp.get("residual_scale"), "max_move": hp.get("max_move"),
        "train_reward": hp.get("train_reward"),
    }  # fmt: skip
    meta_path.write_text(json.dumps(meta, indent=1), encoding="utf-8")
    venv.close()
    return meta


def zoo_entries_of(algo: str) -> list[str]:
    """Env ids with an entry in the shipped hyperparameter file of ``algo``."""
    f = HYPERPARAMS / f"{algo}.yml"
    doc = (yaml.safe_load(f.read_text(encoding="utf-8")) or {}) if f.exists() else {}
    return [env_id for env_id in steamtemp_gym.ENV_IDS if env_id in doc]


def zoo_entries() -> list[tuple[str, str]]:
    """(env id, algo) of every entry of the shipped hyperparameter files, PPO first."""
    return [(env_id, algo) for algo in ALGOS for env_id in zoo_entries_of(algo)]


def run_seed(seed: int, run: int) -> int:
    """The seed of training run ``run`` of an agent: ``seed + RUN_SEED_STRIDE * run``."""
    return seed + RUN_SEED_STRIDE * run


def _run_count(text: str) -> int:
    """``--runs``: an integer from 1 to :data:`MAX_RUNS`."""
    try:
        k = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be an integer >= 1, got {text!r}") from None
    if not 1 <= k <= MAX_RUNS:
        raise argparse.ArgumentTypeError(f"must be an integer from 1 to {MAX_RUNS}, got {k}")
    return k


def _nice() -> None:
    """Lower this process's priority to nice 10 (no further if it is already lower)."""
    os.nice(max(0, 10 - os.nice(0)))


def zoo_run(job: dict[str, Any]) -> dict[str, Any]:
    """One training run of ``--zoo`` at nice 10 (a Ray task with ``--backend ray``):
    :func:`train` with the keyword arguments ``job``; its metadata."""
    _nice()
    return train(**job)


def zoo_jobs(entries: list[tuple[str, str]], out: Path, seed: int, runs: int | None,
             max_minutes: float, **options: Any) -> list[dict[str, Any]]:  # fmt: skip
    """The :func:`zoo_run` jobs of ``entries``: one per entry without ``runs`` (file names
    without a run index, ``seed``), else ``runs`` per entry (run k: :func:`run_seed`);
    ``options``: further arguments of :func:`train` (those that are not None)."""
    ks = [None] if runs is None else list(range(runs))
    extra = {k: v for k, v in options.items() if v is not None}
    return [{"env_id": env_id, "algo": algo, "out": Path(out).resolve(), "run": k,
             "seed": seed if k is None else run_seed(seed, k), "max_minutes": max_minutes,
             **extra} for env_id, algo in entries for k in ks]  # fmt: skip


def _zoo_env(name: str | None) -> str | None:
    """``--env`` of ``--zoo`` as a registered id (the namespace may be left out)."""
    if not name:
        return None
    from steamtemp_gym.envs import resolve_id

    try:
        return resolve_id(name)
    except ValueError as exc:
        raise ConfigError(str(exc)) from None


def make_parser() -> argparse.ArgumentParser:
    doc = __doc__ or ""
    ap = argparse.ArgumentParser(prog="steamtemp-train", description=doc.split("\n")[0],
                                 epilog=doc.split("\n", 2)[2],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    ap.add_argument("--env", help=f"env id, one of {list(steamtemp_gym.ENV_IDS)} (the name "
                    "after 'steamtemp/' is enough)")
    ap.add_argument("--algo", help=f"one of {list(ALGOS)}")
    ap.add_argument("--timesteps", type=int, default=None, help="default: n_timesteps of the YAML")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--n-envs", type=int, default=None, help="default: n_envs of the YAML")
    ap.add_argument("--out", default=None,
                    help="output directory (default: trained; with --zoo: agents/zoo/)")
    ap.add_argument("--hyperparams", default=None, help="YAML file (default: the shipped one)")
    ap.add_argument("--max-minutes", type=float, default=None,
                    help="stop after this wall time (with --zoo: of each run, default 10)")
    ap.add_argument("--tensorboard", default=None, help="TensorBoard log directory")
    ap.add_argument("--zoo", action="store_true",
                    help="rebuild agents/zoo/ (or --out): every shipped agent from its YAML "
                         "entry (or --hyperparams), or with --env/--algo every entry of "
                         "those; one at a time, at nice 10 (--max-minutes each, default 10; "
                         "--timesteps and --n-envs, when given, for each)")  # fmt: skip
    ap.add_argument("--runs", type=_run_count, default=None, metavar="K",
                    help=f"with --zoo: K independent training runs per agent (1 to {MAX_RUNS}), "
                    "written <env>__<algo>__run<k>; run k trains with seed --seed + "
                    f"{RUN_SEED_STRIDE} k (default: one run, written <env>__<algo>)")  # fmt: skip
    ap.add_argument("--backend", choices=("local", "ray"), default="local",
                    help="with --zoo: local trains the runs one after another; ray runs each "
                    "as a Ray task of one CPU (needs the ray extra) (default: %(default)s)")
    ap.add_argument("--address", default=None,
                    help="with --backend ray: an existing Ray cluster (e.g. ray://host:10001 "
                    "or auto); default: start a local Ray with --jobs CPUs")  # fmt: skip
    ap.add_argument("--jobs", type=int, default=None,
                    help="with --backend ray: CPUs of a new local Ray, so runs at a time "
                    f"(default: the number of CPUs, {os.cpu_count() or 1})")  # fmt: skip
    return ap


def _check_zoo_flags(ap: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """argparse errors for --runs, --backend, --address and --jobs out of place."""
    given = [f for f, v in (("--runs", args.runs is not None),
                            ("--backend", args.backend != "local"),
                            ("--address", args.address is not None),
                            ("--jobs", args.jobs is not None)) if v]  # fmt: skip
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
            if not (args.env or args.algo):  # rebuild what ships (a residual ships only
                entries = [e for e in entries if e in set(shipped())]  # where it pays)
            env = _zoo_env(args.env)
            entries = [(env_id, algo) for env_id, algo in entries
                       if (not env or env_id == env)
                       and (not args.algo or algo == args.algo)]  # fmt: skip
            if not entries:
                raise ConfigError(f"no entry for --env {args.env!r} and --algo {args.algo!r} "
                                  f"in the shipped hyperparameter files; entries: "
                                  f"{zoo_entries()}")  # fmt: skip
            for env_id, algo in entries:  # every entry checked before the first run
                read_hyperparams(Path(args.hyperparams or HYPERPARAMS / f"{algo}.yml"),
                                 env_id, algo)  # fmt: skip
            jobs = zoo_jobs(entries, Path(args.out or ZOO), args.seed, args.runs,
                            args.max_minutes or 10.0, timesteps=args.timesteps,
                            n_envs=args.n_envs, hyperparams=args.hyperparams and
                            Path(args.hyperparams).resolve())  # fmt: skip
            if args.backend == "ray":
                done = ray_backend.results(zoo_run, jobs, args.jobs or os.cpu_count() or 1,
                                           args.address)  # fmt: skip
            else:
                done = ((job, zoo_run(job)) for job in jobs)
            for _, meta in done:
                print(_summary(meta), flush=True)
            return
        if not args.env or not args.algo:
            ap.error("--env and --algo are required (or --zoo)")
        out = Path(args.out or "trained")
        meta = train(args.env, args.algo, args.hyperparams, args.timesteps, args.seed,
                     args.n_envs, out, args.max_minutes, args.tensorboard)  # fmt: skip
    except ConfigError as exc:
        ap.error(str(exc))
    print(_summary(meta))


def _summary(meta: dict[str, Any]) -> str:
    keys = ("env_id", "algo", "run", "seed", "timesteps_trained", "wall_time_s")
    return json.dumps({k: meta[k] for k in keys} | {"validation": meta["validation"]["best"]})


if __name__ == "__main__":
    main()
