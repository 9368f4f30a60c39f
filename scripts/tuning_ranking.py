"""Whether the stored tunings' choices hold under the current score ends.

A stored tuning (baselines/tuned/<name>.json) chose the best of the candidates its search
judged in full (commissioning and robustness checks run) by their mean normalized score
on the training episodes, against the score ends of its time. When the ends change (a new
score's 1), the choice may change too: this runs every candidate the search judged
feasible on the training episodes again, scores it against the current ends
(``agents.tuning_terms.ends``) and reports, per controller and plant, whether the stored
choice is still the best of them (feasibility does not depend on the ends: trips, valve
travel and the checks are the policy's own).

    python scripts/tuning_ranking.py [--names mpc_linear,lqi] [--envs ...] [--out FILE]

Results are appended to ``--out`` (JSON lines, one per candidate) as they come, and a
rerun skips what is there; the table is printed at the end.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import baselines
from agents.baseline_tuning import TUNABLE, evaluate
from agents.tuning_terms import ROBUST_COST_MAX, TUNING_TRAVEL_BUDGET, ends
from baselines import tuning


def judged_feasible(plant: dict) -> list[dict]:
    """The history rows the search judged in full and found feasible."""
    def kept(r: dict) -> bool:
        robust = r.get("robust_ratio")
        return (r.get("check") == "" and r["trips"] == 0 and not r.get("robust_breach")
                and r["travel_ratio"] <= TUNING_TRAVEL_BUDGET
                and (robust is None or robust <= ROBUST_COST_MAX))  # fmt: skip

    return [r for r in plant["history"] if kept(r)]


def _key(name: str, env_id: str, knobs: dict) -> str:
    return json.dumps([name, env_id, knobs], sort_keys=True)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--names", default=",".join(TUNABLE), help="controllers (default: all)")
    ap.add_argument("--envs", default=None, help="env ids (default: each tuning's plants)")
    ap.add_argument("--out", default="tuning_ranking.jsonl", help="results file (resumable)")
    args = ap.parse_args(argv)
    out = Path(args.out)
    done = {}
    if out.is_file():
        for line in out.read_text().splitlines():
            r = json.loads(line)
            done[_key(r["name"], r["env"], r["knobs"])] = r
    table = []
    for name in [n.strip() for n in args.names.split(",") if n.strip()]:
        if name not in baselines.NAMES:
            ap.error(f"argument --names: unknown controller {name!r}")
        stored = json.loads(tuning.path(name).read_text())
        for env_id, plant in stored["plants"].items():
            if args.envs and env_id.split("/")[-1] not in args.envs and env_id not in args.envs:
                continue
            e = ends(env_id, compute=False)
            rows = []
            for cand in judged_feasible(plant):
                k = _key(name, env_id, cand["knobs"])
                if k not in done:
                    res = evaluate(name, env_id, cand["knobs"], e)
                    done[k] = {"name": name, "env": env_id, "knobs": cand["knobs"],
                               "old_score": cand["score"], "new_score": res.score,
                               "travel_ratio": res.travel_ratio, "trips": res.trips}  # fmt: skip
                    with out.open("a") as f:
                        f.write(json.dumps(done[k]) + "\n")
                rows.append(done[k])
            if not rows:
                table.append((name, env_id, 0, "-", "-", "-"))
                continue
            new_best = max(rows, key=lambda r: r["new_score"])
            chosen = next((r for r in rows if r["knobs"] == plant["knobs"]), None)
            if chosen is None:  # no candidate kept every term: the least bad was stored
                table.append((name, env_id, len(rows), "-", "-", "no feasible choice"))
                continue
            same = new_best["knobs"] == plant["knobs"]
            table.append((name, env_id, len(rows), f"{chosen['old_score']:.3f}",
                          f"{chosen['new_score']:.3f}",
                          "kept" if same else f"changes: {new_best['new_score']:.3f} by "
                          f"{new_best['knobs']}"))  # fmt: skip
            print(" | ".join(str(c) for c in table[-1]), file=sys.stderr, flush=True)
    print("| controller | plant | feasible candidates | chosen, old ends | chosen, new ends "
          "| choice |")
    print("|---|---|---|---|---|---|")
    for row in table:
        print("| " + " | ".join([row[0], row[1].split("/")[-1], *map(str, row[2:])]) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
