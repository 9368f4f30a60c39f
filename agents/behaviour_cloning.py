"""Behaviour cloning from a Minari dataset, saved as a trained agent's files.

``python -m agents.behaviour_cloning --dataset steamtemp/SupercriticalFSH/mpc_linear-v0
--out bc`` fits a small MLP (two hidden layers of 64 ReLU units, a tanh output) to the
dataset's (observation, action) pairs by mean squared error, the observation
standardized with the dataset's mean and variance, and writes it in steamtemp-train's
layout (agents/files.py): ``bc/<env>__bc.zip``, an SB3 TD3 model whose actor is the MLP
(TD3's actor is exactly such a network), and ``bc/<env>__bc.json`` with the
standardization as frozen VecNormalize statistics. So ``steamtemp-leaderboard --policies
zoo:bc`` scores it as any trained agent (agents/policy.py: the actor in float64 NumPy);
it sees the env's observation alone, without controller memory. docs/offline.md.
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

import steamtemp_gym
from agents.files import steamtemp_paths

ALGO = "bc"
HIDDEN = (64, 64)
#: The standardization's epsilon and clip, as SB3's VecNormalize defaults.
EPSILON, CLIP_OBS = 1e-8, 10.0


def transitions(dataset: Any) -> tuple[np.ndarray, np.ndarray]:
    """(observations, actions) of every step of a Minari dataset: each episode's
    observations but its last, with the action taken after it."""
    obs, act = [], []
    for ep in dataset.iterate_episodes():
        obs.append(np.asarray(ep.observations, dtype=np.float64)[:-1])
        act.append(np.asarray(ep.actions, dtype=np.float64).reshape(len(ep.actions), -1))
    if not obs:
        raise ValueError(f"dataset {dataset.spec.dataset_id} holds no episode")
    return np.concatenate(obs), np.concatenate(act)


def fit(obs: np.ndarray, act: np.ndarray, *, epochs: int = 30, batch: int = 256,
        lr: float = 1e-3, seed: int = 0, max_seconds: float = 120.0,
        log: Any = None) -> tuple[Any, dict[str, Any]]:  # fmt: skip
    """The MLP (a torch Sequential) fitted to ``act`` from standardized ``obs``, and the
    standardization (VecNormalize's frozen statistics, agents.policy.normalize_obs).
    Training stops after ``epochs`` or ``max_seconds``, whichever comes first."""
    import torch

    from agents.policy import normalize_obs

    if obs.ndim != 2 or act.ndim != 2 or len(obs) != len(act) or not len(obs):
        raise ValueError(f"observations {obs.shape} and actions {act.shape} must be 2-d arrays "
                         "of as many rows, at least one")  # fmt: skip
    stats = {"mean": obs.mean(axis=0).tolist(), "var": obs.var(axis=0).tolist(),
             "epsilon": EPSILON, "clip_obs": CLIP_OBS}  # fmt: skip
    torch.set_num_threads(1)  # one core: a minute or two for 100 episodes
    torch.manual_seed(seed)
    x = torch.as_tensor(normalize_obs(obs, stats), dtype=torch.float32)
    y = torch.as_tensor(np.clip(act, -1.0, 1.0), dtype=torch.float32)
    net = actor(obs.shape[1], act.shape[1])
    regress(net, x, y, epochs=epochs, batch=batch, lr=lr, seed=seed, max_seconds=max_seconds,
            log=log)  # fmt: skip
    return net, stats


def regress(net: Any, x: Any, y: Any, *, epochs: int, batch: int = 256, lr: float = 1e-3,
            seed: int = 0, max_seconds: float = 120.0, log: Any = None,
            moves: tuple[Any, Any, float] | None = None) -> float:  # fmt: skip
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
            idx = perm[i:i + batch]
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


def save(net: Any, stats: dict[str, Any], env_id: str, out: str | Path,
         dataset_id: str, training: dict[str, Any]) -> tuple[Path, Path]:  # fmt: skip
    """Write the agent in steamtemp-train's layout; returns the .zip and .json paths."""
    import gymnasium as gym
    import torch
    from stable_baselines3 import TD3

    model_path, meta_path = steamtemp_paths(out, env_id, ALGO)
    model_path.parent.mkdir(parents=True, exist_ok=True)
    env = gym.make(env_id)
    model = TD3("MlpPolicy", env, buffer_size=1, learning_starts=0, device="cpu",
                policy_kwargs={"net_arch": list(HIDDEN)})  # fmt: skip
    with torch.no_grad():
        for target in (model.actor.mu, model.actor_target.mu):
            target.load_state_dict(net.state_dict())
    model.save(model_path)
    meta = {"env_id": env_id, "algo": ALGO, "sb3_class": "TD3", "memory": None,
            "normalization": stats, "residual_scale": None,
            "package_version": steamtemp_gym.__version__, "dataset": dataset_id,
            "training": training}  # fmt: skip
    meta_path.write_text(json.dumps(meta, indent=1) + "\n", encoding="utf-8")
    return model_path, meta_path


def train(dataset_id: str, out: str | Path, *, epochs: int = 30, seed: int = 0,
          max_seconds: float = 120.0, log: Any = None) -> tuple[Path, Path]:  # fmt: skip
    """Load the dataset, fit the MLP, write the agent (module docstring)."""
    import minari

    dataset = minari.load_dataset(dataset_id)
    env_id = dataset.spec.env_spec.id
    obs, act = transitions(dataset)
    t0 = time.perf_counter()
    net, stats = fit(obs, act, epochs=epochs, seed=seed, max_seconds=max_seconds, log=log)
    seconds = time.perf_counter() - t0
    return save(net, stats, env_id, out, dataset_id,
                {"transitions": len(obs), "epochs": epochs, "seed": seed,
                 "seconds": round(seconds, 1)})  # fmt: skip


def _positive(kind: type, what: str):
    def parse(text: str):
        try:
            v = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{what} must be a {kind.__name__}, got {text!r}") \
                from None  # fmt: skip
        if not (v > 0 and np.isfinite(v)):
            raise argparse.ArgumentTypeError(f"{what} must be > 0, got {text!r}")
        return v

    return parse


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m agents.behaviour_cloning",
                                 description=(__doc__ or "").split("\n")[0])  # fmt: skip
    ap.add_argument("--dataset", required=True, help="a Minari dataset id")
    ap.add_argument("--out", required=True, help="folder of the agent's files")
    ap.add_argument("--data-dir", default=None, metavar="DIR",
                    help="Minari's data folder (default: MINARI_DATASETS_PATH, else "
                    "~/.minari/datasets)")  # fmt: skip
    ap.add_argument("--epochs", type=_positive(int, "--epochs"), default=30)
    ap.add_argument("--max-minutes", type=_positive(float, "--max-minutes"), default=2.0)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    try:
        import minari  # noqa: F401
    except ImportError:
        ap.error("minari is not installed: pip install 'steamtemp-gym[offline]'")
    if args.data_dir is not None:
        os.environ["MINARI_DATASETS_PATH"] = str(Path(args.data_dir).resolve())
    from minari.storage import get_dataset_path

    try:
        found = Path(get_dataset_path(args.dataset)).is_dir()
    except ValueError as exc:
        ap.error(f"argument --dataset: {exc}")
    if not found:
        ap.error(f"argument --dataset: no dataset {args.dataset!r} in "
                 f"{os.environ.get('MINARI_DATASETS_PATH', '~/.minari/datasets')} "
                 "(python -m agents.datasets makes one)")  # fmt: skip
    model, meta = train(args.dataset, args.out, epochs=args.epochs, seed=args.seed,
                        max_seconds=60.0 * args.max_minutes,
                        log=lambda m: print(m, file=sys.stderr))  # fmt: skip
    print(f"{model} and {meta}: score it with steamtemp-leaderboard --policies "
          f"zoo:{args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
