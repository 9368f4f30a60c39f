"""Neuro-PID realism on every plant: valve travel against cascade_pi_ff, limit cycles, peaks.

    python benchmarks/neuro_pid_realism.py [--envs a,b] [--scenarios s,...] [--seeds 0-2]
        [--policies neuro_pid_mee,neuro_pid_mse:1e-3,...]

A policy given as ``name:eta`` runs with that learning rate (default: the paper's).

For each plant and scenario (default: the leaderboard's named and held-out scenarios, and
on Cascade300MW also its own two), runs the policies and ``cascade_pi_ff`` on the same
seeds in the vector env and prints, per policy, the mean over seeds of the valve travel
and its ratio to ``cascade_pi_ff``'s (the realism bound: 3), ``quiet_p2p_K`` against its
bound max(2 x cascade_pi_ff's, 1.5 K), the peak |error| (``max_abs_dev_K``) and trips.
"""

from __future__ import annotations

import argparse

import gymnasium as gym
import numpy as np

import baselines
import steamtemp_gym
from agents.evaluation import run_batch
from agents.leaderboard.plan import DEFAULT_SCENARIOS
from steamtemp_gym import scenarios

OWN = {"steamtemp/Cascade300MW-v0": ("setpoint_step_535_545", "load_ramp_100_50_100_2pct")}
REF = "cascade_pi_ff"


def measure(env_id: str, spec: str, policy: str, seeds: list[int], **kw) -> dict[str, float]:
    """Mean over seeds of the episode metrics of ``policy`` (keywords go to its factory)."""
    sc = scenarios.resolve(spec, env_id)
    venv = gym.make_vec(
        env_id, num_envs=len(seeds), scenario=sc, vectorization_mode="vector_entry_point"
    )
    pol = baselines.make(policy, venv, **kw)
    res = run_batch(venv, pol, seeds)
    keys = res[0]["metrics"].keys()
    return {k: float(np.mean([r["metrics"][k] for r in res])) for k in keys}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--envs", default=",".join(steamtemp_gym.ENV_IDS))
    ap.add_argument("--scenarios", default="")
    ap.add_argument("--seeds", default="0-2")
    ap.add_argument("--policies", default="neuro_pid_mee,neuro_pid_mse")
    args = ap.parse_args(argv)
    a, _, b = args.seeds.partition("-")
    seeds = list(range(int(a), int(b or a) + 1))
    policies = [p.partition(":") for p in args.policies.split(",") if p]
    print("| plant | scenario | policy | travel | ratio | quiet p2p K | bound | peak K | trips |")
    print("|---|---|---|---|---|---|---|---|---|")
    for env_id in [e for e in args.envs.split(",") if e]:
        specs = [s for s in args.scenarios.split(",") if s] or [
            *DEFAULT_SCENARIOS,
            *OWN.get(env_id, ()),
        ]
        for spec in specs:
            ref = measure(env_id, spec, REF, seeds)
            bound = max(2.0 * ref["quiet_p2p_K"], 1.5)
            short = env_id.split("/")[1].removesuffix("-v0")
            for name, _, eta in [(REF, "", ""), *policies]:
                kw = {"eta": float(eta)} if eta else {}
                m = ref if name == REF else measure(env_id, spec, name, seeds, **kw)
                name = f"{name} (eta {eta})" if eta else name
                ratio = m["valve_travel"] / ref["valve_travel"]
                flag = " !" if ratio > 3.0 or m["quiet_p2p_K"] > bound else ""
                print(
                    f"| {short} | {spec} | {name} | {m['valve_travel']:.2f} | {ratio:.2f}{flag}"
                    f" | {m['quiet_p2p_K']:.2f} | {bound:.2f} | {m['max_abs_dev_K']:.2f} | "
                    f"{m['tripped']:.2f} |",
                    flush=True,
                )


if __name__ == "__main__":
    main()
