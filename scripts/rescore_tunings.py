"""Rescore the stored tunings against the current score ends, and say whether their choices
hold.

A stored tuning (baselines/tuned/<name>.json) records every candidate its search evaluated
with its mean normalized score on the training episodes against the score ends of its
time (baselines/tuned/ends.json). When the ends change (a new score's 1), those scores
change, and with them, perhaps, the search's path and its choice. This evaluates every
recorded candidate again on the training episodes against the current ends
(``agents.tuning_terms.ends``), checks that its valve travel and trips are the recorded
ones (to 1e-6: the dynamics did not move), and reports per controller and plant the chosen
candidate's score before and after and whether it is still the best of the candidates the
search judged feasible. Feasibility does not depend on the ends: trips, valve travel and
the checks are the policy's own.

    python scripts/rescore_tunings.py [--names cascade_pi,lqi] [--envs Cascade300MW-v0]
    python scripts/rescore_tunings.py --apply     # write the new scores into the files

Results are appended to ``--out`` (JSON lines, one per candidate) as they come and a
rerun skips what is there. ``--apply`` writes the new scores into the stored tunings
(every history row, the result and its start); tests/test_baseline_tuning.py then replays
each search on them: where the search under the new scores leaves the stored path, that
tuning must be searched again (``python -m agents.baseline_tuning --name N --env E``).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import baselines
from agents.baseline_tuning import TUNABLE, evaluate
from agents.tuning_terms import ROBUST_COST_MAX, TUNING_TRAVEL_BUDGET, ends
from baselines import tuning

#: The results, kept with the script so that a rescoring spread over days resumes.
OUT = Path(__file__).with_name("data") / "rescored_tunings.jsonl"


def judged_feasible(plant: dict) -> list[dict]:
    """The history rows the search judged in full and found feasible."""

    def kept(r: dict) -> bool:
        robust = r.get("robust_ratio")
        return (
            r.get("check") == ""
            and r["trips"] == 0
            and not r.get("robust_breach")
            and r["travel_ratio"] <= TUNING_TRAVEL_BUDGET
            and (robust is None or robust <= ROBUST_COST_MAX)
        )

    return [r for r in plant["history"] if kept(r)]


def _key(name: str, env_id: str, knobs: dict) -> str:
    return json.dumps([name, env_id, knobs], sort_keys=True)


def _selected(ap: argparse.ArgumentParser, args: argparse.Namespace) -> list[tuple[str, str]]:
    names = [n.strip() for n in args.names.split(",") if n.strip()]
    unknown = [n for n in names if n not in baselines.NAMES or not tuning.path(n).is_file()]
    if unknown:
        ap.error(f"argument --names: no stored tuning of {unknown}")
    envs = None if args.envs is None else {e.split("/")[-1] for e in args.envs.split(",")}
    pairs = []
    for name in names:
        for env_id in json.loads(tuning.path(name).read_text())["plants"]:
            if envs is None or env_id.split("/")[-1] in envs:
                pairs.append((name, env_id))
    return pairs


def rescore(pairs: list[tuple[str, str]], out: Path) -> dict[str, dict]:
    """Every recorded candidate of ``pairs`` against the current ends, appended to ``out``."""
    done: dict[str, dict] = {}
    if out.is_file():
        for line in out.read_text().splitlines():
            r = json.loads(line)
            done[_key(r["name"], r["env"], r["knobs"])] = r
    for name, env_id in pairs:
        plant = json.loads(tuning.path(name).read_text())["plants"][env_id]
        e = ends(env_id, compute=False)
        for row in plant["history"]:
            k = _key(name, env_id, row["knobs"])
            if k in done:
                continue
            res = evaluate(name, env_id, row["knobs"], e)
            # the commissioning's solvers may move the last digits across library versions
            moved = not math.isclose(res.travel_ratio, row["travel_ratio"], rel_tol=1e-6)
            if moved or res.trips != row["trips"]:
                raise RuntimeError(
                    f"{name} on {env_id} with {row['knobs']}: travel "
                    f"{res.travel_ratio!r} and trips {res.trips} now, "
                    f"{row['travel_ratio']!r} and {row['trips']} recorded: the "
                    "dynamics moved; search again"
                )
            done[k] = {
                "name": name,
                "env": env_id,
                "knobs": row["knobs"],
                "old_score": row["score"],
                "new_score": res.score,
            }
            with out.open("a") as f:
                f.write(json.dumps(done[k]) + "\n")
        print(
            f"{name} {env_id.split('/')[-1]}: {len(plant['history'])} rescored",
            file=sys.stderr,
            flush=True,
        )
    return done


def table(pairs: list[tuple[str, str]], done: dict[str, dict]) -> list[str]:
    lines = [
        "| controller | plant | feasible candidates | chosen: score, old ends -> new "
        "| best feasible under the new ends |",
        "|---|---|---|---|---|",
    ]
    for name, env_id in pairs:
        plant = json.loads(tuning.path(name).read_text())["plants"][env_id]
        rows = [done[_key(name, env_id, r["knobs"])] for r in judged_feasible(plant)]
        chosen = done[_key(name, env_id, plant["knobs"])]
        cell = f"{chosen['old_score']:.3f} -> {chosen['new_score']:.3f}"
        if not plant["feasible"] or not rows:
            best = "no feasible candidate (the least bad stored)"
        else:
            top = max(rows, key=lambda r: r["new_score"])
            best = (
                "the chosen"
                if top["knobs"] == plant["knobs"]
                else (f"another: {top['new_score']:.3f} by {top['knobs']}")
            )
        lines.append(f"| `{name}` | {env_id.split('/')[-1]} | {len(rows)} | {cell} | {best} |")
    return lines


def apply(pairs: list[tuple[str, str]], done: dict[str, dict]) -> None:
    """Write the new scores into the stored tunings (history, result and start)."""
    for name in dict.fromkeys(n for n, _ in pairs):
        f = tuning.path(name)
        data = json.loads(f.read_text())
        for env_id, plant in data["plants"].items():
            if (name, env_id) not in pairs:
                continue
            for row in plant["history"]:
                row["score"] = done[_key(name, env_id, row["knobs"])]["new_score"]
            plant["score"] = done[_key(name, env_id, plant["knobs"])]["new_score"]
            plant["start"]["score"] = done[_key(name, env_id, plant["start"]["knobs"])]["new_score"]
        f.write_text(json.dumps(data, indent=1, sort_keys=True) + "\n")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--names", default=",".join(TUNABLE), help="controllers (default: all)")
    ap.add_argument("--envs", default=None, help="plants, comma-separated (default: all)")
    ap.add_argument("--out", type=Path, default=OUT, help="results (default: %(default)s)")
    ap.add_argument("--apply", action="store_true", help="write the new scores into the files")
    args = ap.parse_args(argv)
    pairs = _selected(ap, args)
    done = rescore(pairs, args.out)
    print("\n".join(table(pairs, done)))
    if args.apply:
        apply(pairs, done)
    return 0


if __name__ == "__main__":
    sys.exit(main())
