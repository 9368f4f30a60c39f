"""steamtemp-leaderboard: every policy on every env, scenario and seed.

Writes ``leaderboard.json`` (one row per env, scenario, policy, seed with the
metrics of steamtemp_gym.metrics plus the episode return), ``leaderboard.md``
(means over seeds) and one trend plot per env and scenario (all policies, first
seed) under ``plots/``. Policies: the baselines (``baselines.NAMES``) and the
shipped trained agents (``agents.shipped()``, named ``sb3:<algo>``).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import gymnasium as gym
import numpy as np

import agents
import baselines
import steamtemp_gym
from agents.evaluation import run_episode

DEFAULT_SCENARIOS = ("load_ramp_100_50", "load_ramp_50_100", "setpoint_step",
                     "heat_imbalance_step", "load_following")  # fmt: skip
TABLE_METRICS = ("iae_K_s", "max_abs_dev_K", "time_outside_5K_s", "settling_time_s",
                 "spray_used_kg", "valve_travel", "valve_reversals", "return")  # fmt: skip


def _policies(env_id: str, names: list[str] | None) -> list[str]:
    avail = list(baselines.NAMES) + [f"sb3:{a}" for e, a in agents.shipped() if e == env_id]
    if names is None:
        return avail
    unknown = [n for n in names if n not in avail and n not in baselines.NAMES]
    if unknown:
        raise SystemExit(f"unknown policies {unknown}; available for {env_id}: {avail}")
    return [n for n in names if n in avail]


def _make_policy(name: str, env_id: str, env):
    if name.startswith("sb3:"):
        return agents.load(env_id, name[4:])
    return baselines.make(name, env)


def _plot(
    out: Path, env_id: str, scenario: str, traces: dict[str, dict], secondary: tuple = ()
) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = 2 + len(secondary)
    fig, axes = plt.subplots(n, 1, figsize=(9, 3 + 1.5 * n), sharex=True,
                             gridspec_kw={"height_ratios": [2] + [1] * (n - 1)})  # fmt: skip
    ax1, ax2 = axes[0], axes[-1]
    for ax, (name, sp2) in zip(axes[1:-1], secondary, strict=True):
        for band, alpha in ((5, 0.2), (8, 0.1)):
            ax.axhspan(sp2 - band, sp2 + band, color="tab:green", alpha=alpha, lw=0)
        ax.axhline(sp2, color="k", ls="--", lw=1)
        for pname, tr in traces.items():
            ax.plot(tr["time_s"] / 60, tr[name], lw=1.2, label=pname)
        ax.set_ylabel(name.replace("_C", " [C]"))
        ax.grid(alpha=0.3)
    first = next(iter(traces.values()))
    t = first["time_s"] / 60
    sp = first["setpoint_C"]
    for band, alpha in ((5, 0.2), (8, 0.1)):
        ax1.fill_between(t, sp - band, sp + band, color="tab:green", alpha=alpha, lw=0)
    ax1.plot(t, sp, "k--", lw=1, label="setpoint")
    for name, tr in traces.items():
        ax1.plot(tr["time_s"] / 60, tr["outlet_temp_C"], lw=1.2, label=name)
        ax2.plot(
            tr["time_s"] / 60, 100 * np.atleast_2d(tr["spray_valve"].T).T[:, 0], lw=1, label=name
        )
    ax1.set_ylabel("main steam [C]")
    ax1.legend(fontsize=7)
    ax1.grid(alpha=0.3)
    ax1.set_title(f"{env_id} - {scenario}", fontsize=9)
    ax2b = ax2.twinx()
    ax2b.plot(t, 100 * first["load"], "tab:gray", lw=0.8)
    ax2b.set_ylabel("load [%]", color="tab:gray")
    ax2.set_ylabel("spray valve 1 [%]")
    ax2.set_xlabel("time [min]")
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    path = out / "plots" / f"{env_id.split('/')[-1]}__{Path(scenario).stem}.png"
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=80)
    plt.close(fig)
    return path


def _mean(values: list[float]) -> float:
    """Mean over the finite values (NaN where a metric does not apply, e.g. no setpoint step)."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    return float(v.mean()) if v.size else float("nan")


def _markdown(rows: list[dict]) -> str:
    lines = ["# steamtemp_gym leaderboard", "",
             "Means over seeds. IAE in K s, deviations in K, times in s, spray in kg; "
             "return is the "
             "default reward summed over the episode (higher is better).", ""]  # fmt: skip
    keys = sorted({(r["env"], r["scenario"]) for r in rows})
    for env_id, sc in keys:
        lines += [f"## {env_id} - {sc}", "",
                  "| policy | " + " | ".join(TABLE_METRICS) + " | trips |",
                  "|---|" + "---|" * (len(TABLE_METRICS) + 1)]  # fmt: skip
        pols = sorted({r["policy"] for r in rows if r["env"] == env_id and r["scenario"] == sc})
        for p in pols:
            sel = [r for r in rows if (r["env"], r["scenario"], r["policy"]) == (env_id, sc, p)]
            vals = [_mean([r["metrics"][m] for r in sel]) for m in TABLE_METRICS]
            trips = int(sum(r["metrics"]["tripped"] for r in sel))
            lines.append(f"| {p} | " + " | ".join(f"{v:.4g}" for v in vals) + f" | {trips} |")
        lines.append("")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(prog="steamtemp-leaderboard", description=__doc__.split("\n")[0])
    ap.add_argument("--envs", default=",".join(steamtemp_gym.ENV_IDS))
    ap.add_argument("--policies", default=None, help="comma list (default: all available)")
    ap.add_argument("--scenarios", default=",".join(DEFAULT_SCENARIOS),
                    help="comma list of scenario names or YAML paths")  # fmt: skip
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--out", default="leaderboard_out")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    envs = [e for e in args.envs.split(",") if e]
    unknown = [e for e in envs if e not in steamtemp_gym.ENV_IDS]
    if unknown:
        raise SystemExit(f"unknown env ids {unknown}; valid: {list(steamtemp_gym.ENV_IDS)}")
    seeds = [int(s) for s in args.seeds.split(",")]
    rows = []
    t0 = time.time()
    for env_id in envs:
        names = _policies(env_id, args.policies.split(",") if args.policies else None)
        for sc in args.scenarios.split(","):
            env = gym.make(env_id, scenario=sc)
            traces = {}
            for name in names:
                policy = _make_policy(name, env_id, env)
                for seed in seeds:
                    res = run_episode(env, policy, seed)
                    rows.append({"env": env_id, "scenario": sc, "policy": name, "seed": seed,
                                 "metrics": res["metrics"]})  # fmt: skip
                    traces.setdefault(name, res["trace"])
                m = rows[-1]["metrics"]
                print(
                    f"{env_id:32s} {sc:22s} {name:14s} IAE {m['iae_K_s']:9.1f} K s  "
                    f"max|dev| {m['max_abs_dev_K']:6.2f} K  return {m['return']:9.2f}",
                    flush=True,
                )
            _plot(out, env_id, sc, traces, env.unwrapped.plant.secondary)
    (out / "leaderboard.json").write_text(json.dumps(rows, indent=1, default=float))
    (out / "leaderboard.md").write_text(_markdown(rows))
    print(
        f"wrote {out / 'leaderboard.json'}, {out / 'leaderboard.md'} and plots/ "
        f"({len(rows)} episodes, {time.time() - t0:.0f} s)"
    )


if __name__ == "__main__":
    main()
