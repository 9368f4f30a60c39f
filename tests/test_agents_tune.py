"""The hyperparameter search (agents/tune.py): trial entries, bad input, and (with Optuna
installed, the [zoo] extra) a two-trial search whose record names its best trial."""

from __future__ import annotations

import json

import pytest
import yaml

from agents import files, train_config, train_runs, tune

ENV_ID = "steamtemp/Cascade300MW-v0"


def test_trial_entry_maps_the_sampled_keys_onto_the_shipped_entry():
    base = {"gamma": 0.9, "policy_kwargs": {"net_arch": [8]}, "n_envs": 4}
    entry = tune.trial_entry(
        base, {"train_ratio": [1, 4], "log_std_init": -2.0, "net": [64, 64], "gamma": 0.99}
    )
    assert entry["train_freq"] == 1 and entry["gradient_steps"] == 4 and entry["gamma"] == 0.99
    assert entry["policy_kwargs"] == {"net_arch": [64, 64], "log_std_init": -2.0}
    assert base == {"gamma": 0.9, "policy_kwargs": {"net_arch": [8]}, "n_envs": 4}  # untouched


@pytest.mark.parametrize("algo", sorted(tune.SPACES))
def test_every_space_key_is_a_valid_hyperparameter(algo, tmp_path):
    """A trial built from the first choice of every key passes steamtemp-train's checks."""
    env_id = train_runs.zoo_entries_of(algo)[0]  # the first env its shipped YAML has
    raw = yaml.safe_load((train_config.HYPERPARAMS / f"{algo}.yml").read_text())[env_id]
    params = {k: v[0] for k, v in tune.SPACES[algo].items()}
    path = tmp_path / f"{algo}.yml"
    path.write_text(yaml.safe_dump({env_id: tune.trial_entry(raw, params)}))
    train_config.read_hyperparams(path, env_id, algo)


@pytest.mark.parametrize(
    ("argv", "match"),
    [
        (["--env", "steamtemp/Nope-v0", "--algo", "sac"], "--env must be one of"),
        (["--env", ENV_ID, "--algo", "ppo_residual"], "no search space"),
        (["--env", ENV_ID, "--algo", "sac", "--trials", "0"], "must be positive"),
    ],
)
def test_bad_input_is_an_argparse_error(argv, match, argparse_error):
    assert match in argparse_error(tune.main, argv)


def test_a_short_search_records_every_trial_and_the_best(tmp_path):
    pytest.importorskip("optuna")
    record = tune.search(
        ENV_ID, "ppo", trials=2, timesteps=2048, max_minutes=1.0, seed=0, out=tmp_path
    )
    saved = json.loads((tmp_path / f"{files.stem(ENV_ID, 'ppo')}__tuning.json").read_text())
    assert saved == json.loads(json.dumps(record))
    assert len(record["results"]) == 2
    assert record["best"]["return"] == max(r["return"] for r in record["results"])
    assert "| trial |" in tune.markdown(record)
