"""The input of a training run: the algorithms and RL Zoo's hyperparameter files, read and
checked before anything trains (agents/train.py's module docstring gives the keys).
"""

from __future__ import annotations

import ast
import math
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from agents.horizons import from_plant
from agents.moves import check_filter, check_max_move, tie_map
from agents.policy import model_class
from agents.residual import check_residual
from agents.travel_price import PRICE_MAX, PRICE_MIN
from agents.wrappers import memory_options
from steamtemp_gym.plants import perturb, plant_class
from steamtemp_gym.rewards import RewardConfig

#: Algorithm names: SB3's PPO, SAC, TD3, PPO as a residual on a base controller
#: (:data:`RESIDUAL_BASES`; each its own YAML file, whose entries need ``residual_scale``)
#: PPO imitating a causal expert by DAgger (agents/imitation.py), the same fine-tuned by PPO
#: (``_rl``), and sb3-contrib's TRPO (a trust-region natural policy gradient) and
#: RecurrentPPO (an LSTM policy: the memory is learned instead of given by agents.wrappers).
ALGOS = (
    "ppo",
    "sac",
    "td3",
    "trpo",
    "ppo_residual",
    "ppo_residual_pi",
    "ppo_residual_mpc",
    "ppo_imitation_mpc",
    "ppo_imitation_mpc_rl",
    "recurrentppo",
    "sac_caps",
    "ppo_privileged",
)
#: The algorithms whose critic sees privileged signals in training (agents/privileged.py):
#: PPO's actor-critic with an actor on the agent's observation only.
PRIVILEGED = ("ppo_privileged",)
#: The base controller of each residual algorithm (agents/residual.py): observed by the
#: agent and told the applied command; None: ``ppo_residual``'s legacy form (the industrial
#: reference, unobserved).
RESIDUAL_BASES = {
    "ppo_residual": None,
    "ppo_residual_pi": "cascade_pi_ff_tuned",
    "ppo_residual_mpc": "mpc_linear",
}
#: The expert of each imitation algorithm (agents/imitation.py).
EXPERTS = {"ppo_imitation_mpc": "mpc_linear", "ppo_imitation_mpc_rl": "mpc_linear"}
#: The imitation algorithms that go on with PPO after DAgger (agents/imitation.py ``anchor``).
FINE_TUNED = ("ppo_imitation_mpc_rl",)
#: Entry keys of an imitation algorithm's DAgger (besides the PPO constructor's and RL Zoo's),
#: and those of a fine-tuned one's RL (:data:`FINE_TUNED` only).
DAGGER_KEYS = ("dagger_iterations", "beta_decay", "fit_epochs", "fit_seconds", "move_weight")
FINE_TUNE_KEYS = ("dagger_minutes", "anchor_weight", "anchor_fraction")
IMITATION_KEYS = DAGGER_KEYS + FINE_TUNE_KEYS
IMITATION_DEFAULTS = {
    "dagger_iterations": 8,
    "beta_decay": 0.5,
    "fit_epochs": 10,
    "fit_seconds": 60.0,
    "move_weight": 1.0,
    "dagger_minutes": None,
    "anchor_weight": 1.0,
    "anchor_fraction": 0.5,
}


def check_imitation(hp: dict[str, Any], algo: str) -> None:
    """ValueError naming the first bad imitation setting of an entry ``hp`` of ``algo``."""
    given = sorted(set(hp) & set(FINE_TUNE_KEYS))
    if given and algo not in FINE_TUNED:
        raise ValueError(f"{given} only for an imitation fine-tuned by RL ({list(FINE_TUNED)})")
    v = hp.get("dagger_minutes")
    if v is not None and not (
        isinstance(v, (int, float)) and not isinstance(v, bool) and 0 < v < np.inf
    ):
        raise ValueError(f"dagger_minutes must be a number > 0, got {v!r}")
    v = hp.get("anchor_fraction", IMITATION_DEFAULTS["anchor_fraction"])
    if not (isinstance(v, (int, float)) and not isinstance(v, bool) and 0 < v <= 1):
        raise ValueError(f"anchor_fraction must be a number in (0, 1], got {v!r}")
    for key, lo, kind in (("dagger_iterations", 1, int), ("fit_epochs", 1, int)):
        v = hp.get(key, IMITATION_DEFAULTS[key])
        if not (isinstance(v, kind) and not isinstance(v, bool) and v >= lo):
            raise ValueError(f"{key} must be an integer >= {lo}, got {v!r}")
    for key in ("move_weight", "anchor_weight"):
        v = hp.get(key, IMITATION_DEFAULTS[key])
        if not (isinstance(v, (int, float)) and not isinstance(v, bool) and 0 <= v < np.inf):
            raise ValueError(f"{key} must be a number >= 0, got {v!r}")
    for key in ("beta_decay", "fit_seconds"):
        v = hp.get(key, IMITATION_DEFAULTS[key])
        ok = isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v)
        if not (ok and v > 0 and (key != "beta_decay" or v < 1)):
            where = "(0, 1)" if key == "beta_decay" else "> 0"
            raise ValueError(f"{key} must be a number in {where}, got {v!r}")


HYPERPARAMS = Path(__file__).with_name("hyperparams")
#: RL Zoo keys with a meaning of their own (the rest go to the algorithm's constructor).
#: The longest budget of a run an entry may ask for (``max_minutes``): minutes of
#: one core, the project's budget per training run.
MAX_RUN_MINUTES = 20
SPECIAL = (
    "n_timesteps",
    "n_envs",
    "policy",
    "normalize",
    "env_wrapper",
    "policy_kwargs",
    "noise_type",
    "noise_std",
    "noise_tau_s",
    "residual_scale",
    "max_move",
    "train_reward",
    "plant_randomization",
    "travel_price",
    "price_probe_every",
    "residual_base",
    "action_filter_s",
    "critic_warmup_steps",
    "tied_valves",
    "action_repeat",
    "max_minutes",
    "privileged_critic",
    *IMITATION_KEYS,
)


class ConfigError(ValueError):
    """Bad training input (env, algo, YAML, hyperparameter keys)."""


def algo_class(algo: str):
    if algo not in ALGOS:
        raise ConfigError(f"unknown algo {algo!r}; valid: {list(ALGOS)}")
    names = {"recurrentppo": "RecurrentPPO", "sac_caps": "SACCAPS"}  # the rest: PPO, SAC, TD3, TRPO
    try:
        return model_class(names.get(algo, algo.split("_")[0].upper()))
    except ValueError as exc:
        raise ConfigError(str(exc)) from None


def _literal(node: ast.AST) -> Any:
    """A literal, or a ``dict(key=literal, ...)`` call of literals (nested)."""
    if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "dict" and not node.args:
        return {kw.arg: _literal(kw.value) for kw in node.keywords}
    return ast.literal_eval(node)


def dict_string(key: str, value: Any) -> dict:
    """RL Zoo's "dict(a=1, b=dict(c=[2]))" strings (literals only; no code is run)."""
    if isinstance(value, dict):
        return dict(value)
    try:
        out = _literal(ast.parse(str(value), mode="eval").body)
        if not isinstance(out, dict):
            raise ValueError
        return out
    except (SyntaxError, ValueError):
        raise ConfigError(
            f"{key} must be a mapping or a 'dict(key=literal, ...)' string, got {value!r}"
        ) from None


def _checked(path: Path, check: Any, *args: Any) -> None:
    """``check(*args)``, its ValueError turned into a ConfigError naming the file."""
    try:
        check(*args)
    except ValueError as exc:
        raise ConfigError(f"--hyperparams {path}: {exc}") from None


def read_hyperparams(path: Path, env_id: str, algo: str) -> dict[str, Any]:
    """The checked hyperparameters of env_id in an RL-Zoo YAML file.

    Raises:
        ConfigError: unreadable or malformed YAML, no entry for env_id, unknown keys.
    """
    cls = algo_class(algo)
    hp = _entry(path, env_id)
    _check_keys(path, hp, algo, cls)
    _check_action_form(path, hp, env_id, algo)
    _check_run(path, hp, algo)
    _check_training_terms(path, hp, env_id)
    _check_imitation_entry(path, hp, algo)
    hp = _completed(path, hp, algo)
    _check_noise(hp)
    return hp


def _entry(path: Path, env_id: str) -> dict[str, Any]:
    """The entry of env_id in the YAML file, its ``plant`` settings read from the plant's
    time scale."""
    try:
        doc = yaml.safe_load(Path(path).read_text(encoding="utf-8"))
    except (OSError, yaml.YAMLError) as exc:
        raise ConfigError(f"--hyperparams {path}: cannot read it as YAML: {exc}") from None
    if not isinstance(doc, dict):
        raise ConfigError(f"--hyperparams {path}: expected a mapping of env ids")
    if env_id not in doc:
        raise ConfigError(f"--hyperparams {path}: no entry for {env_id}; has {sorted(doc)}")
    hp = doc[env_id]
    if not isinstance(hp, dict):
        raise ConfigError(f"--hyperparams {path}: {env_id} must map to a mapping")

    try:
        return from_plant(env_id, hp)  # "plant": the setting read from the plant's time scale
    except ValueError as exc:
        raise ConfigError(f"--hyperparams {path}: {exc}") from None


def _constructor_keys(cls: Any) -> set[str]:
    """The keyword arguments of the algorithm class's constructor, less env and policy."""
    import inspect

    ctor = set()
    for c in cls.__mro__:  # a subclass taking **kwargs (agents/caps.py) passes them on
        params = inspect.signature(c.__init__).parameters
        ctor |= {n for n, p in params.items() if p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)}
        if not any(p.kind == p.VAR_KEYWORD for p in params.values()):
            break
    return ctor - {"self", "env", "policy"}


def _check_keys(path: Path, hp: dict[str, Any], algo: str, cls: Any) -> None:
    """ConfigError for a key that is neither RL Zoo's nor the constructor's."""
    ctor = _constructor_keys(cls)
    unknown = sorted(set(hp) - set(SPECIAL) - ctor)
    if unknown:
        raise ConfigError(
            f"--hyperparams {path}: unknown key(s) {unknown} for {algo}; valid: "
            f"{sorted(ctor | set(SPECIAL))}"
        )


def _check_action_form(path: Path, hp: dict[str, Any], env_id: str, algo: str) -> None:
    """ConfigError for a bad or conflicting setting of the action's form: residual
    (residual_scale), incremental (max_move), filtered (action_filter_s), tied valves."""
    if ("residual_scale" in hp) != (algo in RESIDUAL_BASES):
        raise ConfigError(
            f"--hyperparams {path}: residual_scale is required for a residual "
            f"algo ({list(RESIDUAL_BASES)}) and only there (algo {algo!r})"
        )
    if "residual_scale" in hp:
        _checked(path, check_residual, hp["residual_scale"], RESIDUAL_BASES[algo])
    if "max_move" in hp:
        if "residual_scale" in hp:
            raise ConfigError(
                f"--hyperparams {path}: residual_scale and max_move exclude each "
                "other (an agent is residual or incremental)"
            )
        _checked(path, check_max_move, hp["max_move"])
    if "action_filter_s" in hp:
        if "max_move" in hp or "residual_scale" in hp:
            raise ConfigError(
                f"--hyperparams {path}: action_filter_s filters position "
                "actions: not with max_move or residual_scale"
            )
        _checked(path, check_filter, hp["action_filter_s"])
    if "tied_valves" in hp:
        if "max_move" not in hp and "action_filter_s" not in hp:
            raise ConfigError(
                f"--hyperparams {path}: tied_valves needs incremental "
                "(max_move) or filtered (action_filter_s) actions"
            )

        _checked(path, tie_map, tuple(plant_class(env_id).valves), hp["tied_valves"])


def _check_run(path: Path, hp: dict[str, Any], algo: str) -> None:
    """ConfigError for a bad run budget (max_minutes) or a bad critic warm-up
    (critic_warmup_steps, PPO only)."""
    if "max_minutes" in hp:
        v = hp["max_minutes"]
        ok = isinstance(v, (int, float)) and not isinstance(v, bool)
        if not (ok and 0 < v <= MAX_RUN_MINUTES):
            raise ConfigError(
                f"--hyperparams {path}: max_minutes (a run's budget, CPU minutes) "
                f"must be a number in (0, {MAX_RUN_MINUTES}], got {v!r}"
            )
    if "critic_warmup_steps" in hp:
        v = hp["critic_warmup_steps"]
        if not (isinstance(v, int) and not isinstance(v, bool) and v >= 0):
            raise ConfigError(
                f"--hyperparams {path}: critic_warmup_steps must be an integer >= 0, got {v!r}"
            )
        if algo.split("_")[0] != "ppo":
            raise ConfigError(
                f"--hyperparams {path}: critic_warmup_steps is for PPO's "
                f"actor and critic, not {algo!r}"
            )


def _check_training_terms(path: Path, hp: dict[str, Any], env_id: str) -> None:
    """ConfigError for a bad training reward, travel price, plant randomization or
    discount (gamma, gae_lambda)."""
    if "train_reward" in hp:
        try:
            RewardConfig.from_options(hp["train_reward"])
        except ValueError as exc:
            raise ConfigError(f"--hyperparams {path}: train_reward: {exc}") from None
    if "travel_price" in hp:
        v = hp["travel_price"]
        ok = isinstance(v, (int, float)) and not isinstance(v, bool)
        if not (ok and PRICE_MIN <= v <= PRICE_MAX):
            raise ConfigError(
                f"--hyperparams {path}: travel_price (the starting price per "
                f"valve stroke) must be a number in [{PRICE_MIN}, {PRICE_MAX}], "
                f"got {v!r}"
            )
    if "price_probe_every" in hp:
        v = hp["price_probe_every"]
        if "travel_price" not in hp:
            raise ConfigError(f"--hyperparams {path}: price_probe_every needs travel_price")
        if not (isinstance(v, int) and not isinstance(v, bool) and v >= 1):
            raise ConfigError(
                f"--hyperparams {path}: price_probe_every (transitions between "
                f"two closed-loop travel probes) must be a positive integer, "
                f"got {v!r}"
            )
    if "plant_randomization" in hp:
        _checked(path, perturb.parse, env_id, hp["plant_randomization"])
    for key in ("gamma", "gae_lambda"):
        v = hp.get(key, 0.5)
        if not (isinstance(v, (int, float)) and not isinstance(v, bool) and 0 < v <= 1):
            raise ConfigError(
                f"--hyperparams {path}: {key} must be a number in (0, 1] or "
                f"'plant' (read from the plant's time scale), got {v!r}"
            )


def _check_imitation_entry(path: Path, hp: dict[str, Any], algo: str) -> None:
    """ConfigError for an imitation key outside an imitation algo, a bad imitation setting
    or an action form its expert does not act in."""
    given = sorted(set(hp) & set(IMITATION_KEYS))
    if given and algo not in EXPERTS:
        raise ConfigError(
            f"--hyperparams {path}: {given} only for an imitation algo ({list(EXPERTS)})"
        )
    if algo in EXPERTS:
        _checked(path, check_imitation, hp, algo)
        if any(
            k in hp
            for k in ("max_move", "residual_scale", "travel_price", "tied_valves", "action_repeat")
        ):
            raise ConfigError(
                f"--hyperparams {path}: an imitation agent acts on valve "
                "positions in every interval as its expert does (no max_move, "
                "residual_scale, travel_price, tied_valves or "
                "action_repeat)"
            )


def _completed(path: Path, hp: dict[str, Any], algo: str) -> dict[str, Any]:
    """A copy of the entry with the algo's residual base and its policy_kwargs, normalize
    and env_wrapper parsed."""
    for key, by in (("residual_base", RESIDUAL_BASES), ("privileged_critic", PRIVILEGED)):
        if key in hp:
            raise ConfigError(
                f"--hyperparams {path}: {key} is set by the algo ({by}), not in the file"
            )
    hp = dict(hp)
    hp["residual_base"] = RESIDUAL_BASES.get(algo)
    hp["privileged_critic"] = algo in PRIVILEGED
    hp["policy_kwargs"] = dict_string("policy_kwargs", hp.get("policy_kwargs", {}))
    norm = hp.get("normalize", False)
    hp["normalize"] = norm if isinstance(norm, bool) else dict_string("normalize", norm)
    try:
        hp["env_wrapper"] = memory_options(hp["env_wrapper"]) if "env_wrapper" in hp else None
    except ValueError as exc:
        raise ConfigError(str(exc)) from None
    return hp


def _check_noise(hp: dict[str, Any]) -> None:
    """ConfigError for a bad exploration noise (noise_type, noise_tau_s)."""
    if hp.get("noise_type") not in (None, "normal", "lowpass"):
        raise ConfigError(f"noise_type: 'normal' or 'lowpass', got {hp['noise_type']!r}")
    tau = hp.get("noise_tau_s")
    if (hp.get("noise_type") == "lowpass") != (tau is not None):
        raise ConfigError(
            "noise_tau_s (seconds, or plant) goes with noise_type: lowpass, "
            f"and only with it; got noise_type {hp.get('noise_type')!r}, "
            f"noise_tau_s {tau!r}"
        )
    if tau is not None and not (
        isinstance(tau, (int, float))
        and not isinstance(tau, bool)
        and math.isfinite(tau)
        and tau > 0
    ):
        raise ConfigError(f"noise_tau_s must be a positive number of seconds or plant, got {tau!r}")
