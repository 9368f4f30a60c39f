"""The commissioning tests that choose mpc_linear's move suppression (declared by each plant,
``commissioning["mpc_linear"]``).

    python benchmarks/mpc_linear_tuning.py [--envs a,b] [--seed 0]

Two tests per plant, both with the named scenarios' disturbances (thermocouple noise and
the coloured heat-absorption disturbance) and neither an evaluation scenario: a -5 %
heat-absorption step at minute 5 (40 min, rated load) and cascade_pi's feed-forward
commissioning ramp (100 -> 60 -> 100 % at 3 %/min). For every weight of
``MOVE_WEIGHT_LADDER`` it prints mpc_linear's return and valve travel next to those of
``cascade_pi_ff``, and the rule's choice: the smallest weight (the
least move suppression) whose travel stays within ``TRAVEL_RATIO_MAX`` times the
reference's on both tests.
"""

from __future__ import annotations

import argparse
import dataclasses

import gymnasium as gym

import baselines
import steamtemp_gym
from agents.evaluation import run_episode
from baselines.cascade_pi import FF_RAMP
from baselines.mpc_linear import TRAVEL_RATIO_MAX, MPCLinear
from baselines.mpc_linear_design import MOVE_WEIGHT_LADDER, rule_move_weight
from steamtemp_gym.scenarios import NAMED_DISTURBANCES, Scenario

TESTS = (
    Scenario(
        name="heat_step_commissioning",
        duration_s=2400.0,
        heat_absorption_bias=((0.0, 0.0), (300.0, 0.0), (360.0, -0.05)),
        **NAMED_DISTURBANCES,
    ),
    dataclasses.replace(FF_RAMP, **NAMED_DISTURBANCES),
)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--envs", default=",".join(steamtemp_gym.ENV_IDS))
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    print(
        "| plant | test | move weight | return | travel | cascade_pi_ff return | travel | "
        "ratio |\n|---|---|---|---|---|---|---|---|"
    )
    for env_id in [e for e in args.envs.split(",") if e]:
        if env_id not in steamtemp_gym.ENV_IDS:
            ap.error(f"unknown env {env_id!r}; valid: {list(steamtemp_gym.ENV_IDS)}")
        ok = []
        refs = []
        for sc in TESTS:
            env = gym.make(env_id, scenario=sc)
            refs.append(run_episode(env, baselines.make("cascade_pi_ff", env), args.seed))
        for w in MOVE_WEIGHT_LADDER:
            fits = True
            for sc, ref in zip(TESTS, refs, strict=True):
                env = gym.make(env_id, scenario=sc)
                knobs = {**MPCLinear.knob_defaults(env_id), "move_weight": w}  # not stored ones
                m = run_episode(env, MPCLinear(env, **knobs), args.seed)["metrics"]
                rm = ref["metrics"]
                ratio = m["valve_travel"] / rm["valve_travel"]
                fits &= ratio <= TRAVEL_RATIO_MAX
                print(
                    f"| {env_id.split('/')[-1]} | {sc.name} | {w:g} | {m['return']:.1f} | "
                    f"{m['valve_travel']:.2f} | {rm['return']:.1f} | {rm['valve_travel']:.2f} "
                    f"| {ratio:.2f} |",
                    flush=True,
                )
            if fits:
                ok.append(w)
        choice = min(ok) if ok else max(MOVE_WEIGHT_LADDER)
        print(
            f"\n{env_id}: rule gives {choice:g}; the plant declares {rule_move_weight(env_id)}\n",
            flush=True,
        )


if __name__ == "__main__":
    main()
