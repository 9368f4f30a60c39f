"""Behaviour cloning from a Minari dataset, saved as a trained agent's files.

``python -m agents.behaviour_cloning --dataset steamtemp/SupercriticalFSH/mpc_linear-noisy-v0
--out bc`` fits an MLP (two hidden layers of 128 ReLU units, a tanh output) by mean
squared error to the dataset's (observation, action) pairs and writes it in
steamtemp-train's layout (agents/files.py): ``bc/<env>__bc.zip``, an SB3 TD3 model whose
actor is the MLP (TD3's actor is exactly such a network), and ``bc/<env>__bc.json`` with
the observation pipeline. So ``steamtemp-leaderboard --policies zoo:bc`` scores it as any
trained agent (agents/policy.py: the actor in float64 NumPy). docs/offline.md.

What the clone sees and learns, by default as the imitation agents (agents/imitation.py):

- **observation**: the env's, with the controller memory of the :data:`IMITATION` entry
  (every observed signal over the plant's dead time and lag, the load and setpoint rates,
  the error integral) computed along each recorded episode as the agent computes it when
  it acts (the episodes of one length side by side), standardized with the data's mean
  and variance (frozen VecNormalize statistics);
- **label**: the action the dataset's policy chose: the info ``policy_action`` where the
  dataset injected noise (agents/datasets.py ``--noise``), else the recorded action;
- **output**: a valve position through the first-order filter of the same entry (time
  constant ``agents.horizons.action_filter``, 9-14 s), so that the clone does not
  stroke the valve on every measurement's noise.

``--plain`` clones the env's observation alone into the raw action (no memory, no filter).

``python -m agents.behaviour_cloning --zoo`` rebuilds the shipped clones (``sb3:bc``): per
plant, the datasets :data:`ZOO_DATASET` at each noise of :data:`ZOO_NOISES` (recorded where
Minari's data folder lacks them), a clone of each validated as the agents' checkpoints are
(agents/validation.py: the best return within the tuner's travel bound, else the least
travel), and :data:`ZOO_RUNS` runs (fit seeds 0, 1, 2) from the chosen one into
``agents/zoo``. How much noise a clone needs differs by plant (docs/offline.md).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

import agents
import steamtemp_gym
from agents.files import find, steamtemp_paths
from agents.horizons import from_plant
from agents.memory import MemoryConfig
from agents.tuning_terms import TUNING_TRAVEL_BUDGET
from agents.validation import better_checkpoint, reference_result, scored
from steamtemp_gym import envs as envs_

ALGO = "bc"
HIDDEN = (128, 128)
#: The entry whose controller memory and output filter the clone takes: the imitation
#: agents' (agents/hyperparams/ppo_imitation_mpc.yml).
IMITATION = "ppo_imitation_mpc"
#: The dataset of the shipped clones (agents/datasets.py ``record``'s arguments): 96 episodes
#: of mpc_linear on the training distribution with noise of 5 % of the stroke injected.
ZOO_DATASET = {"policy": "mpc_linear", "episodes": 96, "seed": 0}
#: The noises (fraction of the stroke) of the datasets the shipped clones choose from.
ZOO_NOISES = (0.05, 0.1, 0.2)
#: Runs of each shipped clone, as steamtemp-train's zoo has for every agent.
ZOO_RUNS = 3
#: The standardization's epsilon and clip, as SB3's VecNormalize defaults.
EPSILON, CLIP_OBS = 1e-8, 10.0


def _imitation_entry(env_id: str) -> dict[str, Any]:
    """The :data:`IMITATION` entry of ``env_id`` with its plant rules applied."""
    # torch (the agents extra) through agents.train_config: this module imports without it
    from agents.train_config import HYPERPARAMS, read_hyperparams

    path = HYPERPARAMS / f"{IMITATION}.yml"
    return from_plant(env_id, read_hyperparams(path, env_id, IMITATION))


def memory_of(env_id: str) -> dict[str, Any]:
    """The clone's controller-memory options on ``env_id``: the imitation agents'."""
    return _imitation_entry(env_id)["env_wrapper"]


def filter_of(env_id: str) -> float:
    """The clone's output filter time constant (s) on ``env_id``: the imitation agents'."""
    return _imitation_entry(env_id)["action_filter_s"]


def transitions(
    dataset: Any, memory: dict[str, Any] | None = None, env: Any = None
) -> tuple[np.ndarray, np.ndarray]:
    """(observations, labels) of every step of a Minari dataset: each episode's
    observations but its last (with the controller ``memory`` appended, computed along the
    episode as agents.policy.AgentPolicy does, for ``env``'s observation layout), and the
    action the policy chose there (module docstring)."""
    # torch (the agents extra) through agents.datasets: this module imports without it
    from agents.datasets import POLICY_ACTION

    # torch (the agents extra) through agents.wrappers: this module imports without it
    from agents.wrappers import MemoryState

    obs, act = [], []
    for ep in dataset.iterate_episodes():
        infos = ep.infos if isinstance(ep.infos, dict) else {}
        label = infos[POLICY_ACTION][1:] if POLICY_ACTION in infos else ep.actions
        obs.append(np.asarray(ep.observations, dtype=np.float64)[:-1])
        act.append(np.asarray(label, dtype=np.float64).reshape(len(ep.actions), -1))
    if not obs:
        raise ValueError(f"dataset {dataset.spec.dataset_id} holds no episode")
    if memory is not None:  # episodes of one length side by side, one row each
        config = MemoryConfig.from_kwargs(memory)
        for n in {len(o) for o in obs}:
            same = [i for i, o in enumerate(obs) if len(o) == n]
            state, batch = MemoryState(env, config), np.stack([obs[i] for i in same])
            x = np.stack([state(batch[:, k], np.full(len(same), k == 0)) for k in range(n)], 1)
            for j, i in enumerate(same):
                obs[i] = x[j]
    return np.concatenate(obs), np.concatenate(act)


def standardization(x: np.ndarray) -> dict[str, Any]:
    """Frozen VecNormalize statistics of the observations ``x`` (agents.policy
    ``normalize_obs``): their mean and variance, SB3's epsilon and clip."""
    return {
        "mean": x.mean(axis=0).tolist(),
        "var": x.var(axis=0).tolist(),
        "epsilon": EPSILON,
        "clip_obs": CLIP_OBS,
    }


def fit(
    obs: np.ndarray,
    act: np.ndarray,
    *,
    epochs: int = 10,
    batch: int = 256,
    lr: float = 1e-3,
    seed: int = 0,
    max_seconds: float = 120.0,
    log: Any = None,
) -> tuple[Any, dict[str, Any]]:
    """The MLP (a torch Sequential) fitted to ``act`` from standardized ``obs``, and the
    standardization (VecNormalize's frozen statistics, agents.policy.normalize_obs).
    Training stops after ``epochs`` or ``max_seconds``, whichever comes first."""
    import torch

    # torch (the agents extra) through agents.policy: this module imports without it
    from agents.policy import normalize_obs

    if obs.ndim != 2 or act.ndim != 2 or len(obs) != len(act) or not len(obs):
        raise ValueError(
            f"observations {obs.shape} and actions {act.shape} must be 2-d arrays "
            "of as many rows, at least one"
        )
    stats = standardization(obs)
    torch.set_num_threads(1)  # one core: a minute or two for 100 episodes
    torch.manual_seed(seed)
    x = torch.as_tensor(normalize_obs(obs, stats), dtype=torch.float32)
    y = torch.as_tensor(np.clip(act, -1.0, 1.0), dtype=torch.float32)
    net = actor(obs.shape[1], act.shape[1])
    regress(
        net, x, y, epochs=epochs, batch=batch, lr=lr, seed=seed, max_seconds=max_seconds, log=log
    )
    return net, stats


def regress(
    net: Any,
    x: Any,
    y: Any,
    *,
    epochs: int,
    batch: int = 256,
    lr: float = 1e-3,
    seed: int = 0,
    max_seconds: float = 120.0,
    log: Any = None,
    moves: tuple[Any, Any, float] | None = None,
) -> float:
    """Fit the torch module ``net`` to ``y`` from ``x`` (tensors) by mean squared error with
    Adam, in shuffled minibatches, for ``epochs`` or ``max_seconds``, whichever comes
    first; the last epoch's mean squared error of the actions. ``moves``: (x of the next
    step, y of the next step, weight): the loss adds weight times the squared error of the
    move ``net(x_next) - net(x)`` against ``y_next - y`` over the moves' mean square (a
    learner that matches the actions but not their moves strokes the valve on every
    measurement's noise)."""
    import torch

    opt = torch.optim.Adam(net.parameters(), lr=lr)
    gen = torch.Generator().manual_seed(seed)
    if moves is not None:  # the expert's moves' mean square: the move term's unit
        scale = float(torch.mean((moves[1] - y) ** 2)) + 1e-12
    t0 = time.perf_counter()
    mse = float("nan")
    for epoch in range(epochs):
        perm = torch.randperm(len(x), generator=gen)
        total = 0.0
        for i in range(0, len(x), batch):
            idx = perm[i : i + batch]
            a = net(x[idx])
            loss = torch.mean((a - y[idx]) ** 2)
            fit = loss
            if moves is not None:
                step = net(moves[0][idx]) - a
                loss = loss + moves[2] * torch.mean((step - (moves[1][idx] - y[idx])) ** 2) / scale
            opt.zero_grad()
            loss.backward()
            opt.step()
            total += float(fit.detach()) * len(idx)
        mse = total / len(x)
        if log:
            log(f"epoch {epoch + 1}: mse {mse:.3g}")
        if time.perf_counter() - t0 > max_seconds:
            break
    return mse


def actor(n_obs: int, n_act: int) -> Any:
    """The MLP, laid out as SB3 TD3's actor ``mu`` with ``net_arch`` :data:`HIDDEN`."""
    import torch

    layers, width = [], n_obs
    for h in HIDDEN:
        layers += [torch.nn.Linear(width, h), torch.nn.ReLU()]
        width = h
    return torch.nn.Sequential(*layers, torch.nn.Linear(width, n_act), torch.nn.Tanh())


def save(
    net: Any,
    stats: dict[str, Any],
    env_id: str,
    out: str | Path,
    dataset_id: str,
    training: dict[str, Any],
    memory: dict[str, Any] | None = None,
    action_filter_s: float | None = None,
    run: int | None = None,
) -> tuple[Path, Path]:
    """Write the agent (run ``run``) in steamtemp-train's layout; returns the .zip and .json
    paths."""
    import gymnasium as gym
    import torch
    from stable_baselines3 import TD3

    # torch (the agents extra) through agents.wrappers: this module imports without it
    from agents.wrappers import ControllerMemory

    model_path, meta_path = steamtemp_paths(out, env_id, ALGO, run)
    model_path.parent.mkdir(parents=True, exist_ok=True)
    env = gym.make(env_id)
    env = ControllerMemory(env, **memory) if memory is not None else env
    model = TD3(
        "MlpPolicy",
        env,
        buffer_size=1,
        learning_starts=0,
        device="cpu",
        policy_kwargs={"net_arch": list(HIDDEN)},
    )
    with torch.no_grad():
        for target in (model.actor.mu, model.actor_target.mu):
            target.load_state_dict(net.state_dict())
    model.save(model_path)
    meta = {
        "env_id": env_id,
        "algo": ALGO,
        "run": run,
        "sb3_class": "TD3",
        "memory": memory,
        "normalization": stats,
        "residual_scale": None,
        "action_filter_s": action_filter_s,
        "package_version": steamtemp_gym.__version__,
        "dataset": dataset_id,
        "training": training,
    }
    meta_path.write_text(json.dumps(meta, indent=1) + "\n", encoding="utf-8")
    return model_path, meta_path


def train(
    dataset_id: str,
    out: str | Path,
    *,
    plain: bool = False,
    epochs: int = 10,
    seed: int = 0,
    max_seconds: float = 120.0,
    run: int | None = None,
    log: Any = None,
) -> tuple[Path, Path]:
    """Load the dataset, fit the MLP, write the agent (module docstring); ``plain``: the
    env's observation alone into the raw action."""
    import gymnasium as gym
    import minari

    dataset = minari.load_dataset(dataset_id)
    env_id = dataset.spec.env_spec.id
    held, made = dataset.observation_space.shape, gym.make(env_id).observation_space.shape
    if held != made:
        raise ValueError(
            f"its observations have shape {held} but those of {env_id}, the env "
            f"it names, have {made}: it was recorded on another env"
        )
    memory = None if plain else memory_of(env_id)
    filter_s = None if plain else filter_of(env_id)
    t0 = time.perf_counter()
    obs, act = transitions(dataset, memory, gym.make(env_id))
    t1 = time.perf_counter()
    net, stats = fit(obs, act, epochs=epochs, seed=seed, max_seconds=max_seconds, log=log)
    return save(
        net,
        stats,
        env_id,
        out,
        dataset_id,
        {
            "transitions": len(obs),
            "epochs": epochs,
            "seed": seed,
            "plain": plain,
            "memory_seconds": round(t1 - t0, 1),
            "seconds": round(time.perf_counter() - t1, 1),
        },
        memory,
        filter_s,
        run,
    )


def zoo_dataset_id(env_id: str, noise: float) -> str:
    """The id of the shipped clones' dataset of ``env_id`` with ``noise``."""
    # torch (the agents extra) through agents.datasets: this module imports without it
    from agents import datasets

    name = datasets.dataset_name(ZOO_DATASET["policy"], noise=noise)
    return datasets.dataset_id(env_id, name)


def choose_noise(env_id: str, staging: Path, log: Any = None) -> tuple[str, dict[str, Any], Path]:
    """(dataset id, record, folder of its clone) of ``env_id``'s shipped clones: each
    dataset of :data:`ZOO_NOISES` (recorded where missing) cloned with seed 0 into a folder
    of ``staging`` and validated; the best by agents.validation.better_checkpoint within
    the tuner's travel bound."""
    from minari.storage import get_dataset_path

    # torch (the agents extra) through agents.datasets: this module imports without it
    from agents import datasets

    ref = reference_result(env_id)
    tried, best, chosen, folder = {}, {}, None, None
    for noise in ZOO_NOISES:
        did = zoo_dataset_id(env_id, noise)
        if not Path(get_dataset_path(did)).is_dir():
            d = ZOO_DATASET
            datasets.record(env_id, d["policy"], d["episodes"], d["seed"], noise=noise, log=log)
        here = staging / f"{noise:g}"
        train(did, here, log=None)
        (files,) = find(here)
        score = scored(env_id, files.load(), ref)
        tried[f"{noise:g}"] = {k: score[k] for k in ("return", "travel_ratio")}
        if log:
            log(
                f"{did}: validation return {score['return']:.1f}, travel "
                f"{score['travel_ratio']:.2f}x"
            )
        if better_checkpoint(score, best, TUNING_TRAVEL_BUDGET):
            best.update(score)
            chosen, folder = did, here
    record = {"noises": tried, "dataset": chosen, "reference_return": ref["return"]}
    return chosen, record, folder


def rebuild_zoo(env_ids: list[str], out: str | Path, log: Any = None) -> list[Path]:
    """The shipped clones of ``env_ids`` (module docstring); their model files. Run 0 is
    the clone the noise was chosen with; runs 1 and on are fitted from its dataset."""
    import shutil
    import tempfile

    written = []
    for env_id in env_ids:
        with tempfile.TemporaryDirectory() as tmp:
            did, record, first = choose_noise(env_id, Path(tmp), log)
            for run in range(ZOO_RUNS):
                model, meta = steamtemp_paths(out, env_id, ALGO, run or None)
                if run == 0:
                    model.parent.mkdir(parents=True, exist_ok=True)
                    for src, dst in zip(
                        steamtemp_paths(first, env_id, ALGO), (model, meta), strict=True
                    ):
                        shutil.copyfile(src, dst)
                else:
                    train(did, out, seed=run, run=run, log=log)
                doc = json.loads(meta.read_text(encoding="utf-8"))
                doc["run"], doc["noise_choice"] = run, record
                meta.write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
                written.append(model)
    return written


def _positive(kind: type, what: str):
    def parse(text: str):
        try:
            v = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"{what} must be a {kind.__name__}, got {text!r}"
            ) from None
        if not (v > 0 and np.isfinite(v)):
            raise argparse.ArgumentTypeError(f"{what} must be > 0, got {text!r}")
        return v

    return parse


def _seed(text: str) -> int:
    """``--seed``: an integer in [0, 2**32), what numpy and torch take."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text[:40]!r}") from None
    if not 0 <= value < 2**32:
        raise argparse.ArgumentTypeError(f"{text[:40]} is outside [0, 2**32)")
    return value


def make_parser() -> argparse.ArgumentParser:
    """The command line's argument parser."""
    ap = argparse.ArgumentParser(
        prog="python -m agents.behaviour_cloning", description=(__doc__ or "").split("\n")[0]
    )
    ap.add_argument("--dataset", help="a Minari dataset id")
    ap.add_argument("--out", help="folder of the agent's files (with --zoo: default agents/zoo)")
    ap.add_argument(
        "--zoo",
        action="store_true",
        help="rebuild the shipped clones (module docstring), recording their "
        "datasets where missing",
    )
    ap.add_argument(
        "--env",
        action="append",
        dest="envs",
        metavar="ID",
        help="with --zoo: a plant (repeatable; default every plant)",
    )
    ap.add_argument(
        "--data-dir",
        default=None,
        metavar="DIR",
        help="Minari's data folder (default: MINARI_DATASETS_PATH, else ~/.minari/datasets)",
    )
    ap.add_argument("--epochs", type=_positive(int, "--epochs"), default=10)
    ap.add_argument("--max-minutes", type=_positive(float, "--max-minutes"), default=2.0)
    ap.add_argument("--seed", type=_seed, default=0)
    ap.add_argument(
        "--run",
        type=_positive(int, "--run"),
        default=None,
        metavar="K",
        help="write run K's files (<env>__bc__runK), as steamtemp-train --runs names them",
    )
    ap.add_argument(
        "--plain",
        action="store_true",
        help="the env's observation alone into the raw action: no controller "
        "memory, no output filter",
    )
    return ap


def main(argv: list[str] | None = None) -> int:
    ap = make_parser()
    args = ap.parse_args(argv)
    if args.zoo == (args.dataset is not None):
        ap.error("give one of --dataset ID or --zoo")
    if args.envs and not args.zoo:
        ap.error("argument --env: only with --zoo (a dataset names its plant)")
    if not args.zoo and args.out is None:
        ap.error("argument --out is required with --dataset")
    for flag, path in (("--out", args.out), ("--data-dir", args.data_dir)):
        if path is not None and Path(path).exists() and not Path(path).is_dir():
            ap.error(f"argument {flag}: {str(path)[:200]!r} is a file, not a folder")
    try:
        env_ids = [envs_.resolve_id(e) for e in args.envs or steamtemp_gym.ENV_IDS]
    except ValueError as exc:
        ap.error(f"argument --env: {exc}")
    try:
        import minari  # noqa: F401
    except ImportError:
        ap.error("minari is not installed: pip install 'steamtemp-gym[offline]'")
    if args.data_dir is not None:
        os.environ["MINARI_DATASETS_PATH"] = str(Path(args.data_dir).resolve())
    from minari.storage import get_dataset_path

    say = lambda m: print(m, file=sys.stderr)  # noqa: E731
    if args.zoo:
        for model in rebuild_zoo(env_ids, args.out or agents.ZOO, log=say):
            print(model)
        return 0

    try:
        found = Path(get_dataset_path(args.dataset)).is_dir()
    except ValueError as exc:
        ap.error(f"argument --dataset: {exc}")
    if not found:
        ap.error(
            f"argument --dataset: no dataset {args.dataset!r} in "
            f"{os.environ.get('MINARI_DATASETS_PATH', '~/.minari/datasets')} "
            "(python -m agents.datasets makes one)"
        )
    try:
        model, meta = train(
            args.dataset,
            args.out,
            plain=args.plain,
            epochs=args.epochs,
            seed=args.seed,
            max_seconds=60.0 * args.max_minutes,
            run=args.run,
            log=say,
        )
    except (ValueError, OSError, KeyError, IndexError, TypeError) as exc:  # its files' fault
        ap.error(
            f"argument --dataset: {args.dataset!r} cannot be learnt from: "
            f"{type(exc).__name__}: {str(exc)[:300]}"
        )
    print(f"{model} and {meta}: score it with steamtemp-leaderboard --policies zoo:{args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
