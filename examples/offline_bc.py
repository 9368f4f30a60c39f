"""From an offline dataset to a leaderboard row: record mpc_linear on SupercriticalFSH's
training distribution in Minari's format, with noise injected into its actions (DART),
clone it with an MLP on the controller memory, score the clone.

Run from the project's root with the [offline] extra installed (docs/offline.md):

    python examples/offline_bc.py --data-dir minari_data --episodes 96

It writes the dataset ``steamtemp/SupercriticalFSH/mpc_linear-noisy5-v0`` (kept if it exists),
the agent's files in ``bc_agent/`` and the leaderboard run in ``bc_leaderboard/``.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from agents import behaviour_cloning, datasets
from agents.leaderboard import cli

ENV, POLICY = "SupercriticalFSH-v0", "mpc_linear"
NOISE = "0.05"  # of the valve stroke
DATASET = "steamtemp/SupercriticalFSH/mpc_linear-noisy5-v0"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data-dir", default="minari_data")
    ap.add_argument("--episodes", default="96")
    ap.add_argument("--seeds", default="0,1,2", help="the leaderboard's seeds")
    args = ap.parse_args()
    os.environ["MINARI_DATASETS_PATH"] = str(Path(args.data_dir).resolve())
    from minari.storage import get_dataset_path

    # 1. the dataset (python -m agents.datasets)
    if not Path(get_dataset_path(DATASET)).exists():
        datasets.main(["--env", ENV, "--policy", POLICY, "--episodes", args.episodes,
                       "--noise", NOISE, "--data-dir", args.data_dir])  # fmt: skip
    # 2. behaviour cloning, written as a trained agent's files (python -m agents.behaviour_cloning)
    behaviour_cloning.train(DATASET, "bc_agent", log=print)
    # 3. the leaderboard row: zoo:bc_agent next to the expert it cloned
    cli.main(["--policies", f"zoo:bc_agent,{POLICY}", "--envs", ENV,
              "--scenarios", datasets.EVAL_SCENARIO, "--seeds", args.seeds, "--no-mismatch",
              "--out", "bc_leaderboard"])  # fmt: skip


if __name__ == "__main__":
    main()
