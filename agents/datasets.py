"""Offline RL datasets in Minari's format: episodes of a policy on a plant's ``random``
training distribution, with the leaderboard's score ends as the reference scores.

``python -m agents.datasets --env SupercriticalFSH-v0 --policy mpc_linear --episodes 20``
records 20 episodes (seeds ``--seed`` .. ``--seed + 19``) of the policy with
``minari.DataCollector`` (every info key recorded, the safe-RL ``cost`` among them) and
creates the dataset ``steamtemp/SupercriticalFSH/mpc_linear-v0`` in Minari's data folder
(``--data-dir``, else ``MINARI_DATASETS_PATH``, else ``~/.minari/datasets``). Minari reads
a dataset id as ``(namespace/)name(-v<version>)``: the namespace here is
``steamtemp/<Plant>``, the name the policy's (characters other than letters, digits, ``_``
and ``-`` written ``-``: ``sb3:ppo`` -> ``sb3-ppo``) or ``--name``.

The policy is any name ``steamtemp-leaderboard --policies`` takes (agents/specs.py).
``--mixed F`` makes a mixed-quality dataset for offline RL, ``<name>-mixed-v0``: each
episode is, with probability F, ``cascade_pi`` at a tuning drawn from the search box of
its knobs (``CascadePI.KNOBS``: every gain and integral time factor log-uniform in
0.25-4, so from sluggish to oscillating), else the policy.

``--noise S`` injects noise into the policy's actions, as DART does (Laskey, Lee, Fox,
Dragan and Goldberg, "DART: noise injection for robust imitation learning", CoRL 2017):
per valve a first-order low-pass Gaussian noise of standard deviation S (a fraction of the
stroke) and time constant :data:`NOISE_FACTOR` times the plant's time scale (dead time +
lag, agents/horizons.py), added to the policy's action and clipped to the valve's range.
The env gets the noisy action and the dataset records it as the action (the transitions
are the plant's); each step's info ``policy_action`` holds what the policy chose before
the noise, the label behaviour cloning learns from (agents/behaviour_cloning.py). So the
data visit the states around the expert's path a clone drifts into, labelled with what the
expert does there; the name gets ``-noisy`` and the noise in percent of the stroke
(``--noise 0.05``: ``mpc_linear-noisy5``).

Reference scores: the dataset's evaluation env is the plant under a named scenario
(``--eval-scenario``, default ``load_ramp_100_50``); ``ref_min_score`` and
``ref_max_score`` are the mean returns of ``cascade_pi_ff`` and the oracle there over
``--eval-seeds`` (default the leaderboard's 0-4), the episodes the leaderboard runs (the
oracle's replayed from the stored optima, agents/optima.py). So
``minari.get_normalized_score(dataset, returns)`` is the leaderboard's normalized score of
those episodes on that scenario wherever the oracle's margin is at least
``agents.stats.MIN_SPAN`` of the reference's cost (docs/offline.md).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import baselines
import steamtemp_gym
from agents import horizons, specs
from agents.evaluation import run_episode
from agents.exploration import low_pass
from agents.files import git_revision
from agents.leaderboard.episodes import score_ends
from baselines.cascade_pi import CascadePI
from steamtemp_gym import envs as envs_
from steamtemp_gym import scenarios

#: Every dataset's namespace starts with this (then the plant's name).
NAMESPACE = "steamtemp"
#: The evaluation env's default scenario: the load-ramp test of Sagara et al. 1998.
EVAL_SCENARIO = "load_ramp_100_50"
#: The leaderboard's default seeds, over which the reference scores are means.
EVAL_SEEDS = (0, 1, 2, 3, 4)
#: The detuned controller of a mixed dataset.
DETUNED = "cascade_pi"
AUTHOR = "steamtemp_gym contributors"
MAX_EPISODES = 100_000
#: The injected noise's time constant as a fraction of the plant's time scale (dead time +
#: lag, ``agents.horizons.time_scale``): 29 s on SupercriticalFSH.
NOISE_FACTOR = 0.125
#: The largest noise (standard deviation, fraction of the valve stroke) ``--noise`` takes.
MAX_NOISE = 0.5
#: The info key of the policy's own action in a dataset with injected noise.
POLICY_ACTION = "policy_action"
_NOT_NAME = re.compile(r"[^A-Za-z0-9_-]+")


def plant_name(env_id: str) -> str:
    """``steamtemp/SupercriticalFSH-v0`` -> ``SupercriticalFSH``."""
    return gym.spec(env_id).name


def dataset_name(policy: str, mixed: float | None = None, noise: float | None = None) -> str:
    """The dataset name of a policy: its name with every run of characters Minari refuses
    in a name written ``-`` (``sb3:ppo`` -> ``sb3-ppo``), ``-mixed`` appended for a mixed
    dataset and ``-noisy<percent of the stroke>`` for one with injected noise
    (``-noisy5``)."""
    name = _NOT_NAME.sub("-", policy).strip("-") or "policy"
    name += ("-mixed" if mixed else "") + (f"-noisy{100 * noise:g}" if noise else "")
    return _NOT_NAME.sub("-", name)


def dataset_id(env_id: str, name: str, version: int = 0) -> str:
    """``steamtemp/<Plant>/<name>-v<version>``."""
    return f"{NAMESPACE}/{plant_name(env_id)}/{name}-v{version}"


def reference_scores(
    env_id: str, scenario: str = EVAL_SCENARIO, seeds: tuple[int, ...] = EVAL_SEEDS
) -> tuple[float, float]:
    """(ref_min_score, ref_max_score): the leaderboard's ``zero_return`` and ``one_return``
    on ``env_id``'s ``scenario`` over ``seeds`` (agents/leaderboard/episodes.py:
    ``score_ends``)."""
    return score_ends(env_id, scenario, seeds)


def detuned_knobs(rng: np.random.Generator) -> dict[str, float]:
    """A tuning of :data:`DETUNED` drawn from its knobs' search box (log-uniform)."""
    out = {}
    for k in CascadePI.KNOBS:
        out[k.name] = float(
            np.exp(rng.uniform(np.log(k.lo), np.log(k.hi))) if k.log else rng.uniform(k.lo, k.hi)
        )
    return out


def episode_plan(
    policy: str, episodes: int, seed: int, mixed: float | None = None
) -> list[dict[str, Any]]:
    """Per episode its seed, policy and (for a detuned one) knobs; the draws of a mixed
    dataset come from ``seed``, so the same flags give the same dataset."""
    rng = np.random.default_rng([seed, 0x5EED])
    out = []
    for i in range(episodes):
        if mixed and rng.uniform() < mixed:
            out.append({"seed": seed + i, "policy": DETUNED, "knobs": detuned_knobs(rng)})
        else:
            out.append({"seed": seed + i, "policy": policy})
    return out


class PolicyActionInfo(gym.Wrapper):
    """Puts the action the dataset's policy chose (``chosen``, set before each step) in the
    step's info as :data:`POLICY_ACTION`; NaN in a reset's info (no action yet)."""

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        self.chosen: np.ndarray | None = None

    def reset(self, **kwargs: Any):
        obs, info = self.env.reset(**kwargs)
        self.chosen = None
        return obs, {**info, POLICY_ACTION: np.full(self.action_space.shape, np.nan)}

    def step(self, action: Any):
        if self.chosen is None:
            raise ValueError("PolicyActionInfo.step: no chosen action set for this step")
        chosen, self.chosen = self.chosen, None
        obs, reward, terminated, truncated, info = self.env.step(action)
        return obs, reward, terminated, truncated, {**info, POLICY_ACTION: chosen}


class NoisyPolicy:
    """A policy's actions plus low-pass Gaussian noise (``--noise``, module docstring).

    Args:
        policy: The policy (agents.specs' ``make``).
        label: The :class:`PolicyActionInfo` under the collector, told each chosen action.
        sigma: The noise's standard deviation, a fraction of the valve stroke.
        tau_s: Its time constant (s).
        dt_s: The control interval (s).
    """

    def __init__(
        self, policy: Any, label: PolicyActionInfo, sigma: float, tau_s: float, dt_s: float
    ) -> None:
        self.policy, self.label = policy, label
        self.scale = 2.0 * sigma  # actions span the stroke as [-1, 1]
        self.a = float(np.exp(-dt_s / tau_s))
        self.rng = np.random.default_rng(0)
        self.noise: np.ndarray | None = None

    def seed(self, seed: int) -> None:
        """Draw the next episode's noise from ``seed`` (the episode's seed)."""
        self.rng = np.random.default_rng([seed, 0xDA27])

    def reset(self) -> None:
        self.policy.reset()
        self.noise = None

    def predict(
        self,
        observation: Any,
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]:
        action, state = self.policy.predict(observation, state, episode_start, deterministic)
        action = np.asarray(action, dtype=np.float64)
        white = self.rng.standard_normal(action.shape) * self.scale
        if self.noise is None or np.any(episode_start):  # from the stationary distribution
            self.noise = white
        else:
            self.noise = low_pass(self.noise, self.a, white)
        noisy = np.clip(action + self.noise, -1.0, 1.0)
        self.label.chosen = action.copy()
        if hasattr(self.policy, "applied"):  # its estimator follows the command applied
            self.policy.applied(noisy)
        return noisy.astype(np.float32), state


def record(
    env_id: str,
    policy: str,
    episodes: int,
    seed: int = 0,
    *,
    mixed: float | None = None,
    noise: float | None = None,
    name: str | None = None,
    version: int = 0,
    eval_scenario: str = EVAL_SCENARIO,
    eval_seeds: tuple[int, ...] = EVAL_SEEDS,
    author: str = AUTHOR,
    code_permalink: str | None = None,
    log: Any = None,
) -> Any:
    """Record the episodes and create the dataset (module docstring) in Minari's data
    folder (``MINARI_DATASETS_PATH``); returns the ``MinariDataset``.

    Raises:
        ValueError: an unknown env, policy or scenario, a bad count, seed or fraction, or a
            dataset id that exists already; nothing is written then.
    """
    import minari
    from minari.storage import get_dataset_path

    env_id = envs_.resolve_id(env_id)
    spec = _check_arguments(env_id, policy, episodes, seed, mixed, noise, eval_scenario)
    did = dataset_id(env_id, name or dataset_name(policy, mixed, noise), version)
    minari.dataset.minari_dataset.parse_dataset_id(did)  # Minari's own rules
    if Path(get_dataset_path(did)).exists():
        raise ValueError(
            f"dataset {did} exists already in {get_dataset_path(did)}; delete "
            "it (minari delete) or give another --version or --name"
        )
    say = log or (lambda msg: None)
    t0 = time.perf_counter()
    lo, hi = reference_scores(env_id, eval_scenario, tuple(eval_seeds))
    say(
        f"reference scores on {eval_scenario}, seeds {list(eval_seeds)}: cascade_pi_ff "
        f"{lo:.6g}, oracle {hi:.6g} ({time.perf_counter() - t0:.1f} s)"
    )
    t1 = time.perf_counter()
    plan = episode_plan(policy, episodes, seed, mixed)
    plant_env = gym.make(env_id, scenario=scenarios.RANDOM)
    label = PolicyActionInfo(plant_env) if noise else None
    env = minari.DataCollector(label or plant_env, record_infos=True)
    tau_s = NOISE_FACTOR * sum(horizons.time_scale(env_id)) if noise else None
    _run_plan(env, env_id, plan, policy, spec, label, noise, tau_s)
    what = policy + (f" mixed {mixed:g}" if mixed else "") + (f" noise {noise:g}" if noise else "")
    say(
        f"{episodes} episodes of {what} on {env_id} random, seeds {seed}-{seed + episodes - 1}: "
        f"{time.perf_counter() - t1:.1f} s"
    )
    eval_env = gym.make(env_id, scenario=eval_scenario)
    description = _description(
        env_id, policy, episodes, seed, mixed, noise, tau_s, eval_scenario, eval_seeds
    )
    with warnings.catch_warnings():  # the one field left out: no e-mail address
        warnings.filterwarnings("ignore", message="`author_email` is set to None")
        dataset = env.create_dataset(
            dataset_id=did,
            eval_env=eval_env,
            algorithm_name=policy,
            author=author,
            code_permalink=code_permalink or _permalink(),
            ref_min_score=lo,
            ref_max_score=hi,
            num_episodes_average_score=len(eval_seeds),
            description=description,
            requirements=[f"steamtemp-gym=={steamtemp_gym.__version__}"],
        )
    dataset.storage.update_metadata({"steamtemp_episodes": json.dumps(plan)})
    env.close()
    return dataset


def _run_plan(
    env: Any,
    env_id: str,
    plan: list[dict[str, Any]],
    policy: str,
    spec: Any,
    label: PolicyActionInfo | None,
    noise: float | None,
    tau_s: float | None,
) -> None:
    """Run the episodes of ``plan`` in the collecting ``env``, each by the detuned controller
    at its knobs or else by ``policy`` (built once), with the action noise on top where
    ``label`` takes the chosen actions; each entry of ``plan`` gets its episode's return
    (and the noise's parameters)."""
    built: dict[str, Any] = {}
    for ep in plan:
        if "knobs" in ep:
            pol = baselines.make(DETUNED, env.unwrapped, **ep["knobs"])
        else:
            if policy not in built:
                built[policy] = spec.make(env_id, env.unwrapped)
            pol = built[policy]
        if label is not None:
            pol = NoisyPolicy(pol, label, noise, tau_s, env.unwrapped.plant.dt_s)
            pol.seed(ep["seed"])
            ep["noise"] = {"sigma": noise, "tau_s": tau_s}
        ep["return"] = _episode(env, pol, ep["seed"])


def _description(
    env_id: str,
    policy: str,
    episodes: int,
    seed: int,
    mixed: float | None,
    noise: float | None,
    tau_s: float | None,
    eval_scenario: str,
    eval_seeds: tuple[int, ...],
) -> str:
    """The dataset's description: who acted in which episodes, the detuned share and the
    action noise if any, the infos recorded and the evaluation env with its score ends."""
    text = (
        f"{episodes} episodes of {policy} on {env_id}, scenario 'random' (the training "
        f"distribution, a fresh draw per episode), seeds {seed}..{seed + episodes - 1}"
    )
    if mixed:
        text += (
            f"; each episode with probability {mixed:g} by {DETUNED} at a tuning drawn "
            "log-uniform from its knobs' box (factors 0.25-4 on every gain and integral "
            "time) instead: the steamtemp_episodes metadata names each"
        )
    if noise:
        text += (
            f"; low-pass Gaussian noise of standard deviation {noise:g} of the stroke and "
            f"time constant {tau_s:.1f} s added to every action (DART); the info "
            f"'{POLICY_ACTION}' holds the policy's action before it"
        )
    return text + (
        f". Infos recorded (cost: the safe-RL constraint cost). eval_env: {env_id} "
        f"under '{eval_scenario}'; ref_min_score / ref_max_score: the mean returns of "
        f"cascade_pi_ff and the oracle there over seeds {list(eval_seeds)}, the "
        "leaderboard's score ends (0 and 1). steamtemp_gym "
        f"{steamtemp_gym.__version__}, python -m agents.datasets."
    )


def _check_arguments(
    env_id: str, policy: str, episodes: Any, seed: Any, mixed: Any, noise: Any, eval_scenario: str
) -> Any:
    """ValueError for a bad count, seed, fraction, policy or evaluation scenario of
    :func:`record`; else the policy's spec (agents/specs.py)."""
    if (
        isinstance(episodes, bool)
        or not isinstance(episodes, int)
        or not (1 <= episodes <= MAX_EPISODES)
    ):
        raise ValueError(f"episodes must be an integer in 1..{MAX_EPISODES}, got {episodes!r}")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ValueError(f"seed must be an integer >= 0, got {seed!r}")
    if mixed is not None and not (isinstance(mixed, float | int) and 0.0 < mixed <= 1.0):
        raise ValueError(f"mixed must be a fraction in (0, 1], got {mixed!r}")
    if noise is not None and not (
        isinstance(noise, float | int) and not isinstance(noise, bool) and 0.0 < noise <= MAX_NOISE
    ):
        raise ValueError(
            f"noise must be a fraction of the stroke in (0, {MAX_NOISE}], got {noise!r}"
        )
    spec = specs.parse(policy)
    if not spec.available(env_id):
        raise ValueError(f"policy {policy!r} has no agent for {env_id}")
    scenarios.resolve(eval_scenario, env_id)  # a bad name fails before anything runs
    if eval_scenario == scenarios.RANDOM:
        raise ValueError("the evaluation scenario must be a fixed one, not 'random'")
    return spec


def _episode(env: Any, policy: Any, seed: int) -> float:
    """One episode through the collector, run as the leaderboard runs it; its return."""
    return float(run_episode(env, policy, seed)["metrics"]["return"])


def _permalink() -> str:
    return f"steamtemp_gym {steamtemp_gym.__version__}, git {git_revision()}: agents/datasets.py"


def _int(lo: int, hi: int, what: str):
    def parse(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{what} must be an integer, got {text!r}") from None
        if not lo <= v <= hi:
            raise argparse.ArgumentTypeError(f"{what} must be in {lo}..{hi}, got {v}")
        return v

    return parse


def _share(hi: float, what: str):
    """An argparse type: a float in (0, ``hi``], else an error describing it as ``what``."""

    def parse(text: str) -> float:
        try:
            v = float(text)
        except ValueError:
            v = np.nan
        if not 0.0 < v <= hi:  # False for NaN too
            raise argparse.ArgumentTypeError(f"{what} in (0, {hi:g}], got {text!r}")
        return v

    return parse


_fraction = _share(1.0, "a fraction")
_noise = _share(MAX_NOISE, "a fraction of the stroke")


def _seeds(text: str) -> tuple[int, ...]:
    try:
        seeds = tuple(dict.fromkeys(int(s) for s in text.split(",") if s.strip()))
    except ValueError:
        seeds = ()
    if not seeds or min(seeds) < 0:
        raise argparse.ArgumentTypeError(f"comma-separated integers >= 0, got {text!r}")
    return seeds


def make_parser() -> argparse.ArgumentParser:
    doc = __doc__ or ""
    ap = argparse.ArgumentParser(
        prog="python -m agents.datasets", description=doc.split("\n")[0], epilog="docs/offline.md"
    )
    ap.add_argument(
        "--env",
        default=steamtemp_gym.ENV_IDS[0].split("/")[-1],
        help="the plant's env id, with or without steamtemp/ (default: the first "
        "plant, %(default)s)",
    )
    ap.add_argument("--policy", required=True, help="the policy that acts: " + specs.FORMS)
    ap.add_argument(
        "--episodes",
        type=_int(1, MAX_EPISODES, "--episodes"),
        default=20,
        help="number of episodes (default: %(default)s)",
    )
    ap.add_argument(
        "--seed",
        type=_int(0, 2**31 - 1, "--seed"),
        default=0,
        help="seed of the first episode; episode i has seed + i (default: 0)",
    )
    ap.add_argument(
        "--data-dir",
        default=None,
        metavar="DIR",
        help="Minari's data folder (sets MINARI_DATASETS_PATH; default: that "
        "variable, else ~/.minari/datasets)",
    )
    ap.add_argument(
        "--mixed",
        type=_fraction,
        default=None,
        metavar="F",
        help=f"mixed quality: each episode by {DETUNED} at a random tuning with "
        "probability F, else by --policy; the name gets -mixed",
    )
    ap.add_argument(
        "--noise",
        type=_noise,
        default=None,
        metavar="S",
        help="inject low-pass Gaussian noise of standard deviation S (fraction "
        "of the stroke) into the actions (DART); the policy's own action is in "
        f"the info '{POLICY_ACTION}'; the name gets -noisy<percent>",
    )
    ap.add_argument("--name", default=None, help="the dataset name (default: from the policy)")
    ap.add_argument(
        "--version",
        type=_int(0, 10**6, "--version"),
        default=0,
        help="the dataset version (default: 0)",
    )
    ap.add_argument(
        "--eval-scenario",
        default=EVAL_SCENARIO,
        help="the evaluation env's scenario, where the reference scores are "
        "measured (default: %(default)s)",
    )
    ap.add_argument(
        "--eval-seeds",
        type=_seeds,
        default=EVAL_SEEDS,
        metavar="S,S,...",
        help="seeds of the reference episodes (default: 0,1,2,3,4, the leaderboard's)",
    )
    ap.add_argument("--author", default=AUTHOR, help="(default: %(default)s)")
    return ap


def main(argv: list[str] | None = None) -> int:
    ap = make_parser()
    args = ap.parse_args(argv)
    if (
        args.data_dir is not None
        and Path(args.data_dir).exists()
        and not Path(args.data_dir).is_dir()
    ):
        ap.error(f"argument --data-dir: {str(args.data_dir)[:200]!r} is a file, not a folder")
    try:
        import minari  # noqa: F401
    except ImportError:
        ap.error("minari is not installed: pip install 'steamtemp-gym[offline]'")
    try:
        env_id = envs_.resolve_id(args.env)
    except ValueError as exc:
        ap.error(f"argument --env: {exc}")
    try:
        spec = specs.parse(args.policy)
    except ValueError as exc:
        ap.error(f"argument --policy: {exc}")
    if not spec.available(env_id):
        ap.error(f"argument --policy: {args.policy!r} has no agent for {env_id}")
    try:
        scenarios.resolve(args.eval_scenario, env_id)
    except ValueError as exc:
        ap.error(f"argument --eval-scenario: {exc}")
    if args.eval_scenario == scenarios.RANDOM:
        ap.error("argument --eval-scenario: must be a fixed scenario, not 'random'")
    if args.name is not None and not re.fullmatch(r"[A-Za-z0-9_][A-Za-z0-9_-]*", args.name):
        ap.error(f"argument --name: letters, digits, '_' and '-' only, got {args.name!r}")
    if args.data_dir is not None:
        os.environ["MINARI_DATASETS_PATH"] = str(Path(args.data_dir).resolve())
    from minari.storage import get_dataset_path

    did = dataset_id(
        env_id, args.name or dataset_name(args.policy, args.mixed, args.noise), args.version
    )
    if Path(get_dataset_path(did)).exists():
        ap.error(
            f"dataset {did} exists already in {get_dataset_path(did)}; delete it "
            "(minari delete) or give another --version or --name"
        )
    t0 = time.perf_counter()
    dataset = record(
        env_id,
        args.policy,
        args.episodes,
        args.seed,
        mixed=args.mixed,
        noise=args.noise,
        name=args.name,
        version=args.version,
        eval_scenario=args.eval_scenario,
        eval_seeds=args.eval_seeds,
        author=args.author,
        log=lambda m: print(m, file=sys.stderr),
    )
    path = Path(get_dataset_path(did))
    size = sum(f.stat().st_size for f in path.rglob("*") if f.is_file())
    print(
        f"{did}: {dataset.total_episodes} episodes, {dataset.total_steps} steps, "
        f"{size / 1e6:.1f} MB in {path}, {time.perf_counter() - t0:.1f} s; ref_min_score "
        f"{dataset.storage.metadata['ref_min_score']:.6g}, ref_max_score "
        f"{dataset.storage.metadata['ref_max_score']:.6g}"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
