"""The leaderboard's results do not depend on the number of BLAS threads: a unit runs with
the thread pools of its process limited to one (agents/leaderboard/episodes.py run_unit)."""

from __future__ import annotations

import json
import os
import subprocess
import sys


def _returns(tmp_path, threads: int) -> dict:
    out = tmp_path / f"threads{threads}"
    env = {**os.environ, "OPENBLAS_NUM_THREADS": str(threads), "OMP_NUM_THREADS": str(threads)}
    subprocess.run(
        [
            sys.executable,
            "-m",
            "agents.leaderboard",
            "--envs",
            "steamtemp/BoilerTurbineMIMO-v0",
            "--policies",
            "mpc_evarx",
            "--scenarios",
            "load_ramp_100_50",
            "--seeds",
            "0",
            "--out",
            str(out),
        ],
        check=True,
        env=env,
        capture_output=True,
    )
    rows = [json.loads(line) for line in (out / "episodes.jsonl").read_text().splitlines()]
    return {r["scenario"]: r["metrics"]["return"] for r in rows if r["policy"] == "mpc_evarx"}


def test_one_and_two_blas_threads_give_the_same_returns_bit_for_bit(tmp_path):
    """mpc_evarx on BoilerTurbineMIMO's model-mismatch variants: with two BLAS threads its
    return on ``slow_firing_lag_sensor`` differed from one thread's in the ninth digit
    before units limited their thread pools."""
    one, two = _returns(tmp_path, 1), _returns(tmp_path, 2)
    assert "mismatch:slow_firing_lag_sensor" in one
    assert one == two
