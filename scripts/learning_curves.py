"""Learning curves of the model-free agents, one figure per plant: each run's validation against the
decisions it trained on and against the CPU time it took, so that a reader sees whether
the budget or the method limits an agent.

    python scripts/learning_curves.py DIR [DIR ...] [--out docs/img] [--envs Benson,...]

Every run in the directories (``<env>__<algo>[__run<k>].json``, as steamtemp-train writes
them; agents/zoo/ and candidate directories alike) is read from its metadata: the
validation curve (the return on the 16 ``random`` validation episodes at every checkpoint,
with the decisions and the wall time of one core at that point) and the reference's
return on the same episodes. The curve is shown as the share of the reference's cost
(``cascade_pi_ff``'s negative return) a checkpoint removes, ``1 - R / R_ref``: 0 is the
reference, 1 a cost of zero; the kept checkpoint is marked. Runs of one algorithm and
directory share a colour. Output: ``<out>/learning_<plant>.png``.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import defaultdict
from pathlib import Path

import agents
from agents.files import parse_stem
from agents.leaderboard.plots import pyplot, save, short_env
from steamtemp_gym.envs import resolve_id

#: The chart's lowest share: an untrained policy's first checkpoints lie far below.
FLOOR = -1.0


def runs(directories: list[Path]) -> dict[str, list[dict]]:
    """Per env id, every run's (label, curve points, kept point, reference return)."""
    out: dict[str, list[dict]] = defaultdict(list)
    for d in directories:
        if not d.is_dir():
            raise ValueError(f"{d}: not a directory of trained agents")
        for f in sorted(d.glob("*.json")):
            try:
                env_id, algo, run = parse_stem(f.stem)
            except ValueError:
                continue
            if not agents.kind(algo).startswith("model-free"):
                continue
            meta = json.loads(f.read_text(encoding="utf-8"))
            val = meta.get("validation")
            if not val or not val.get("curve"):  # trained offline: no validation curve
                continue
            ref = val["reference"]["return"]
            # CPU minutes where recorded (a run's budget), else wall minutes (older runs)
            points = [
                (p["timesteps"], p.get("cpu_s", p["wall_s"]) / 60.0, 1.0 - p["return"] / ref)
                for p in val["curve"]
            ]
            kept = meta["timesteps_of_best"]
            out[env_id].append(
                {"label": f"{algo} ({d.name})", "run": run or 0, "points": points, "kept": kept}
            )
    return out


def figure(env_id: str, rows: list[dict], path: Path) -> None:
    """Write the figure of one plant."""
    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    labels = sorted({r["label"] for r in rows})
    colours = {lab: plt.cm.tab10(i % 10) for i, lab in enumerate(labels)}
    for r in rows:
        steps, minutes, share = zip(*r["points"], strict=True)
        for ax, x in zip(axes, (steps, minutes), strict=True):
            first = r["run"] == min(q["run"] for q in rows if q["label"] == r["label"])
            ax.plot(
                x,
                share,
                color=colours[r["label"]],
                lw=1.2,
                alpha=0.85,
                label=r["label"] if first and ax is axes[0] else None,
            )
            k = [i for i, s in enumerate(steps) if s == r["kept"]]
            if k:
                ax.plot(x[k[0]], share[k[0]], "o", color=colours[r["label"]], ms=5)
    top = max(s for r in rows for *_, s in r["points"])
    axes[0].set_ylim(FLOOR, max(0.2, top + 0.1))
    for ax in axes:
        ax.axhline(0.0, color="0.4", lw=0.8, ls="--")
        ax.grid(alpha=0.3)
    axes[0].set_xscale("log")
    axes[0].set_xlabel("decisions trained")
    axes[1].set_xlabel("minutes of one core")
    axes[0].set_ylabel("share of cascade_pi_ff's cost removed\n(16 validation episodes)")
    axes[0].legend(fontsize=8, loc="lower right")
    fig.suptitle(
        f"{short_env(env_id)}: validation while training (dot: the kept checkpoint; dashed: "
        f"the reference; below {FLOOR:g}: off the chart)",
        fontsize=10,
    )
    fig.tight_layout()
    save(fig, path)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("dirs", nargs="+", type=Path, help="directories of trained agents")
    ap.add_argument("--out", type=Path, default=Path("docs/img"))
    ap.add_argument("--envs", default=None, help="plants, comma-separated (default: all found)")
    args = ap.parse_args(argv)
    try:
        found = runs(args.dirs)
        wanted = None if args.envs is None else {resolve_id(e) for e in args.envs.split(",")}
    except ValueError as exc:
        ap.error(str(exc))
    for env_id, rows in sorted(found.items()):
        if wanted is None or env_id in wanted:
            path = args.out / f"learning_{env_id.split('/')[-1]}.png"
            figure(env_id, rows, path)
            print(path, file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
