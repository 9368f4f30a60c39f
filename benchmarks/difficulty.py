"""How hard is each plant? Reference policies on every named scenario (3 seeds, means).

    python benchmarks/difficulty.py [--envs ID,...] [--seeds 3] [--update-docs]

Prints, per env and named scenario, for a frozen valve, random actions, cascade PI,
cascade PI with doubled outer gain and cascade PI with the load feed-forward: peak
|e|, IAE, time outside +-5 K, spray used, valve travel, return and trips; then the
headroom (peak |e| of the feed-forward cascade against plain cascade PI on the
5 %/min ramps) and the spray step-response characteristics of every plant (gain,
Tu, Tg of the true and measured outlet for a last-stage step at 100 % and 50 % load). With
``--update-docs`` it rewrites the tables of docs/difficulty.md (between the
``difficulty:start`` / ``difficulty:end`` markers) from these numbers.
Targets: agents/difficulty.py (TARGETS).
"""

from __future__ import annotations

import argparse
import re
import time
from pathlib import Path

import numpy as np

import steamtemp_gym
from agents.difficulty import RAMPS, REFERENCE_POLICIES, difficulty_table, spray_step_dead_time

PAGE = Path(__file__).resolve().parents[1] / "docs" / "difficulty.md"
SHORT = {
    "max_abs_dev_K": "peak K",
    "iae_K_s": "IAE K s",
    "time_outside_5K_s": "t>5K s",
    "spray_used_kg": "spray t",
    "valve_travel": "travel",
    "return": "return",
    "tripped": "trips",
}


def _fmt(key: str, v: float) -> str:
    if not np.isfinite(v):
        return "-"
    if key == "spray_used_kg":
        return f"{v / 1000:.1f}"
    if key == "tripped":
        return f"{v:.2f}".rstrip("0").rstrip(".") if v else "0"
    if key in ("iae_K_s", "time_outside_5K_s", "return"):
        return f"{v:.0f}"
    return f"{v:.2f}"


def difficulty_markdown(rows: list[dict]) -> str:
    cols = list(SHORT)
    lines = [
        "| env | scenario | policy | " + " | ".join(SHORT[c] for c in cols) + " |",
        "|---|---|---|" + "---|" * len(cols),
    ]
    for r in rows:
        env = r["env"].split("/")[1].removesuffix("-v0")
        lines.append(
            f"| {env} | {r['scenario']} | {r['policy']} | "
            + " | ".join(_fmt(c, r[c]) for c in cols)
            + " |"
        )
    return "\n".join(lines)


def headroom_markdown(rows: list[dict]) -> str:
    by = {(r["env"], r["scenario"], r["policy"]): r for r in rows}
    envs = sorted({r["env"] for r in rows}, key=list(steamtemp_gym.ENV_IDS).index)
    lines = [
        "| env | frozen, 100->50 % | PI 100->50 % | PI 50->100 % | PI+FF 100->50 % "
        "| PI+FF 50->100 % | PI 2x gain 100->50 % |",
        "|---|---|---|---|---|---|---|",
    ]
    for env in envs:

        def g(sc, pol, env=env):
            r = by.get((env, sc, pol))
            return r["max_abs_dev_K"] if r else np.nan

        pi = [g(sc, "cascade_pi") for sc in RAMPS]
        ff = [g(sc, "cascade_pi_ff") for sc in RAMPS]
        cut = [f"{b:.1f} K ({100 * (b / a - 1):+.0f} %)" for a, b in zip(pi, ff, strict=True)]
        lines.append(
            f"| {env.split('/')[1].removesuffix('-v0')} | "
            f"{g(RAMPS[0], 'frozen'):.1f} K | {pi[0]:.1f} K | {pi[1]:.1f} K | "
            f"{cut[0]} | {cut[1]} | {g(RAMPS[0], 'cascade_pi_2x'):.1f} K |"
        )
    return "\n".join(lines)


def step_markdown(env_ids: list[str]) -> str:
    lines = [
        "| env | load | gain, K per unit valve | Tg true s | Tu/Tg true | Tu/Tg measured |",
        "|---|---|---|---|---|---|",
    ]
    for env_id in env_ids:
        for load in (1.0, 0.5):
            t, r = spray_step_dead_time(env_id, load)
            lines.append(
                f"| {env_id.split('/')[1].removesuffix('-v0')} | {load:.0%} | "
                f"{t.K:.1f} | {t.tau_s:.0f} | {t.theta_s / t.tau_s:.2f} | "
                f"{r.theta_s / r.tau_s:.2f} |"
            )
    return "\n".join(lines)


def replace_block(text: str, block: str) -> str:
    """``text`` with its ``difficulty:start`` ... ``difficulty:end`` block replaced by
    ``block``.

    Raises:
        SystemExit: ``text`` has not exactly one such block.
    """
    new, n = re.subn(
        r"<!-- difficulty:start.*?<!-- difficulty:end -->", lambda m: block, text, flags=re.S
    )
    if n != 1:
        raise SystemExit(f"{PAGE} has {n} difficulty:start/end blocks, expected 1")
    return new


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--envs", default=",".join(steamtemp_gym.ENV_IDS))
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--policies", default=",".join(REFERENCE_POLICIES))
    ap.add_argument(
        "--update-docs",
        action="store_true",
        help="rewrite the tables of docs/difficulty.md from this run",
    )
    args = ap.parse_args(argv)
    envs = [e if "/" in e else f"steamtemp/{e}-v0" for e in args.envs.split(",")]
    unknown = [e for e in envs if e not in steamtemp_gym.ENV_IDS]
    if unknown:
        raise SystemExit(f"unknown env ids {unknown}; valid: {list(steamtemp_gym.ENV_IDS)}")
    if args.seeds < 1:
        raise SystemExit("--seeds must be >= 1")
    t0 = time.perf_counter()
    rows = difficulty_table(envs, tuple(args.policies.split(",")), args.seeds)
    diff, head, steps = difficulty_markdown(rows), headroom_markdown(rows), step_markdown(envs)
    print(diff, "\n\nHeadroom (peak |e|, means over seeds):\n", head, "\n\nSpray steps:\n", steps)
    print(f"\n({time.perf_counter() - t0:.0f} s)")
    if args.update_docs:
        text = PAGE.read_text()
        block = (
            f"<!-- difficulty:start (generated by benchmarks/difficulty.py) -->\n"
            f"Spray step responses (last spray stage, +5 %; Tu/Tg of the true outlet and "
            f"of the thermocouple reading):\n\n{steps}\n\nHeadroom on the 5 %/min ramps "
            f"(peak \\|e\\|, means over {args.seeds} seeds):\n\n{head}\n\n"
            f"<details><summary>Every named scenario</summary>\n\n{diff}\n\n</details>\n"
            f"<!-- difficulty:end -->"
        )
        PAGE.write_text(replace_block(text, block))
        print(f"{PAGE.name} updated")


if __name__ == "__main__":
    main()
