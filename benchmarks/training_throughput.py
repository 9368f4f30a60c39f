"""Training throughput: decisions per CPU-second of an SB3 learner on the native vector env,
an entry's settings against the same entry with large-batch settings, per plant.

    python -m benchmarks.training_throughput [--algo ppo] [--envs FSH,Benson]
        [--hyperparams FILE] [--seconds 60] [--repeats 1]

For each plant the entry of ``--algo`` in the hyperparameter file (default: the shipped
one) is built as ``steamtemp-train`` builds it (agents.vec_env.make_training_env,
agents.sb3_models.sb3_model: the same wrappers, memory, action repeat, normalization and
model) and trained for about ``--seconds`` of this process's CPU time, rollouts and
updates both, without validation; then the same entry with the large-batch settings of
:data:`LARGE` for the algorithm family. A decision is one action of the agent (``k``
control intervals with an action repeat of ``k``). Printed: decisions per CPU-second of
each and their ratio, the best of ``--repeats`` interleaved runs (the machine may be
shared: compare the ratios, measured in the same run).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import torch
from stable_baselines3.common.callbacks import BaseCallback

import steamtemp_gym
from agents.sb3_models import sb3_model
from agents.train_config import HYPERPARAMS, algo_class, read_hyperparams
from agents.vec_env import make_training_env
from steamtemp_gym.envs import resolve_id

#: Large-batch settings per algorithm family: on-policy (PPO and its kinds) and off-policy.
#: On-policy: 64 envs x 128-step rollouts (8,192 decisions), minibatches of 2,048, 5
#: epochs. Off-policy: 64 envs, 2 gradient steps on minibatches of 2,048 per vector step: 64
#: sampled transitions per decision, as the shipped 8 envs with 2 steps of 256.
LARGE = {
    "on": {"n_envs": 64, "n_steps": 128, "batch_size": 2048, "n_epochs": 5},
    "off": {"n_envs": 64, "batch_size": 2048, "train_freq": 1, "gradient_steps": 2},
}


def family(algo: str) -> str:
    """ "off" for an algorithm with a replay buffer, else "on"."""
    return "off" if algo.split("_")[0] in ("sac", "td3") else "on"


def large(hp: dict[str, Any], algo: str) -> dict[str, Any]:
    """The entry ``hp`` with the large-batch settings of its family."""
    return {**hp, **LARGE[family(algo)]}


class _CpuBudget(BaseCallback):
    """Stops learning after ``seconds`` of this process's CPU time."""

    def __init__(self, seconds: float) -> None:
        super().__init__()
        self.seconds, self.t0 = seconds, time.process_time()

    def _on_step(self) -> bool:
        return time.process_time() - self.t0 < self.seconds


def decisions_per_cpu_s(env_id: str, algo: str, hp: dict[str, Any], seconds: float) -> float:
    """Decisions per CPU-second of learning with the entry ``hp`` for about ``seconds``."""
    venv, native, _ = make_training_env(env_id, hp["n_envs"], 0, hp, reference_rate=1.0)
    repeat = hp.get("action_repeat") or 1
    model = sb3_model(algo_class(algo), hp, venv, 0, None, native.plant.dt_s * repeat)
    t0 = time.process_time()
    model.learn(total_timesteps=10**9, callback=_CpuBudget(seconds), progress_bar=False)
    rate = model.num_timesteps / (time.process_time() - t0)
    venv.close()
    return rate


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--algo", default="ppo")
    ap.add_argument("--envs", default=",".join(steamtemp_gym.ENV_IDS))
    ap.add_argument("--hyperparams", type=Path, default=None)
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--repeats", type=int, default=1)
    args = ap.parse_args(argv)
    torch.set_num_threads(1)  # one core per run, as steamtemp-train trains
    path = args.hyperparams or HYPERPARAMS / f"{args.algo}.yml"
    print(f"{args.algo} ({path.name}): decisions per CPU-second, {args.seconds:g} s each")
    print(f"{'plant':24s} {'entry':>10s} {'large batch':>12s} {'ratio':>6s}")
    for name in args.envs.split(","):
        env_id = resolve_id(name)
        hp = read_hyperparams(path, env_id, args.algo)
        best = {"entry": 0.0, "large": 0.0}
        for _ in range(args.repeats):
            best["entry"] = max(
                best["entry"], decisions_per_cpu_s(env_id, args.algo, hp, args.seconds)
            )
            best["large"] = max(
                best["large"],
                decisions_per_cpu_s(env_id, args.algo, large(hp, args.algo), args.seconds),
            )
        short = env_id.split("/")[-1]
        print(
            f"{short:24s} {best['entry']:10,.0f} {best['large']:12,.0f} "
            f"{best['large'] / best['entry']:5.1f}x",
            flush=True,
        )


if __name__ == "__main__":
    main()
