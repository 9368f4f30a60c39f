"""The score's two ends as a leaderboard run gets them: the oracle's episodes replay the
stored optima (agents/optima.py), every plant, default scenario and seed of which is
stored for the current scenarios, and a run solves none of them; the score's 0 is run
(``cascade_pi_ff``, milliseconds an episode) and gives the return the store recorded for
it."""

from __future__ import annotations

import pytest

import steamtemp_gym
from agents import optima
from agents.leaderboard import cli
from agents.leaderboard.plan import DEFAULT_SCENARIOS, DEFAULT_SEEDS
from agents.leaderboard.records import EPISODES, read_record
from agents.leaderboard.summary import ONE, ZERO
from steamtemp_gym import scenarios

#: The sample run: the shortest default scenario.
SAMPLE = "setpoint_step"
#: The package's plants (a registered plant, such as the tests' toy, has no stored optima).
PLANTS = [e for e in steamtemp_gym.ENV_IDS if e.startswith("steamtemp/")]


@pytest.mark.parametrize("env_id", PLANTS)
def test_every_default_reference_episode_has_its_stored_optimum(env_id):
    """The store holds every default scenario and seed of the plant, for the scenario as it
    is now (its digest), with its actions file."""
    assert DEFAULT_SEEDS == "0-4"
    stored = optima.load()
    missing, stale = [], []
    for sc in DEFAULT_SCENARIOS:
        digest = optima.scenario_digest(scenarios.resolve(sc, env_id))
        for seed in range(5):
            r = stored.get((env_id, sc, seed))
            if r is None:
                missing.append((sc, seed))
            elif r["scenario_digest"] != digest or optima.actions(r) is None:
                stale.append((sc, seed))
    assert not missing and not stale, (
        f"{len(missing)} episodes not stored, {len(stale)} stored for another scenario or "
        f"without their actions: python -m agents.leaderboard.optima; {missing[:5]} {stale[:5]}"
    )


@pytest.mark.parametrize("env_id", PLANTS)
def test_a_run_replays_the_stored_optimum_and_reruns_the_zero(env_id, tmp_path, capsys):
    """One scenario of the plant, seeds 0 and 1: the oracle's rows are the stored returns,
    with nothing solved; ``cascade_pi_ff``'s are the returns the store recorded as the
    episode's 0."""
    out = tmp_path / "out"
    cli.main(
        [
            "--out",
            str(out),
            "--envs",
            env_id,
            "--policies",
            ZERO,
            "--scenarios",
            SAMPLE,
            "--seeds",
            "0,1",
            "--no-mismatch",
            "--jobs",
            "1",
        ]
    )
    assert "solving the clairvoyant optimum" not in capsys.readouterr().err
    stored = optima.load()
    rows = [r for r in read_record(out / EPISODES) if r["policy"] in (ZERO, ONE)]
    assert len(rows) == 4
    for r in rows:
        record = stored[env_id, SAMPLE, r["seed"]]
        want = record["return"] if r["policy"] == ONE else record["zero"]
        # bit for bit on the machine that stored them, to the replay tolerance on another
        assert optima.replays(r["metrics"]["return"], want), (r["policy"], r["seed"])
