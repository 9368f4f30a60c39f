"""Hyperparameter search for the zoo: a seeded Optuna search over a small space per
algorithm, each trial a short ``agents.training.train`` run scored by its best validation
return (``random`` scenario, the validation seeds; never the leaderboard's scenarios).

    python -m agents.tune --env steamtemp/SupercriticalFSH-v0 --algo sac \\
        [--trials 8] [--timesteps 100000] [--max-minutes 2] [--seed 0] [--out tuning]

Each trial starts from the shipped YAML entry of the env (``agents/hyperparams/<algo>.yml``)
and overrides the sampled keys. The sampler is Optuna's TPE seeded with ``--seed``, its
first five trials random; every trial trains with the same ``--seed``, on one core, so a
rerun on the same machine gives the same table. Output in ``--out``:
``<env>__<algo>__tuning.json`` (every trial: parameters, validation return and IAE, wall
time; the best trial) and the same as a markdown table on stdout. The chosen values are
copied into the shipped YAML by hand, with the search recorded in docs/notes/agents_search.md.

Needs Optuna (``pip install optuna``; RL Zoo, extra ``[zoo]``, brings it).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path
from typing import Any

import yaml

import steamtemp_gym
from agents.files import stem
from agents.train_config import ALGOS, HYPERPARAMS, ConfigError, dict_string, read_hyperparams
from agents.training import checked_run, train

#: The search space per algorithm: key -> categorical choices. ``train_ratio`` is SAC/TD3's
#: (train_freq, gradient_steps) pair; ``log_std_init`` and ``net`` go to policy_kwargs.
SPACES: dict[str, dict[str, list[Any]]] = {
    "ppo": {
        "learning_rate": ["lin_3.0e-4", "lin_1.0e-3", 1.0e-4],
        "gamma": [0.98, 0.99, 0.995],
        "n_steps": [256, 512, 1024],
        "n_epochs": [5, 10],
        "gae_lambda": [0.9, 0.95],
        "log_std_init": [-3.0, -2.0, -1.0],
    },
    "sac": {
        "learning_rate": [1.0e-4, 3.0e-4, 1.0e-3],
        "gamma": [0.98, 0.99, 0.995],
        "batch_size": [256, 512],
        "train_ratio": [[4, 2], [1, 1], [1, 4]],
        "tau": [0.005, 0.02],
        "log_std_init": [-3.0, -2.0],
        "net": [[64, 64], [256, 256]],
    },
}
SPACES["td3"] = {k: v for k, v in SPACES["sac"].items() if k != "log_std_init"}
SPACES["td3"]["noise_std"] = [0.05, 0.1, 0.2]
#: CAPS's weights on the shipped SAC settings: 0.1 is smooth but slow, 1 a constant action
#: (docs/notes/agents_sac.md)
SPACES["sac_caps"] = {
    "caps_temporal": [0.003, 0.01, 0.03, 0.1],
    "caps_spatial": [0.003, 0.01, 0.03, 0.1],
}


def trial_entry(base: dict[str, Any], params: dict[str, Any]) -> dict[str, Any]:
    """The YAML entry of one trial: the shipped ``base`` entry with ``params`` applied."""
    entry = dict(base)
    kwargs = dict_string("policy_kwargs", entry.get("policy_kwargs") or {})
    for key, value in params.items():
        if key == "train_ratio":
            entry["train_freq"], entry["gradient_steps"] = value
        elif key == "log_std_init":
            kwargs["log_std_init"] = value
        elif key == "net":
            kwargs["net_arch"] = list(value)
        else:
            entry[key] = value
    entry["policy_kwargs"] = kwargs
    return entry


def search(
    env_id: str, algo: str, trials: int, timesteps: int, max_minutes: float, seed: int, out: Path
) -> dict[str, Any]:
    """Run the search (module docstring); returns the record written to ``out``."""
    if algo not in SPACES:
        raise ConfigError(f"no search space for {algo!r}; valid: {sorted(SPACES)}")
    if trials < 1 or timesteps < 1 or max_minutes <= 0:
        raise ConfigError("--trials, --timesteps and --max-minutes must be positive")
    try:
        import optuna
    except ImportError:
        raise ConfigError(
            "agents.tune needs optuna: pip install optuna (or the project's [zoo] extra)"
        ) from None
    shipped = HYPERPARAMS / f"{algo}.yml"
    read_hyperparams(shipped, env_id, algo)  # checked; the raw entry keeps its YAML forms
    raw = yaml.safe_load(shipped.read_text(encoding="utf-8"))[env_id]
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    records: list[dict[str, Any]] = []

    def objective(trial) -> float:
        params = {
            k: trial.suggest_categorical(k, [json.dumps(c) for c in v])
            for k, v in SPACES[algo].items()
        }
        params = {k: json.loads(v) for k, v in params.items()}
        with tempfile.TemporaryDirectory() as tmp:
            yml = Path(tmp) / f"{algo}.yml"
            yml.write_text(yaml.safe_dump({env_id: trial_entry(raw, params)}), encoding="utf-8")
            meta = train(
                checked_run(
                    env_id,
                    algo,
                    hyperparams=yml,
                    timesteps=timesteps,
                    seed=seed,
                    out=Path(tmp),
                    max_minutes=max_minutes,
                    quiet=True,
                )
            )
        best = meta["validation"]["best"]
        records.append(
            {
                "trial": trial.number,
                "params": params,
                **best,
                "timesteps_trained": meta["timesteps_trained"],
                "wall_time_s": meta["wall_time_s"],
            }
        )
        print(
            f"trial {trial.number}: return {best['return']:.1f}, IAE {best['iae_K_s']:.0f} "
            f"K*s, {meta['wall_time_s']:.0f} s, {params}",
            file=sys.stderr,
            flush=True,
        )
        return best["return"]

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    sampler = optuna.samplers.TPESampler(seed=seed, n_startup_trials=min(5, trials))
    study = optuna.create_study(direction="maximize", sampler=sampler)
    study.optimize(objective, n_trials=trials)
    record = {
        "env_id": env_id,
        "algo": algo,
        "trials": trials,
        "timesteps": timesteps,
        "max_minutes": max_minutes,
        "seed": seed,
        "space": SPACES[algo],
        "package_version": steamtemp_gym.__version__,
        "results": records,
        "best": max(records, key=lambda r: r["return"]),
    }
    (out / f"{stem(env_id, algo)}__tuning.json").write_text(
        json.dumps(record, indent=1), encoding="utf-8"
    )
    return record


def markdown(record: dict[str, Any]) -> str:
    keys = list(record["space"])
    lines = [
        "| trial | " + " | ".join(keys) + " | return | IAE (K·s) | steps | wall (s) |",
        "|" + "---|" * (len(keys) + 5),
    ]
    for r in sorted(record["results"], key=lambda r: -r["return"]):
        cells = [str(r["params"][k]) for k in keys]
        lines.append(
            f"| {r['trial']} | " + " | ".join(cells) + f" | {r['return']:.1f} | "
            f"{r['iae_K_s']:.0f} | {r['timesteps_trained']:,} | "
            f"{r['wall_time_s']:.0f} |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    doc = __doc__ or ""
    ap = argparse.ArgumentParser(
        prog="python -m agents.tune",
        description=doc.split("\n")[0],
        epilog=doc.split("\n", 2)[2],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ap.add_argument("--env", required=True, help=f"one of {list(steamtemp_gym.ENV_IDS)}")
    ap.add_argument("--algo", required=True, help=f"one of {sorted(SPACES)}")
    ap.add_argument("--trials", type=int, default=8)
    ap.add_argument("--timesteps", type=int, default=100_000)
    ap.add_argument("--max-minutes", type=float, default=2.0, help="per trial")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default="tuning")
    args = ap.parse_args(argv)
    if args.env not in steamtemp_gym.ENV_IDS or args.algo not in ALGOS:
        ap.error(
            f"--env must be one of {list(steamtemp_gym.ENV_IDS)} and --algo one of {sorted(SPACES)}"
        )
    try:
        record = search(
            args.env,
            args.algo,
            args.trials,
            args.timesteps,
            args.max_minutes,
            args.seed,
            Path(args.out),
        )
    except ConfigError as exc:
        ap.error(str(exc))
    print(markdown(record))
    return 0


if __name__ == "__main__":
    sys.exit(main())
