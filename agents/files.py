"""A trained agent's files, found from a path: what ``steamtemp-train --out`` writes and
what an RL Zoo run writes, each turned into the same Policy (agents/policy.py).

Two layouts:

- ``steamtemp-train --out DIR`` (and the shipped ``agents/zoo/``):
  ``DIR/<env>__<algo>.zip`` (the SB3 model) and ``DIR/<env>__<algo>.json`` (env id,
  ``sb3_class``, controller ``memory``, ``normalization`` statistics, ``residual_scale``,
  ``residual_base``, ``max_move``);
  ``<env>`` is the env id with ``/`` written ``__``. Independent training runs of one
  agent (``python -m agents.train --zoo --runs K``) are ``<env>__<algo>__run<k>``,
  k = 0..K-1; a file without the run index is read as run 0 (where ``__run0`` is absent).
  :func:`stem` builds these names, :func:`steamtemp_paths` the two files' paths, and
  :func:`parse_stem` reads them.
- an RL Zoo run (``python -m rl_zoo3.train --algo A --env ID --log-folder LOGS``):
  ``LOGS/A/<name>_<n>/`` holding ``<name>.zip`` (the last model), ``best_model.zip``
  (with evaluation) and ``<name>/`` with ``args.yml`` (``algo``, ``env``), ``config.yml``
  (the hyperparameters: ``env_wrapper``, ``normalize``) and ``vecnormalize.pkl`` (the
  VecNormalize statistics, when normalized); ``<name>`` is the env id with ``/`` written
  ``-``.

:func:`find` takes a directory of either layout or one model ``.zip`` in it. The files
that decide an agent's actions (the model and its metadata or statistics) are hashed
for the leaderboard's fingerprint (:meth:`AgentFiles.digest`). :meth:`AgentFiles.check`
reads the model's observation and action shapes from its ``.zip`` (no torch, nothing
unpickled) and checks them against the env it is labelled with, so that a model of
another env, an RL Zoo run without its controller memory or a corrupt ``.zip`` is refused
when the name is parsed, not episode by episode.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import pickle
import re
import subprocess
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from agents.memory import MemoryConfig, memory_options

#: steamtemp-train's layout and RL Zoo's.
STEAMTEMP, RL_ZOO = "steamtemp-train", "rl-zoo"
#: RL Zoo's algo names of the model classes whose names are not the algo upper-cased.
_RL_ZOO_CLASSES = {"ppo_lstm": "RecurrentPPO", "crossq": "CrossQ"}
#: The run index at the end of a stem: ``__run<k>``, k without leading zeros.
RUN_TAG = "__run"
_STEM = re.compile(
    r"^(?P<env>.+?)__(?!run[0-9]*(?:__|$))(?P<algo>[A-Za-z0-9]+(?:_[A-Za-z0-9]+)*)"
    r"(?:__run(?P<run>0|[1-9][0-9]*))?$"
)


@dataclass(frozen=True)
class AgentFiles:
    """One trained agent on disk.

    Attributes:
        env_id: The env id it was trained on.
        algo: Its algorithm name as its files spell it.
        model: The SB3 model ``.zip``.
        meta: The other files its actions depend on (metadata, normalization statistics).
        layout: :data:`STEAMTEMP` or :data:`RL_ZOO`.
    """

    env_id: str
    algo: str
    model: Path
    meta: tuple[Path, ...]
    layout: str

    def digest(self) -> str:
        """SHA-256 over the model and its other files, in order."""
        h = hashlib.sha256()
        for f in (self.model, *self.meta):
            h.update(f.read_bytes())
        return h.hexdigest()

    def shapes(self) -> tuple[tuple[int, ...], tuple[int, ...]]:
        """The observation and action shapes the model was trained with (its ``.zip``'s
        ``data`` entry, as SB3 writes it).

        Raises:
            ValueError: the file is not an SB3 model (not a zip, no ``data``, no spaces).
        """
        try:
            with zipfile.ZipFile(self.model) as z:
                data = json.loads(z.read("data"))
            return tuple(data["observation_space"]["_shape"]), tuple(data["action_space"]["_shape"])
        except (OSError, zipfile.BadZipFile, KeyError, TypeError, ValueError) as exc:
            raise ValueError(
                f"{str(self.model)!r} is not a Stable-Baselines3 model file (a .zip "
                f"with its 'data' entry and spaces): {type(exc).__name__}: {exc}; "
                "is it corrupt or cut short?"
            ) from None

    def check(self) -> None:
        """The model fits the env it is labelled with: it takes that env's observation
        with this agent's controller memory appended and gives that env's action.

        Raises:
            ValueError: naming the model, its env and both sides' shapes.
        """
        stat = tuple((f.stat().st_size, f.stat().st_mtime_ns) for f in (self.model, *self.meta))
        _check(self, stat)

    def _memory(self) -> dict | None:
        """The controller-memory options of its observation pipeline (None: no memory)."""
        if self.layout == STEAMTEMP:
            return json.loads(self.meta[0].read_text(encoding="utf-8"))["memory"]
        return _rl_zoo_pipeline(self.model, self.meta)

    def load(self):
        """The agent as a Policy (agents.policy.AgentPolicy) on a new env of its id."""
        import gymnasium as gym

        # torch (the agents extra) through agents.policy: agents.files imports without it
        from agents.policy import AgentPolicy

        memory = self._memory()
        if self.layout == STEAMTEMP:
            meta = json.loads(self.meta[0].read_text(encoding="utf-8"))
            cls, norm, residual = meta["sb3_class"], meta["normalization"], meta["residual_scale"]
            max_move = meta.get("max_move")  # no key: the action is a valve position
            filter_s = meta.get("action_filter_s")
            tied = meta.get("tied_valves")  # no key: one action per valve
            base = meta.get("residual_base")  # no key: the legacy residual form
            repeat = meta.get("action_repeat")  # no key: a decision every interval
        else:
            cls = _RL_ZOO_CLASSES.get(self.algo, self.algo.upper())
            norm, residual, max_move, base, filter_s, tied, repeat = (None,) * 7
            pkl = [f for f in self.meta if f.name == "vecnormalize.pkl"]
            if pkl:
                norm = _vecnormalize_stats(pkl[0])
        st = self.model.stat()
        model = _model(cls, str(self.model), (st.st_size, st.st_mtime_ns))
        return AgentPolicy(
            model,
            gym.make(self.env_id),
            memory=memory,
            obs_norm=norm,
            residual_scale=residual,
            max_move=max_move,
            residual_base=base,
            action_filter_s=filter_s,
            tied_valves=tied,
            action_repeat=repeat,
        )


def git_revision() -> str:
    """The git commit of this checkout (recorded in a trained agent's or a dataset's
    metadata), "unknown" outside a git checkout."""
    try:
        done = subprocess.run(
            ["git", "rev-parse", "HEAD"],
            cwd=Path(__file__).parent,
            capture_output=True,
            text=True,
            check=True,
        )
        return done.stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


@functools.lru_cache(maxsize=32)
def _model(cls: str, path: str, stat: tuple) -> Any:
    """The SB3 model of class ``cls`` in file ``path``, read once per process and state
    (size, modification time) of the file: a leaderboard loads an agent for every scenario,
    and its policies only read the model."""
    # torch (the agents extra) through agents.policy: agents.files imports without it
    from agents.policy import model_class

    return model_class(cls).load(path, device="cpu")


@functools.lru_cache(maxsize=64)
def _env(env_id: str) -> Any:
    """One env of each id, to read its spaces and plant."""
    import gymnasium as gym

    return gym.make(env_id)


@functools.lru_cache(maxsize=256)
def _check(files: AgentFiles, stat: tuple) -> None:
    """:meth:`AgentFiles.check` (once per agent and state of its files)."""
    # torch (the agents extra) through agents.moves: agents.files imports without it
    from agents.moves import n_actions, tie_map

    obs, act = files.shapes()
    try:
        env = _env(files.env_id)
    except Exception as exc:  # noqa: BLE001 - an unknown or broken env id
        raise ValueError(
            f"{str(files.model)!r} is labelled for env {files.env_id!r}, which "
            f"cannot be made: {type(exc).__name__}: {exc}"
        ) from None
    plant = env.unwrapped.plant
    memory = files._memory()
    extra = (
        0
        if memory is None
        else MemoryConfig.from_kwargs(memory).n_extra(
            len(plant.valves), len(plant.secondary), env.observation_space.shape[-1]
        )
    )
    meta = (
        json.loads(files.meta[0].read_text(encoding="utf-8")) if files.layout == STEAMTEMP else {}
    )
    if meta.get("residual_base") is not None:  # the base's action is observed (residual.py)
        extra += len(plant.valves)
    if meta.get("privileged_critic"):  # what its critic saw besides (privileged.py)
        extra += len(meta["privileged_critic"]["signals"])
    want_obs = (env.observation_space.shape[-1] + extra,)
    want_act = tuple(env.action_space.shape)
    if meta.get("tied_valves") is not None:  # one action per group of tied valves (moves.py)
        want_act = (n_actions(tie_map(tuple(plant.valves), meta["tied_valves"])),)
    if (obs, act) == (want_obs, want_act):
        return
    how = (
        f"with its controller memory of {extra} entries ({memory})"
        if memory is not None
        else "without controller memory"
        + (" (its config.yml has no env_wrapper)" if files.layout == RL_ZOO else "")
    )
    raise ValueError(
        f"{str(files.model)!r} does not fit {files.env_id}, the env its files name: the model "
        f"takes observations of shape {obs} and gives actions of shape {act}; {files.env_id} "
        f"{how} gives observations of shape {want_obs} and takes actions of shape {want_act}. "
        "Was it trained on another env, or with another controller memory?"
    )


def stem(env_id: str, algo: str, run: int | None = None) -> str:
    """The file stem steamtemp-train gives an agent: ``steamtemp__Cascade300MW-v0__ppo``,
    and with a run index ``steamtemp__Cascade300MW-v0__ppo__run2``.

    Raises:
        ValueError: an env id that is empty or holds ``__`` (it would not read back), an
            algo that is not letters and digits joined by single ``_`` (or is ``run`` with
            or without digits), or a run that is not an integer >= 0.
    """
    if not isinstance(env_id, str) or not env_id or "__" in env_id or env_id.endswith("/"):
        raise ValueError(
            f"env id {env_id!r}: must be a non-empty string without '__' "
            "(its '/' is written '__' in file names)"
        )
    if run is not None and (isinstance(run, bool) or not isinstance(run, int) or run < 0):
        raise ValueError(f"run index {run!r}: must be an integer >= 0")
    name = f"{env_id.replace('/', '__')}__{algo}" + ("" if run is None else f"{RUN_TAG}{run}")
    if parse_stem(name, check=False) != (env_id, algo, run):
        raise ValueError(
            f"algo {algo!r}: must be letters and digits joined by single '_', "
            "and not 'run' with or without digits (the run index's tag)"
        )
    return name


def steamtemp_paths(
    directory: str | Path, env_id: str, algo: str, run: int | None = None
) -> tuple[Path, Path]:
    """The model ``.zip`` and the metadata ``.json`` of run ``run`` of (env_id, algo) in
    ``directory``, as steamtemp-train writes them (their stem: :func:`stem`).

    Raises:
        ValueError: parts :func:`stem` refuses.
    """
    base = stem(env_id, algo, run)
    return Path(directory) / f"{base}.zip", Path(directory) / f"{base}.json"


def parse_stem(name: str, check: bool = True) -> tuple[str, str, int | None]:
    """``(env_id, algo, run)`` of a stem :func:`stem` builds; ``run`` is None for a stem
    without a run index (read as run 0).

    Raises:
        ValueError: ``name`` is not such a stem.
    """
    m = _STEM.match(name) if isinstance(name, str) else None
    env = m.group("env") if m else ""
    if m is None or not env or "____" in env or env.startswith("__") or env.endswith("__"):
        if not check:
            return ("", "", None)
        raise ValueError(
            f"{name!r} is not a trained agent's file stem: expected "
            "<env>__<algo> or <env>__<algo>__run<k> (<env> the env id with '/' "
            "written '__', k an integer >= 0 without leading zeros)"
        )
    run = m.group("run")
    return env.replace("__", "/"), m.group("algo"), None if run is None else int(run)


def zoo_runs(directory: Path) -> dict[tuple[str, str], list[int]]:
    """The run indices of every (env id, algo) of steamtemp-train's files in ``directory``
    (a model .zip with its .json), in file-name order; the file without a run index is
    run 0 unless ``__run0`` is there too.

    Raises:
        ValueError: a model .zip with its .json whose stem :func:`parse_stem` refuses.
    """
    d = Path(directory)
    if not d.is_dir():
        return {}
    found = _zoo_runs(str(d.resolve()), tuple(sorted(os.listdir(d))))
    return {k: list(v) for k, v in found.items()}


@functools.lru_cache(maxsize=64)
def _zoo_runs(directory: str, names: tuple[str, ...]) -> dict[tuple[str, str], tuple[int, ...]]:
    """:func:`zoo_runs` of a folder holding ``names`` (memoized: a leaderboard asks it
    for every unit of every trained agent)."""
    out: dict[tuple[str, str], set[int]] = {}
    for name in names:
        if not name.endswith(".zip") or name.startswith("."):  # what glob("*.zip") finds
            continue
        stem = name.removesuffix(".zip")
        if os.path.isfile(os.path.join(directory, f"{stem}.json")):
            env_id, algo, run = parse_stem(stem)
            out.setdefault((env_id, algo), set()).add(0 if run is None else run)
    return {k: tuple(sorted(v)) for k, v in out.items()}


def steamtemp_files(directory: Path, env_id: str, algo: str, run: int = 0) -> AgentFiles:
    """steamtemp-train's files of run ``run`` of (env_id, algo) in ``directory``: the
    ``__run<k>`` files, or for run 0 without them the files without a run index.

    Raises:
        ValueError: the .zip or the .json is missing.
    """
    tried = [
        steamtemp_paths(directory, env_id, algo, k) for k in ((run, None) if run == 0 else (run,))
    ]
    for model, meta in tried:
        if model.is_file() and meta.is_file():
            return AgentFiles(env_id, algo, model, (meta,), STEAMTEMP)
    names = [f"{model.parent / model.stem}.zip/.json" for model, _ in tried]
    raise ValueError(f"no trained agent {' nor '.join(names)}")


def find(path: str | Path) -> list[AgentFiles]:
    """Every agent in ``path``: a directory of steamtemp-train's files, an RL Zoo run
    directory, or one model ``.zip`` of either layout (module docstring).

    Raises:
        ValueError: naming the path and what was looked for, when nothing is found there.
    """
    p = Path(path)
    if p.is_file():
        return [_one_file(p)]
    if not p.is_dir():
        raise ValueError(f"no file or directory {str(p)!r}")
    ours = sorted(f for f in p.glob("*__*.zip") if f.with_suffix(".json").is_file())
    if ours:
        return [_steamtemp_of(f) for f in ours]
    run = _rl_zoo_run(p)
    if run is not None:
        return [run]
    raise ValueError(
        f"{str(p)!r} holds no trained agent: expected steamtemp-train's <env>__<algo>.zip "
        "with its .json, or an RL Zoo run (<name>.zip and <name>/args.yml)"
    )


def _steamtemp_of(model: Path) -> AgentFiles:
    meta = model.with_suffix(".json")
    try:
        doc = json.loads(meta.read_text(encoding="utf-8"))
        env_id, algo = doc["env_id"], doc["algo"]
        for key in ("sb3_class", "memory", "normalization", "residual_scale"):
            doc[key]  # noqa: B018 - every key load() reads
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise ValueError(f"{str(meta)!r} is not steamtemp-train's metadata ({exc!r})") from None
    return AgentFiles(env_id, algo, model, (meta,), STEAMTEMP)


def _one_file(model: Path) -> AgentFiles:
    if model.suffix != ".zip":
        raise ValueError(f"{str(model)!r}: a trained agent's model file ends in .zip")
    if model.with_suffix(".json").is_file():
        return _steamtemp_of(model)
    run = _rl_zoo_run(model.parent, model)
    if run is None:
        raise ValueError(
            f"{str(model)!r} has neither steamtemp-train's {model.stem}.json next to it nor "
            "an RL Zoo run's <name>/args.yml in its directory"
        )
    return run


def _rl_zoo_run(run: Path, model: Path | None = None) -> AgentFiles | None:
    """The agent of an RL Zoo run directory (its last model, or ``model``), None if the
    directory is not one."""
    for args_file in sorted(run.glob("*/args.yml")):
        params = args_file.parent
        if model is None:
            model = run / f"{params.name}.zip"
            if not model.is_file():
                continue
        args = _zoo_yaml(args_file)
        if not isinstance(args, dict) or not {"algo", "env"} <= set(args):
            raise ValueError(f"{str(args_file)!r} has no 'algo' and 'env' (an RL Zoo args.yml)")
        meta = [f for f in (params / "config.yml", params / "vecnormalize.pkl") if f.is_file()]
        return AgentFiles(str(args["env"]), str(args["algo"]), model, tuple(meta), RL_ZOO)
    return None


class _ZooLoader(yaml.SafeLoader):
    """YAML as RL Zoo writes it (PyYAML's dump of OrderedDicts) without running code:
    an OrderedDict becomes a dict, a tuple a list, any other Python object None."""


def _ordered_dict(loader: yaml.SafeLoader, node: yaml.Node) -> dict:
    (pairs,) = loader.construct_sequence(node, deep=True) or ([],)
    return {k: v for k, v in pairs}


def _other(loader: yaml.SafeLoader, suffix: str, node: yaml.Node) -> Any:
    return None


_ZooLoader.add_constructor(
    "tag:yaml.org,2002:python/object/apply:collections.OrderedDict", _ordered_dict
)
_ZooLoader.add_constructor(
    "tag:yaml.org,2002:python/tuple",
    lambda loader, node: loader.construct_sequence(node, deep=True),
)
_ZooLoader.add_multi_constructor("tag:yaml.org,2002:python/", _other)


def _zoo_yaml(path: Path) -> Any:
    try:
        return yaml.load(path.read_text(encoding="utf-8"), Loader=_ZooLoader)  # noqa: S506
    except (OSError, yaml.YAMLError) as exc:
        raise ValueError(f"cannot read {str(path)!r} as YAML: {exc}") from None


def _rl_zoo_pipeline(model: Path, meta: tuple[Path, ...]) -> dict | None:
    """The controller-memory options of an RL Zoo run (its config.yml's ``env_wrapper``)."""
    config = [f for f in meta if f.name == "config.yml"]
    hp = _zoo_yaml(config[0]) if config else {}
    wrapper = (hp or {}).get("env_wrapper")
    if wrapper is None:
        return None
    try:
        return memory_options(wrapper)
    except ValueError as exc:
        raise ValueError(f"{str(config[0])!r}: {exc}") from None


def _vecnormalize_stats(path: Path) -> dict | None:
    """Frozen observation statistics of a saved VecNormalize (None if it does not
    normalize observations), in the form agents.policy.normalize_obs takes."""
    # torch (the agents extra) through agents.policy: agents.files imports without it
    from agents.policy import frozen_stats

    with path.open("rb") as f:
        return frozen_stats(pickle.load(f))  # the user's own training output, as SB3 reads it
