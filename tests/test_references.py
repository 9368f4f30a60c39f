"""The stored reference episodes (agents/leaderboard/references.py): every plant, default
scenario and seed of both ends is stored for the current code, a sample recomputed gives
the stored metrics bit for bit, and the leaderboard takes them instead of running them
(and runs them where the code changed)."""

from __future__ import annotations

import json

import pytest

import steamtemp_gym
from agents.leaderboard import cli, references
from agents.leaderboard.plan import DEFAULT_SCENARIOS, DEFAULT_SEEDS
from agents.leaderboard.records import EPISODES, read_record

#: The sample recomputed: the shortest default scenario, on every plant, the first seed.
SAMPLE = "setpoint_step"


def _plan(tmp_path, *args: str):
    ap = cli.make_parser()
    a = ap.parse_args(["--out", str(tmp_path / "out"), *args])
    return cli.build_plan(ap, a)


@pytest.fixture(scope="module")
def stored():
    rows = references.load()
    if not rows:
        pytest.skip(f"no stored reference episodes in {references.ROWS}; make them with "
                    "steamtemp-leaderboard and python -m agents.leaderboard.references --from OUT")
    return rows


def _skip_unstored(stored, env_id: str) -> None:
    if not any(key[0][0] == env_id for key in stored):
        pytest.skip(f"no stored reference episodes of {env_id}; make them with "
                    f"steamtemp-leaderboard --envs {env_id} --recompute-references --out OUT "
                    "and python -m agents.leaderboard.references --from OUT")  # fmt: skip


@pytest.mark.parametrize("env_id", steamtemp_gym.ENV_IDS)
def test_every_default_reference_episode_is_stored_for_the_current_code(stored, tmp_path,
                                                                        env_id):  # fmt: skip
    _skip_unstored(stored, env_id)
    plan = _plan(tmp_path, "--envs", env_id, "--policies", "cascade_pi_ff", "--no-mismatch")
    rows, stale = references.matching(plan, stored)
    n = len(DEFAULT_SCENARIOS) * 5 * len(references.POLICIES)
    assert DEFAULT_SEEDS == "0-4"
    assert stale == 0, (f"{stale} reference episodes are not stored for the current code: "
                        "regenerate them (agents/leaderboard/references.py)")  # fmt: skip
    assert len(rows) == n


@pytest.mark.parametrize("env_id", steamtemp_gym.ENV_IDS)
def test_a_recomputed_sample_gives_the_stored_metrics_bit_for_bit(stored, tmp_path, capsys,
                                                                  env_id):  # fmt: skip
    """One scenario of the plant, both ends, seed 0, run with --recompute-references: each
    row's metrics are the stored row's exactly."""
    _skip_unstored(stored, env_id)
    out = tmp_path / "out"
    cli.main(["--out", str(out), "--envs", env_id, "--policies", "cascade_pi_ff", "--scenarios",
              SAMPLE, "--seeds", "0", "--no-mismatch", "--recompute-references",
              "--jobs", "1"])  # fmt: skip
    ran = [r for r in read_record(out / EPISODES) if r["policy"] in references.POLICIES]
    assert len(ran) == len(references.POLICIES)
    for r in ran:
        key = ((r["env"], r["scenario"], r["policy"], r["seed"]), r["fingerprint"])
        assert key in stored, f"{key} not stored"
        assert json.dumps(r["metrics"], sort_keys=True) == json.dumps(
            stored[key]["metrics"], sort_keys=True), key  # fmt: skip
    assert "taken from the stored references" not in capsys.readouterr().err


def test_the_leaderboard_takes_stored_episodes_and_runs_what_is_not_stored(
    stored, tmp_path, capsys, monkeypatch
):
    """With the stored references, a run of one cheap policy runs no oracle episode of
    the default seeds; a reference episode whose stored row is missing runs."""
    some = dict(stored)
    dropped = next(k for k in some if k[0][1] == SAMPLE and k[0][2] == "oracle"
                   and k[0][0] == "steamtemp/Cascade300MW-v0" and k[0][3] == 0)  # fmt: skip
    del some[dropped]
    monkeypatch.setattr(references, "load", lambda path=references.ROWS: some)
    out = tmp_path / "out"
    cli.main(["--out", str(out), "--envs", "Cascade300MW-v0", "--policies", "cascade_pi_ff",
              "--scenarios", SAMPLE, "--seeds", "0,1", "--no-mismatch", "--jobs", "1"])  # fmt: skip
    err = capsys.readouterr().err
    assert "3 episodes of cascade_pi_ff and oracle taken from the stored references" in err
    assert "1 run now" in err
    rows = read_record(out / EPISODES)
    oracle = sorted(r["seed"] for r in rows if r["policy"] == "oracle")
    assert oracle == [0, 1]  # both in the record: one stored, one run now
    doc = json.loads((out / "leaderboard.json").read_text())
    assert doc["plants"]["steamtemp/Cascade300MW-v0"]["policies"]["cascade_pi_ff"]
