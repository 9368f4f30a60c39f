"""Policy names as ``steamtemp-leaderboard --policies`` and ``steamtemp-check --policy``
take them: one parser for both, so a name means the same policy everywhere.

- a baseline: a name of ``baselines.NAMES`` (the shipped controllers and those added with
  ``baselines.register``);
- ``sb3:<algo>``: the shipped trained agent of the env's plant (``agents.shipped()``): its
  run 0; ``sb3:<algo>@run<k>``: its training run k (``agents.runs``). Where the zoo holds
  several runs, :func:`training_runs` turns ``sb3:<algo>`` into one name per run and
  :func:`split_run` reads the agent and the run back (the leaderboard scores each run and
  reports the agent over all of them);
- a trained agent's files: ``zoo:PATH``, or ``PATH`` itself when it contains a ``/`` or
  ends in ``.zip``: a directory of ``steamtemp-train --out``'s files, an RL Zoo run
  directory, or one model ``.zip`` of either (agents/files.py); available for the env
  it was trained on;
- ``module:callable``: a factory ``callable(env) -> Policy`` (``env`` a single or a vector
  env; the policy needs ``predict`` and ``reset``, baselines/policy.py), with ``module`` a
  dotted module importable from ``sys.path`` (``PYTHONPATH=.`` adds the current directory)
  or a ``.py`` file; ``callable`` may be dotted (``MyController.create``).
- with ``parse(name, references=True)`` (the leaderboard's names), the references that are
  no baselines: ``oracle`` (the score's 1, agents/oracle.py) and ``frozen_valve``
  (agents/difficulty.py).

A :class:`Spec` carries what the leaderboard asks of a policy: whether it is a reference
(listed, never ranked) and which end of the score it is (:attr:`Spec.score_end`), whether
it runs in a process of its own (:attr:`Spec.own_process`: user code does), and what its
digest covers (:meth:`Spec.modules`, :meth:`Spec.digest`).

:func:`parse` checks a name (finding a factory's module file without importing it, an
agent's files, and checking that its model fits the observation and action spaces of the
env it names);
:meth:`Spec.make` builds the policy for an env; :func:`check_built` checks what a factory
returns; :meth:`Spec.digest` is what the leaderboard's fingerprint hashes: the name, with
a baseline's stored tuning on the env, or the hash of a trained agent's files or of a
factory's module file; the oracle's with its incumbents' and its engine's.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.machinery
import importlib.util
import json
import re
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import agents
import baselines
from agents.difficulty import FrozenValves
from agents.oracle import DEFAULT_ENGINE, INCUMBENTS, Oracle
from baselines import tuning
from steamtemp_gym import plants, provenance
from steamtemp_gym.checks import head
from steamtemp_gym.testing import guard

BASELINE, SHIPPED, FILES, FACTORY = "baseline", "shipped", "files", "factory"
#: The kinds of the references that are no baselines: the oracle and the frozen valve.
ORACLE, FROZEN = "oracle", "frozen"
#: The score's 0: the cascade as a commissioned unit runs it (a baseline).
ZERO = baselines.INDUSTRIAL_REFERENCE
#: The score's 1: the clairvoyant oracle on the true plant (agents/oracle.py).
ONE = "oracle"
#: Every actuator held at its reset opening (agents/difficulty.py).
FROZEN_VALVE = "frozen_valve"
#: The references: listed and plotted, never ranked; :func:`parse` takes them with
#: ``references=True`` (the leaderboard's names), name -> (kind, the module of its code).
REFERENCE_KINDS = {ONE: (ORACLE, "agents.oracle"), FROZEN_VALVE: (FROZEN, "agents.difficulty")}
REFERENCES = tuple(REFERENCE_KINDS)
#: The code of the oracle's certified optimizer (every engine but ``cem``).
OPTIMUM_MODULE = "agents.optimum"
SB3_PREFIX, ZOO_PREFIX = "sb3:", "zoo:"
#: ``sb3:<algo>@run<k>``: training run k of a shipped agent.
RUN_SUFFIX = "@run"
_RUN = re.compile(r"^(?P<agent>sb3:[^@]+)@run(?P<run>0|[1-9][0-9]*)$")
#: Every form, for error messages and --help.
FORMS = (
    "a baseline name, sb3:<algo> (a shipped trained agent), zoo:DIR or a path to a "
    "trained agent's files (a directory or .zip from steamtemp-train --out or an RL Zoo "
    "run), or module:callable (a factory env -> Policy; module a dotted name or a .py "
    "file)"
)
_FACTORY = re.compile(r"^(?P<module>[A-Za-z_][\w.]*|.+\.py):(?P<attr>[A-Za-z_][\w.]*)$")


@dataclass(frozen=True)
class Spec:
    """A parsed policy name.

    Attributes:
        name: The name as given.
        kind: :data:`BASELINE`, :data:`SHIPPED`, :data:`FILES`, :data:`FACTORY`, or a
            reference's: :data:`ORACLE`, :data:`FROZEN`.
        target: The baseline name, the algo, the path, ``module:callable``, or a
            reference's name.
        envs: Env ids it is available for (None: every env).
        run: A shipped agent's training run (None: run 0, the agent's default).
    """

    name: str
    kind: str
    target: str
    envs: frozenset[str] | None = None
    run: int | None = None

    @property
    def shipped(self) -> bool:
        """Whether it is the benchmark's own code: a shipped baseline or trained agent, or a
        reference (the leaderboard runs every other policy in a process of its own)."""
        own = self.kind == BASELINE and self.target in baselines.SHIPPED
        return own or self.kind in (SHIPPED, ORACLE, FROZEN)

    @property
    def reference(self) -> bool:
        """Whether it is a reference (:data:`REFERENCES`): listed, never ranked."""
        return self.kind in (ORACLE, FROZEN)

    @property
    def score_end(self) -> int | None:
        """Which end of the normalized score it is: 1 (the oracle), 0 (:data:`ZERO`), or
        None."""
        if self.kind == ORACLE:
            return 1
        return 0 if self.kind == BASELINE and self.target == ZERO else None

    @property
    def own_process(self) -> bool:
        """Whether the leaderboard runs it in a process of its own: user code (a factory, a
        trained agent's files, a registered baseline); the shipped policies and the
        references run in the leaderboard's."""
        return not self.shipped

    @property
    def is_factory(self) -> bool:
        """Whether it is a user's ``module:callable`` factory."""
        return self.kind == FACTORY

    @property
    def needs_extra(self) -> bool:
        """Whether building it needs the agents extra (Stable-Baselines3, torch)."""
        return self.kind in (SHIPPED, FILES)

    def available(self, env_id: str) -> bool:
        """Whether it can act on ``env_id``."""
        return self.envs is None or env_id in self.envs

    def make(self, env_id: str, env: Any, engine: str = DEFAULT_ENGINE) -> Any:
        """The policy for ``env`` (a single or vector env of ``env_id``; ``engine``: the
        oracle's, agents/oracle.py)."""
        if self.kind == FROZEN:
            return FrozenValves(env)
        if self.kind == ORACLE:
            return Oracle(env, engine=engine)
        if self.kind == BASELINE:
            return baselines.make(self.target, env)
        if self.kind == SHIPPED:
            return agents.load(env_id, self.target, run=self.run or 0)
        if self.kind == FILES:
            return _agent(self.target, env_id).load()
        policy = _factory(self.name, self.target)(env)
        check_built(self.name, policy)
        return policy

    def modules(self, engine: str = DEFAULT_ENGINE) -> tuple[str, ...]:
        """The modules of its code that its digest covers (with what they import from
        baselines and agents, :func:`code_digest`); none for a factory (its file is)."""
        if self.kind == BASELINE:
            return (baselines.factory(self.target).__module__,)
        if self.kind in (SHIPPED, FILES):
            return (AGENT_MODULE,)
        if self.reference:
            own = (REFERENCE_KINDS[self.name][1],)
            return own + ((OPTIMUM_MODULE,) if self.kind == ORACLE and engine != "cem" else ())
        return ()

    def digest(self, env_id: str, engine: str = DEFAULT_ENGINE) -> str:
        """The name, and the provenance digests of what decides its actions: its code (the
        modules of :meth:`modules`, :func:`code_digest`) and a baseline's stored tuning on
        the env (:func:`tuning_digest`), a trained agent's files, a factory's module; the
        oracle's with its incumbents' (their episodes are candidates of its own) and its
        engine's."""
        if self.kind == FROZEN:
            return f"{self.name}:{code_digest(*self.modules())}"
        if self.kind == ORACLE:
            own = f"{self.name}:{code_digest(*self.modules()[:1])}"
            own += "".join(f"+{parse(i).digest(env_id)}" for i in INCUMBENTS)
            if engine != "cem":
                own += f"+{engine}:{code_digest(*self.modules(engine)[1:])}"
            return own
        if self.kind == BASELINE:
            own = code_digest(*self.modules())
            return f"{self.name}:{tuning_digest(self.target, env_id)}:{own}"
        if self.kind == SHIPPED:
            from agents.files import steamtemp_files

            files = steamtemp_files(agents.ZOO, env_id, self.target, self.run or 0)
            return f"{self.name}:{files.digest()}:{code_digest(*self.modules())}"
        if self.kind == FILES:
            files = _agent(self.target, env_id)
            return f"{self.name}:{files.digest()}:{code_digest(*self.modules())}"
        if self.kind == FACTORY:
            path = module_file(self.name, self.target.rsplit(":", 1)[0])
            return self.name + ":" + provenance.file_digest(path)
        return self.name


#: The module of the trained agents' policies (observation pipeline, model).
AGENT_MODULE = "agents.policy"
#: The packages a policy's code digest follows imports into (the plant's own scope,
#: steamtemp_gym, is the fingerprint's other part).
POLICY_PACKAGES = ("baselines", "agents")


def code_digest(*modules: str) -> str:
    """The provenance digest (steamtemp_gym/provenance.py) of ``modules`` and of every
    module of baselines and agents they import; a module outside the checkout (a user's
    baseline registered with ``--import``) enters with its own file."""
    files = []
    for m in modules:
        found = provenance.module_files(m, POLICY_PACKAGES)
        if not found:
            path = getattr(importlib.import_module(m), "__file__", None)
            found = [Path(path)] if path else []
        files += found
    return provenance.digest(files)


#: The module that computes an episode's metrics and return from its trace.
EVALUATION = "agents.evaluation"


def source_digest(env_id: str) -> str:
    """The provenance digest of the code every result on ``env_id`` depends on: the plant's
    own package with the code all plants share (steamtemp_gym.provenance.plant_files) and
    the evaluation (metrics and return from the trace). A policy's own code and stored
    files are its part of a fingerprint (:meth:`Spec.digest`), so editing one baseline
    reruns its rows only, editing one plant that plant's, a docstring nothing."""
    module = plants.PLANTS[env_id].split(":")[0] if env_id in plants.PLANTS else None
    outside = provenance.outside_plant_files(env_id)
    if module is None or outside:  # a variant id, or a plant registered from outside
        files = [*provenance.package_files(), *outside]
        return f"{code_digest(EVALUATION)}:{provenance.digest(files)}"
    return provenance.digest(
        [*provenance.plant_files(module), *provenance.module_files(EVALUATION, POLICY_PACKAGES)]
    )


def tuning_digest(name: str, env_id: str) -> str:
    """Hash of the knob values the benchmark's tuning stored on ``env_id`` for the controller
    whose tuning the baseline row ``name`` reads (``baselines.tuning_source``): so a new
    tuning reruns that controller's rows and no other."""
    path = tuning.path(baselines.tuning_source(name))
    entry = json.loads(path.read_text())["plants"].get(env_id) if path.is_file() else None
    knobs = entry.get("knobs") if isinstance(entry, dict) else None
    return hashlib.sha256(json.dumps(knobs, sort_keys=True).encode()).hexdigest()[:16]


def parse(name: str, references: bool = False) -> Spec:
    """The Spec of a policy name (module docstring); with ``references``, the names of the
    references that are no baselines too (:data:`REFERENCES`, the leaderboard's).

    Raises:
        ValueError: an unknown name (listing every form and the valid names), a factory
            that cannot be imported or is not callable, a path without a trained agent.
    """
    if not isinstance(name, str) or not name.strip():
        raise ValueError(f"a policy name must be a non-empty string, got {_show(name)}; {FORMS}")
    if name in baselines.NAMES:
        return Spec(name, BASELINE, name)
    if references and name in REFERENCE_KINDS:
        return Spec(name, REFERENCE_KINDS[name][0], name)
    if name.startswith(SB3_PREFIX):
        agent, run = split_run(name)
        algo = agent[len(SB3_PREFIX) :]
        envs = frozenset(e for e, a in agents.shipped() if a == algo)
        if not envs:
            raise ValueError(
                f"no shipped trained agent {_show(name)}; shipped: {', '.join(shipped_names())}"
            )
        if run is not None:
            have = {e: agents.runs(e, algo) for e in envs}
            envs = frozenset(e for e in envs if run in have[e])
            if not envs:
                raise ValueError(
                    f"no training run {run} of {agent!r} shipped; its runs: "
                    f"{ {e: have[e] for e in sorted(have)} }"
                )
        from agents.files import steamtemp_files

        for e in sorted(envs):
            try:
                steamtemp_files(agents.ZOO, e, algo, run or 0).check()
            except ValueError as exc:
                raise ValueError(f"policy {_show(name)}: {exc}") from None
        return Spec(name, SHIPPED, algo, envs, run)
    if name.startswith(ZOO_PREFIX):
        return _files_spec(name, name[len(ZOO_PREFIX) :])
    m = _FACTORY.match(name)
    if m:
        module_file(name, m.group("module"))  # found, not imported (module_file)
        return Spec(name, FACTORY, name)
    if "/" in name or "\\" in name or name.endswith(".zip"):
        return _files_spec(name, name)
    raise ValueError(
        f"unknown policy {_show(name)}; valid names: {', '.join(baselines.NAMES)}, "
        f"{', '.join(shipped_names())}; a policy is {FORMS}"
    )


def everyday_names() -> list[str]:
    """What ``steamtemp-check --policy all`` stands for: every baseline."""
    return list(baselines.NAMES)


def listing() -> list[str]:
    """The baselines and the shipped trained agents, as ``python -m steamtemp_gym`` lists
    them."""
    where: dict[str, list[str]] = {}
    for env_id, algo in agents.shipped():
        where.setdefault(f"{SB3_PREFIX}{algo}", []).append(env_id.split("/")[-1])
    lines = [
        f"Baselines (baselines.make(name, env)): {', '.join(baselines.NAMES)}",
        "",
        "Shipped trained agents (agents.load(id, algo); need the agents extra):",
    ]
    return lines + [f"  {name}: {', '.join(ids)}" for name, ids in sorted(where.items())]


def _show(name: Any) -> str:
    """A bounded repr of a (possibly huge) name for messages."""
    return repr(head(name, 100)) if isinstance(name, str) else repr(name)[:100]


def run_name(agent: str, run: int) -> str:
    """The policy name of training run ``run`` of the shipped agent ``agent``
    (``sb3:ppo``, 2 -> ``sb3:ppo@run2``)."""
    return f"{agent}{RUN_SUFFIX}{run}"


def split_run(name: str) -> tuple[str, int | None]:
    """``(agent, run)`` of a policy name: ``sb3:ppo@run2`` -> ``("sb3:ppo", 2)``; any other
    name -> ``(name, None)``."""
    m = _RUN.match(name)
    return (m.group("agent"), int(m.group("run"))) if m else (name, None)


def training_runs(name: str, env_id: str) -> list[str]:
    """The names a policy name is scored under on ``env_id``: one per training run
    (:func:`run_name`) for ``sb3:<algo>`` when the zoo holds several runs of it there,
    else the name itself."""
    if not name.startswith(SB3_PREFIX) or split_run(name)[1] is not None:
        return [name]
    runs = agents.runs(env_id, name[len(SB3_PREFIX) :])
    return [run_name(name, k) for k in runs] if len(runs) > 1 else [name]


def shipped_names() -> list[str]:
    """``sb3:<algo>`` of every shipped algo (for some plant)."""
    return sorted({SB3_PREFIX + a for _, a in agents.shipped()})


def check_built(name: str, policy: Any) -> None:
    """A factory's return value has ``predict`` and ``reset``.

    Raises:
        ValueError: naming the policy and what is missing.
    """
    missing = [m for m in ("predict", "reset") if not callable(getattr(policy, m, None))]
    if missing:
        raise ValueError(
            f"policy {_show(name)}: the factory returned {type(policy).__name__}, "
            f"which has no {' and no '.join(missing)} method (a Policy needs "
            "predict(observation, state, episode_start, deterministic) and "
            "reset(), baselines/policy.py)"
        )


def _files_spec(name: str, path: str) -> Spec:
    from agents.files import find

    try:
        found = find(path)
        for f in found:  # the model fits the env it is labelled with (agents/files.py)
            f.check()
    except ValueError as exc:
        raise ValueError(f"policy {_show(name)}: {exc}") from None
    by_env: dict[str, list[str]] = {}
    for f in found:
        by_env.setdefault(f.env_id, []).append(f.model.name)
    several = {e: m for e, m in by_env.items() if len(m) > 1}
    if several:
        raise ValueError(
            f"policy {_show(name)}: several agents for one env in {path!r}: "
            f"{several}; name one model .zip instead"
        )
    return Spec(name, FILES, path, frozenset(by_env))


def _agent(path: str, env_id: str):
    """The agent of ``env_id`` among the files at ``path``."""
    from agents.files import find

    for f in find(path):
        if f.env_id == env_id:
            return f
    raise ValueError(f"{path!r} holds no trained agent for {env_id}")


def module_file(name: str, ref: str) -> Path:
    """The source file of a factory's module (a dotted name or a ``.py`` file), found the
    way an import would find it but without running any of its code or its packages':
    the leaderboard names, checks and fingerprints a user's policy from its file, and
    imports it only in the policy's own process (agents/leaderboard/isolated.py).

    Raises:
        ValueError: no such file or module, naming it.
    """
    if ref.endswith(".py"):
        path = Path(ref).resolve()
        if not path.is_file():
            raise ValueError(f"policy {_show(name)}: cannot import {ref!r}: no file {ref!r}")
        return path
    parts, spec, done = ref.split("."), None, []
    for part in parts:
        done.append(part)
        full = ".".join(done)
        known = sys.modules.get(full)
        if known is not None and getattr(known, "__spec__", None) is not None:
            spec = known.__spec__
        else:
            where = None if spec is None else spec.submodule_search_locations
            if spec is not None and where is None:  # a module, not a package: no submodules
                spec = None
            else:
                spec = importlib.machinery.PathFinder.find_spec(full, where)
        if spec is None:
            raise ValueError(
                f"policy {_show(name)}: cannot import {ref!r}: no module named {full!r} on "
                "sys.path (PYTHONPATH=. adds the current directory)"
            )
    origin = getattr(spec, "origin", None)
    if not origin or not Path(origin).is_file():
        raise ValueError(f"policy {_show(name)}: cannot import {ref!r}: it has no source file")
    return Path(origin)


def _module(name: str, ref: str):
    """The module of a factory: a dotted name or a ``.py`` file (loaded once per file)."""
    try:
        if not ref.endswith(".py"):
            return importlib.import_module(ref)
        path = Path(ref).resolve()
        if not path.is_file():
            raise ValueError(f"no file {ref!r}")
        key = path.stem if path.stem.isidentifier() else "_policy_module"
        known = sys.modules.get(key)
        if known is not None and getattr(known, "__file__", None) == str(path):
            return known
        if known is not None:  # another module of that name: a name of this file's own
            key = f"{key}_{hashlib.sha256(str(path).encode()).hexdigest()[:12]}"
            if key in sys.modules:
                return sys.modules[key]
        spec = importlib.util.spec_from_file_location(key, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[key] = module
        try:
            spec.loader.exec_module(module)
        except BaseException:
            del sys.modules[key]
            raise
        return module
    except BaseException as exc:  # any failure of the import is a bad name, SystemExit too
        if not guard.own_failure(exc):  # Ctrl-C
            raise
        raise ValueError(
            f"policy {_show(name)}: cannot import {ref!r}: {guard.describe(exc, 'the module')}"
        ) from None


def _factory(name: str, ref: str):
    """The callable of ``module:callable``."""
    module_ref, attr = ref.rsplit(":", 1)
    obj = _module(name, module_ref)
    for part in attr.split("."):
        if not hasattr(obj, part):
            raise ValueError(f"policy {_show(name)}: {module_ref!r} has no attribute {attr!r}")
        obj = getattr(obj, part)
    if not callable(obj):
        raise ValueError(
            f"policy {_show(name)}: {attr!r} is a {type(obj).__name__}, not callable "
            "(a factory env -> Policy)"
        )
    return obj
