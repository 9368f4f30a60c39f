"""python -m agents.mismatch: policies on the model-mismatch variants against the nominal plant.

Every policy is built (commissioned) on the NOMINAL env of each plant and then run,
unchanged, on the nominal plant and on each variant of
``steamtemp_gym.plants.perturb.mismatch(id)`` (``gym.make(id, params=variant)``): a baseline's
step tests and feed-forward fit see the model, the episodes see the unit. Scenarios:
``load_ramp_100_50`` and one held-out scenario (``--heldout``). The seeds of a policy,
plant and scenario run side by side in the native vector env (agents/evaluation.py).

Policies are named as for ``steamtemp-leaderboard --policies`` (agents/specs.py: baseline
names, ``sb3:<algo>``, trained agents' files, ``module:callable``); a policy not available
for a plant is skipped there (a note on stderr).

Output: a markdown table per plant (printed; also written to ``--out``): per policy and
variant the mean return over the seeds of each scenario, and the robustness column, the
return relative to the policy's nominal return (returns are negative costs: 1.00 is as
good as on the model, 1.30 is 30 % more cost), and the trips.

Bad flags are argparse errors (usage, exit code 2) before anything runs.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import steamtemp_gym
from agents import specs
from agents.evaluation import run_batch
from agents.leaderboard.plan import env_id_of, items, parse_seeds, policies
from steamtemp_gym import scenarios
from steamtemp_gym.plants import perturb

RAMP = "load_ramp_100_50"
DEFAULT_HELDOUT = "heldout:sootblowing"
DEFAULT_POLICIES = "cascade_pi,cascade_pi_ff,sb3:ppo"
NOMINAL = "nominal"


def make_parser() -> argparse.ArgumentParser:
    """The CLI's argument parser."""
    doc = __doc__ or ""
    ap = argparse.ArgumentParser(
        prog="python -m agents.mismatch",
        description=doc.split("\n")[0],
        epilog=doc.split("\n", 2)[2],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ap.add_argument(
        "--env",
        default=None,
        metavar="ID",
        help="one env id, with or without the steamtemp/ namespace (default: "
        "every plant with variants)",
    )
    ap.add_argument(
        "--policies",
        default=DEFAULT_POLICIES,
        help="comma list of policy names as steamtemp-leaderboard takes them "
        "(default: %(default)s)",
    )
    ap.add_argument(
        "--seeds", default="0,1", help="integers >= 0 or ranges a-b (default: %(default)s)"
    )
    ap.add_argument(
        "--heldout",
        default=DEFAULT_HELDOUT,
        help="the held-out scenario run besides load_ramp_100_50 (default: %(default)s)",
    )
    ap.add_argument(
        "--out",
        default=None,
        metavar="FILE",
        help="also write the markdown tables to FILE (default: print only)",
    )
    return ap


def _envs(ap: argparse.ArgumentParser, name: str | None) -> list[str]:
    if name is None:
        return [e for e in steamtemp_gym.ENV_IDS if perturb.variant_factors(e)]
    env_id = env_id_of(name)
    if env_id not in steamtemp_gym.ENV_IDS or not perturb.variant_factors(env_id):
        valid = [e for e in steamtemp_gym.ENV_IDS if perturb.variant_factors(e)]
        ap.error(
            f"argument --env: {name[:100]!r} is not a plant with mismatch variants; valid: {valid}"
        )
    return [env_id]


def _heldout(ap: argparse.ArgumentParser, spec: str, envs: list[str]) -> str:
    if not spec.startswith("heldout:"):
        ap.error(f"argument --heldout: {spec[:100]!r} is not a held-out scenario (heldout:<name>)")
    for e in envs:
        try:
            scenarios.resolve(spec, e)
        except ValueError as exc:
            ap.error(f"argument --heldout: {str(exc)[:400]}")
    return spec


def evaluate(
    env_id: str, policy: str, scenario: str, seeds: list[int], spec: specs.Spec | None = None
) -> dict[str, Any]:
    """{variant: (mean return, trips)} of ``policy`` (its Spec ``spec``, None: parsed here)
    commissioned on the nominal plant and run on it (``nominal``) and on every variant of
    ``env_id``, under ``scenario``."""

    def venv(params: dict | None = None) -> Any:
        return gym.make_vec(
            env_id,
            num_envs=len(seeds),
            vectorization_mode="vector_entry_point",
            scenario=scenario,
            params=params or {},
        )

    nominal = venv()
    spec = spec or specs.parse(policy, references=True)
    pol = spec.make(env_id, nominal)  # commissioned on the model
    out = {}
    for name, params in [(NOMINAL, None), *perturb.mismatch(env_id).items()]:
        rows = run_batch(nominal if params is None else venv(params), pol, seeds)
        out[name] = (
            float(np.mean([r["metrics"]["return"] for r in rows])),
            int(sum(r["metrics"]["tripped"] > 0 for r in rows)),
        )
    return out


def table(
    env_id: str, results: dict[str, dict[str, dict[str, Any]]], scenario_names: list[str]
) -> str:
    """The markdown table of one plant: results[policy][scenario][variant] = (return, trips)."""
    head = ["policy", "variant"]
    for s in scenario_names:
        head += [f"{s} return", f"{s} rel. nominal"]
    head.append("trips")
    lines = [f"### {env_id}", "", "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for pol, by_sc in results.items():
        for v in [NOMINAL, *perturb.variant_factors(env_id)]:
            cells = [pol, v]
            trips = 0
            for s in scenario_names:
                ret, n_trip = by_sc[s][v]
                nom = by_sc[s][NOMINAL][0]
                cells += [f"{ret:.1f}", f"{ret / nom:.2f}" if nom != 0 else "n/a"]
                trips += n_trip
            cells.append(str(trips))
            lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> None:
    ap = make_parser()
    args = ap.parse_args(argv)
    envs = _envs(ap, args.env)
    seeds = parse_seeds(ap, args.seeds)
    requested = items(ap, "--policies", args.policies)
    available, parsed = policies(ap, envs, args.policies, oracle=False)
    heldout = _heldout(ap, args.heldout, envs)
    scenario_names = [RAMP, heldout]
    if args.out is not None:
        out = Path(args.out)
        if out.is_dir() or not out.parent.is_dir():
            ap.error(f"argument --out: {args.out!r} must be a file in an existing directory")
    t0 = time.perf_counter()
    parts = []
    for e in envs:
        results: dict[str, dict[str, Any]] = {}
        for pol in [p for p in requested if p in available[e]]:
            results[pol] = {s: evaluate(e, pol, s, seeds, parsed[pol]) for s in scenario_names}
            print(f"note: {e} {pol} done ({time.perf_counter() - t0:.0f} s)", file=sys.stderr)
        parts.append(table(e, results, scenario_names))
    text = "\n".join(parts)
    text += (
        f"\nSeeds {seeds}; policies commissioned on the nominal plant; "
        f"{time.perf_counter() - t0:.0f} s in one process.\n"
    )
    print(text)
    if args.out is not None:
        Path(args.out).write_text(text)


if __name__ == "__main__":
    main()
