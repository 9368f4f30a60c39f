"""What the learning rate does to the neuro-PID: a ladder of eta per criterion on training
episodes, then MEE against MSE on the paper's setpoint step.

    python benchmarks/neuro_pid_eta.py [--env ID] [--etas 1e-4,1e-3,...] [--train-seeds 1000-1005]
        [--step-seeds 0-9]

Part 1 (training episodes only: the ``random`` scenario, seeds ``--train-seeds``, never a
named or held-out scenario): for each criterion and eta, the mean return less
``cascade_pi_ff``'s on the same seeds (the leaderboard's score before its normalization by
the oracle), the valve-travel ratio to ``cascade_pi_ff``, trips, and how far the net moved
the gains: the mean over the episode of |k_l(t) / k_l(0) - 1| for k_p and k_i, and the time
share of k_i within 5 % of its bounds (k_i0 (1 -+ GAIN_RANGE): a saturated output). The choice
per criterion (baselines.neuro_pid.ADAPTING_ETA) is the smallest eta at which the net adapts
without saturating: training moves k_i at zero input by at least ADAPT_MIN = 10 % on average
over the training episodes, k_i sits near a bound less than 5 % of the time, travel stays
within 2x ``cascade_pi_ff``'s and nothing trips (the common tuner's constraints). It
compares the criteria between nets that adapt by about the same amount; the return column
shows what a score-driven choice (the common tuner's) would take. ``--chosen
mee=...,mse=...`` skips part 1.

Part 2 (Cascade300MW, ``setpoint_step_535_545``, seeds ``--step-seeds``): the error
e = setpoint - true outlet, mean and std over each episode, at the paper's eta and at the
chosen etas, and the paired MEE - MSE differences over the seeds.
"""

from __future__ import annotations

import argparse

import gymnasium as gym
import numpy as np

import baselines
from agents.evaluation import run_batch
from baselines.neuro_pid import NeuroPID, Recorder
from baselines.neuro_pid_net import ETA, GAIN_RANGE, N_HIDDEN, N_IN, forward

TRAVEL_MAX, ADAPT_MIN = 2.0, 0.10


def _seeds(text: str) -> list[int]:
    a, _, b = text.partition("-")
    return list(range(int(a), int(b or a) + 1))


def run(env_id: str, scenario: str, seeds: list[int], criterion: str | None, eta: float):
    """(results, gains (steps, seeds, 3) or None) of one batch."""
    venv = gym.make_vec(
        env_id, num_envs=len(seeds), scenario=scenario, vectorization_mode="vector_entry_point"
    )
    if criterion is None:
        return run_batch(venv, baselines.make("cascade_pi_ff", venv), seeds), None
    rec = Recorder(NeuroPID(venv, criterion=criterion, eta=eta))
    res = run_batch(venv, rec, seeds)
    return res, (np.array(rec.outputs), learned(rec.pol))


def learned(pol: NeuroPID) -> np.ndarray:
    """(rows, 3): the net's gains at zero input after the episode relative to the start,
    |k(W_end) / k(W_0) - 1| (what training moved, apart from the inputs' modulation)."""
    W = pol._st["W"][:: len(pol.main)]
    h, g = np.empty(N_HIDDEN), np.empty(3)
    out = []
    for w in W:
        forward(w, np.zeros(N_IN), h, g)
        out.append(GAIN_RANGE * np.abs(g / 0.5 - 1.0))  # k / k0 - 1 = 2 r (g - 1/2)
    return np.array(out)


def adaptation(g: np.ndarray) -> tuple[float, float, float]:
    """Mean |k/k0 - 1| of k_p and k_i (k0: the commissioning gain at the same load, the net's
    output at its start g0 = 1/2), and the time share of k_i within 5 % of its bounds."""
    rel = GAIN_RANGE * np.abs(g / 0.5 - 1.0)
    near = (g[..., 1] < 0.05) | (g[..., 1] > 0.95)
    return float(rel[..., 0].mean()), float(rel[..., 1].mean()), float(near.mean())


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--env", default="steamtemp/Cascade300MW-v0")
    ap.add_argument("--etas", default="1e-4,1e-3,1e-2,1e-1,1,10")
    ap.add_argument("--train-seeds", default="1000-1005")
    ap.add_argument("--step-seeds", default="0-9")
    ap.add_argument("--chosen", default="")
    args = ap.parse_args(argv)
    etas = [float(x) for x in args.etas.split(",")]
    if args.chosen:
        chosen = {k: float(v) for k, v in (kv.split("=") for kv in args.chosen.split(","))}
    else:
        chosen = ladder(args, etas)
    compare(args, chosen)


def ladder(args: argparse.Namespace, etas: list[float]) -> dict[str, float]:
    """Part 1: the eta ladder on training episodes; the choice per criterion."""
    train = _seeds(args.train_seeds)
    ref, _ = run(args.env, "random", train, None, 0.0)
    r_ref = np.array([r["metrics"]["return"] for r in ref])
    t_ref = np.array([r["metrics"]["valve_travel"] for r in ref])
    print(
        f"training: {args.env} random seeds {train[0]}-{train[-1]}; cascade_pi_ff return "
        f"{r_ref.mean():.1f}, travel {t_ref.mean():.2f}"
    )
    print(
        "| criterion | eta | return - ff | travel ratio | trips | |kp/kp0-1| | |ki/ki0-1| | "
        "ki near bound | learned kp | ki | kd |\n|---|---|---|---|---|---|---|---|---|---|---|"
    )
    chosen = {}
    for crit in ("mee", "mse"):
        best = None
        for eta in etas:
            res, g = run(args.env, "random", train, crit, eta)
            dr = np.array([r["metrics"]["return"] for r in res]) - r_ref
            ratio = np.mean([r["metrics"]["valve_travel"] for r in res]) / t_ref.mean()
            trips = np.mean([r["metrics"]["tripped"] for r in res])
            ap_, ai, near = adaptation(g[0])
            lp, li, ld = g[1].mean(axis=0)
            print(
                f"| {crit} | {eta:g} | {dr.mean():+.2f} | {ratio:.2f} | {trips:.2f} | "
                f"{ap_:.3f} | {ai:.3f} | {near:.2f} | {lp:.3f} | {li:.3f} | {ld:.3f} |",
                flush=True,
            )
            fits = ratio <= TRAVEL_MAX and trips == 0 and li >= ADAPT_MIN and near < 0.05
            if fits and best is None:
                best = (eta, dr.mean())
        chosen[crit] = best[0] if best else ETA
    print(f"chosen: {chosen}")
    return chosen


def compare(args: argparse.Namespace, chosen: dict[str, float]) -> None:
    """Part 2: MEE against MSE on the paper's step at the paper's and the chosen etas."""
    step = _seeds(args.step_seeds)
    print(
        f"\npaper's step, seeds {step[0]}-{step[-1]}: e = setpoint - true outlet\n"
        "| criterion | eta | mean e K | std e K | |kp/kp0-1| | |ki/ki0-1| | learned kp | ki "
        "| kd |\n|---|---|---|---|---|---|---|---|---|"
    )
    stats = {}
    for label, etas_c in (("paper", {"mee": ETA, "mse": ETA}), ("chosen", chosen)):
        for crit in ("mee", "mse"):
            res, g = run(args.env, "setpoint_step_535_545", step, crit, etas_c[crit])
            e = np.array([r["trace"]["setpoint_C"] - r["trace"]["outlet_temp_C"] for r in res])
            stats[label, crit] = np.stack([e.mean(axis=1), e.std(axis=1)], axis=1)
            ap_, ai, _ = adaptation(g[0])
            lp, li, ld = g[1].mean(axis=0)
            m = stats[label, crit].mean(axis=0)
            print(
                f"| {crit} ({label}) | {etas_c[crit]:g} | {m[0]:.4f} | {m[1]:.4f} | "
                f"{ap_:.3f} | {ai:.3f} | {lp:.3f} | {li:.3f} | {ld:.3f} |",
                flush=True,
            )
        d = stats[label, "mee"] - stats[label, "mse"]
        se = d.std(axis=0, ddof=1) / np.sqrt(len(step))
        print(
            f"paired MEE - MSE ({label}): mean {d[:, 0].mean():+.4f} +- {se[0]:.4f} K, "
            f"std {d[:, 1].mean():+.4f} +- {se[1]:.4f} K (paper: -0.0641, -0.0104)"
        )


if __name__ == "__main__":
    main()
