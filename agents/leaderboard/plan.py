"""The plan of a leaderboard run: every flag checked (argparse errors, exit code 2) and the
envs built before anything runs, and the fingerprint of each env, scenario and policy (a hash
of everything but the seed that decides an episode's result).
"""

from __future__ import annotations

import argparse
import functools
import hashlib
import importlib
import json
import math
import os
import re
import sys
from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import gymnasium as gym

import agents
import baselines
from agents import specs, stats
from agents.leaderboard import mismatch, summary
from agents.leaderboard.isolated import PolicyFailed, PolicyProcess
from agents.leaderboard.records import EPISODES, SCHEMA, Key
from agents.oracle import DEFAULT_ENGINE
from steamtemp_gym import envs as envs_
from steamtemp_gym import scenarios
from steamtemp_gym.checks import head, tail
from steamtemp_gym.scenarios import heldout
from steamtemp_gym.testing import guard

#: The named scenarios every plant has, then the held-out set (steamtemp_gym/scenarios/heldout).
NAMED_SCENARIOS = (
    "load_ramp_100_50",
    "load_ramp_50_100",
    "load_cycle",
    "setpoint_step",
    "heat_imbalance_step",
    "load_following",
)
DEFAULT_SCENARIOS = NAMED_SCENARIOS + tuple(heldout.PREFIX + n for n in heldout.NAMES)
DEFAULT_SEEDS = "0-4"
#: The frozen-valve reference run on every plant (agents/difficulty.py).
REFERENCE = summary.REFERENCE
#: Policies that join every run: the score's 0, its 1 and the frozen valve.
ALWAYS = (specs.ZERO, *specs.REFERENCES)
#: Upper bound on the number of seeds (a range such as ``0-1000000000`` is a typo).
MAX_SEEDS = 10_000
MAX_SEED = 2**63 - 1
#: Default --episode-timeout (s): about 10 times the longest episode of a shipped policy (the
#: oracle and mpc_evarx on BoilerTurbineMIMO's load_cycle, 4800 s of plant time: 28 s and
#: 24 s wall on 2 shared cores).
EPISODE_TIMEOUT_S = 300.0
#: Longest excerpt of an exception message quoted in an argparse error.
EXCERPT = 400
_SEED_ITEM = re.compile(r"^(\d+)(?:-(\d+))?$")


@dataclass
class Plan:
    """What a run does, checked before anything runs."""

    envs: list[str]
    scenarios: list[str]
    seeds: list[int]
    policies: dict[str, list[str]]  # env -> policy names available for it
    envs_made: dict[tuple[str, str], Any] = field(default_factory=dict)  # (env, scenario) -> env
    resolved: dict[tuple[str, str], Any] = field(default_factory=dict)  # -> Scenario
    fingerprints: dict[tuple[str, str, str], str] = field(default_factory=dict)
    imports: tuple[str, ...] = ()  # --import: modules every worker imports first
    travel_budget: float = stats.TRAVEL_BUDGET  # --travel-budget
    episode_timeout: float | None = EPISODE_TIMEOUT_S  # --episode-timeout
    #: env -> mismatch label -> the variant's params (agents/leaderboard/mismatch.py)
    variants: dict[str, dict[str, dict]] = field(default_factory=dict)
    oracle: str = DEFAULT_ENGINE  # --oracle: the engine of the score's 1 (agents/oracle.py)
    #: policy name -> its Spec (agents/specs.py), parsed once for the run
    parsed: dict[str, specs.Spec] = field(default_factory=dict)

    def spec(self, name: str) -> specs.Spec:
        """The Spec of the policy ``name`` (parsed on first use, then kept)."""
        if name not in self.parsed:
            self.parsed[name] = specs.parse(name, references=True)
        return self.parsed[name]

    def scenarios_of(self, env_id: str) -> list[str]:
        """The run's scenarios on ``env_id``, then its mismatch labels."""
        return [*self.scenarios, *self.variants.get(env_id, {})]

    def policies_of(self, env_id: str, sc: str) -> list[str]:
        """The policies run on ``env_id`` under ``sc``: all but the references on a
        mismatch variant."""
        if sc in self.variants.get(env_id, {}):
            return [p for p in self.policies[env_id] if not self.spec(p).reference]
        return self.policies[env_id]

    def grid(self) -> Iterable[Key]:
        """Every episode of the run, in run order."""
        for env_id in self.envs:
            for sc in self.scenarios_of(env_id):
                for name in self.policies_of(env_id, sc):
                    for seed in self.seeds:
                        yield env_id, sc, name, seed


def items(ap: argparse.ArgumentParser, flag: str, text: str, key=None) -> list[str]:
    """Comma list: stripped, empty items ignored, duplicates dropped (first kept)."""
    items = [s.strip() for s in text.split(",")]
    items = [s for s in items if s]
    if not items:
        ap.error(f"argument {flag}: empty list {text!r}; give at least one comma-separated value")
    seen: dict[Any, str] = {}
    dups = []
    for s in items:
        k = key(s) if key else s
        if k in seen:
            dups.append(s)
        else:
            seen[k] = s
    if dups:
        print(f"note: {flag}: duplicates dropped: {dups}", file=sys.stderr)
    return list(seen.values())


def parse_seeds(ap: argparse.ArgumentParser, text: str) -> list[int]:
    """``--seeds``: integers >= 0 and inclusive ranges ``a-b``, comma separated, deduplicated."""
    seeds: list[int] = []
    for item in items(ap, "--seeds", text):
        m = _SEED_ITEM.match(item)
        if not m:
            ap.error(
                f"argument --seeds: invalid seed {head(item, 40)!r}: seeds are integers >= 0 "
                "or inclusive ranges a-b, comma separated (e.g. '0,1,2' or '0-4')"
            )
        lo = int(m.group(1))
        hi = int(m.group(2)) if m.group(2) is not None else lo
        if hi < lo:
            ap.error(f"argument --seeds: empty range {item!r} (write a-b with a <= b)")
        if hi > MAX_SEED:
            ap.error(f"argument --seeds: seed {hi} is larger than {MAX_SEED}")
        if hi - lo + 1 + len(seeds) > MAX_SEEDS:
            ap.error(f"argument --seeds: more than {MAX_SEEDS} seeds ({item!r})")
        seeds.extend(range(lo, hi + 1))
    unique = list(dict.fromkeys(seeds))
    if len(unique) < len(seeds):
        dups = sorted(s for s, n in Counter(seeds).items() if n > 1)
        print(f"note: --seeds: duplicates dropped: {dups[:20]}", file=sys.stderr)
    return unique


def available_policies(env_id: str) -> list[str]:
    """The policies of a run on ``env_id`` without ``--policies``: every baseline, every
    training run of the shipped agents there (with the agents extra), the references."""
    trained = (
        [
            r
            for e, a in agents.shipped()
            if e == env_id
            for r in specs.training_runs(f"{specs.SB3_PREFIX}{a}", e)
        ]
        if _sb3()
        else []
    )
    return list(baselines.NAMES) + trained + list(specs.REFERENCES)


@functools.lru_cache(maxsize=1)
def _sb3() -> bool:
    """Whether the trained agents can run (the agents extra); a note on stderr if not."""
    import importlib.util

    if importlib.util.find_spec("stable_baselines3") is not None:
        return True
    if agents.shipped():
        print(
            "note: the trained agents (sb3:*) are left out: they need the agents extra, "
            "pip install 'steamtemp-gym[agents]'",
            file=sys.stderr,
        )
    return False


def resolve_scenario(spec: str, env_id: str) -> Any:
    """A scenario name, ``heldout:<name>``, ``random`` or a YAML file as a Scenario (or
    ``random``): steamtemp_gym.scenarios.resolve, as gym.make takes them."""
    return scenarios.resolve(spec, env_id)


def parse_policy(ap: argparse.ArgumentParser, name: str, parsed: dict[str, specs.Spec]) -> None:
    """Parse the policy ``name`` into ``parsed`` (once: a name already there is kept); a name
    that does not parse (agents/specs.py), or a trained agent without the agents extra, is a
    bad --policies value."""
    if name in parsed:
        return
    try:
        parsed[name] = specs.parse(name, references=True)
    except ValueError as exc:
        ap.error(f"argument --policies: {head(str(exc), 1000)}")
    if parsed[name].needs_extra and not _sb3():
        ap.error(
            f"argument --policies: {head(name, 60)!r} is a trained agent: it needs the "
            "agents extra, pip install 'steamtemp-gym[agents]'"
        )


def policies(
    ap: argparse.ArgumentParser,
    envs: list[str],
    text: str | None,
    oracle: bool = True,
    imports: tuple[str, ...] = (),
    timeout: float | None = EPISODE_TIMEOUT_S,
) -> tuple[dict[str, list[str]], dict[str, specs.Spec]]:
    """Policies per env, and the Spec of each (parsed once); every requested name must parse
    (agents/specs.py) and be available for at least one env, and a factory's policy is
    built once on each env and checked, in a process of its own as it runs
    (agents/leaderboard/isolated.py), within ``timeout``. :data:`ALWAYS` joins every env
    (the oracle only with ``oracle``)."""
    parsed: dict[str, specs.Spec] = {}
    names = [] if text is None else items(ap, "--policies", text)
    for n in [*names, *ALWAYS]:
        parse_policy(ap, n, parsed)
    if text is None:
        out = {e: available_policies(e) for e in envs}
    else:
        if not oracle and any(parsed[n].score_end == 1 for n in names):
            ap.error(f"argument --policies: {summary.ONE} is listed but --no-oracle is given")
        out = _requested(ap, envs, names, parsed)
    for e, pols in out.items():
        if text is not None:
            pols[:] = list(dict.fromkeys(r for n in pols for r in specs.training_runs(n, e)))
        for n in pols:
            parse_policy(ap, n, parsed)
        for n in [n for n in pols if parsed[n].is_factory]:
            try:
                PolicyProcess(n, e, None, None, imports, timeout).close()
            except PolicyFailed as exc:  # any failure is a bad --policies value
                ap.error(f"argument --policies: {head(n, 60)!r} on {e}: {head(str(exc), EXCERPT)}")
        pols += [p for p in ALWAYS if p not in pols]
        pols[:] = [p for p in pols if oracle or parsed[p].score_end != 1]
    return out, parsed


def _requested(
    ap: argparse.ArgumentParser, envs: list[str], names: list[str], parsed: dict[str, specs.Spec]
) -> dict[str, list[str]]:
    """The requested ``names`` available on each env (a note for each env that lacks some);
    a name available on none of ``envs`` is a bad --policies value."""
    nowhere = [n for n in names if not any(parsed[n].available(e) for e in envs)]
    if nowhere:
        ap.error(
            f"argument --policies: {[head(n, 60) for n in nowhere]} not available for envs "
            f"{envs}: only for {[sorted(parsed[n].envs) for n in nowhere]}"
        )
    out = {e: [n for n in names if parsed[n].available(e)] for e in envs}
    for e, pols in out.items():
        missing = [n for n in names if n not in pols]
        if missing:
            print(f"note: {missing} not available for {e}; skipped there", file=sys.stderr)
    return out


def env_id_of(name: str) -> str:
    """The id an --envs item names (with or without the namespace); itself if none."""
    try:
        return envs_.resolve_id(name)
    except ValueError:
        return name


def _scenario_key(spec: str) -> str:
    """Two spellings of one YAML file are one scenario."""
    if spec.endswith((".yaml", ".yml")):
        return os.path.realpath(spec)
    return spec


def _check_out(ap: argparse.ArgumentParser, out: Path, resume: bool) -> None:
    """The output directory can be created (or exists) and is writable; no stale record."""
    if out.exists() and not out.is_dir():
        ap.error(f"argument --out: {str(out)!r} exists and is not a directory")
    parent = out
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        ap.error(f"argument --out: {str(parent)!r} (in {str(out)!r}) is not a directory")
    if not os.access(parent, os.W_OK | os.X_OK):
        ap.error(f"argument --out: {str(out)!r} is not writable (no write access to {parent})")
    record = out / EPISODES
    if record.exists() and not record.is_file():
        ap.error(f"argument --out: {str(record)!r} is not a file")
    if not resume and record.is_file() and record.stat().st_size > 0:
        ap.error(
            f"argument --out: {str(record)!r} already holds episodes; pass --resume to "
            "continue that run, choose another --out, or move the file aside"
        )


def policy_digest(env_id: str, name: str | specs.Spec, oracle: str = DEFAULT_ENGINE) -> str:
    """The policy's part of the fingerprint (:meth:`agents.specs.Spec.digest`, ``oracle``
    the oracle's engine) of a policy name or its Spec."""
    spec = name if isinstance(name, specs.Spec) else specs.parse(name, references=True)
    return spec.digest(env_id, oracle)


def fingerprint(
    env_id: str, scenario: Any, policy_digest: str, source_digest: str, params: dict | None = None
) -> str:
    """Short hash of everything but the seed that decides an episode's result (``params``:
    a mismatch variant's plant parameters)."""
    sc = scenario.to_dict() if isinstance(scenario, scenarios.Scenario) else str(scenario)
    payload = {
        "schema": SCHEMA,
        "env": env_id,
        "scenario": sc,
        "policy": policy_digest,
        "source": source_digest,
    }
    if params:
        payload["params"] = params
    text = json.dumps(payload, sort_keys=True, allow_nan=False, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def episode_fingerprint(
    env_id: str, scenario: str, name: str | specs.Spec, oracle: str = DEFAULT_ENGINE
) -> str:
    """The fingerprint :func:`build_plan` gives the episodes of policy ``name`` (or its
    Spec) on the nominal plant of ``env_id`` under ``scenario`` (a name as ``--scenarios``
    takes it)."""
    return fingerprint(
        env_id,
        resolve_scenario(scenario, env_id),
        policy_digest(env_id, name, oracle),
        specs.source_digest(env_id),
    )


def _import_modules(ap: argparse.ArgumentParser, imports: tuple[str, ...]) -> tuple[str, ...]:
    """Import every ``--import`` module (first: they may register env ids, baselines and
    scenarios); any failure, SystemExit too, is a bad value."""
    for module in imports:
        try:
            importlib.import_module(module)
        except BaseException as exc:
            if not guard.own_failure(exc):  # Ctrl-C
                raise
            ap.error(
                f"argument --import: cannot import {head(module, 100)!r}: "
                f"{head(guard.describe(exc, 'the module'), EXCERPT)}"
            )
    return imports


def _number(ap: argparse.ArgumentParser, flag: str, value, ok, expected: str) -> float:
    """``value`` as a finite float that ``ok`` accepts, else an argparse error naming ``flag``."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = math.nan
    if not (math.isfinite(number) and ok(number)):
        ap.error(f"argument {flag}: must be {expected}, got {head(str(value), 60)!r}")
    return number


def build_plan(ap: argparse.ArgumentParser, args: argparse.Namespace) -> Plan:
    """Check every flag (argparse errors, exit code 2) and build the envs; runs nothing."""
    imports = _import_modules(ap, tuple(getattr(args, "modules", None) or ()))
    envs = items(ap, "--envs", args.envs, key=env_id_of)
    unknown = [e for e in envs if env_id_of(e) not in envs_.ids()]
    if unknown:
        ap.error(
            f"argument --envs: unknown {[head(e, 60) for e in unknown]}; "
            f"valid choices: {envs_.ids()} (the name after 'steamtemp/' is enough)"
        )
    envs = [env_id_of(e) for e in envs]
    seeds = parse_seeds(ap, args.seeds)
    budget = _number(
        ap,
        "--travel-budget",
        args.travel_budget,
        lambda v: v > 0.0,
        f"a finite number > 0 (a multiple of {summary.ZERO}'s valve travel)",
    )
    timeout = _number(
        ap,
        "--episode-timeout",
        getattr(args, "episode_timeout", str(EPISODE_TIMEOUT_S)),
        lambda v: v >= 0.0,
        "a number of seconds >= 0 (0: no limit)",
    )
    timeout = timeout or None
    pols, parsed = policies(
        ap, envs, args.policies, oracle=not args.no_oracle, imports=imports, timeout=timeout
    )
    scs = items(ap, "--scenarios", args.scenarios, key=_scenario_key)
    if args.out is None or str(args.out).strip() == "":
        ap.error("argument --out: empty path")
    _check_out(ap, Path(args.out), args.resume)
    resolved = {}
    for env_id in envs:  # cheap pass first: names and YAML files
        for sc in scs:
            try:
                resolved[env_id, sc] = resolve_scenario(sc, env_id)
            except Exception as exc:  # noqa: BLE001 - any failure is a bad --scenarios value
                ap.error(
                    f"argument --scenarios: {tail(sc, 80)!r} for {env_id}: "
                    f"{head(str(exc), 1000)}"  # the message lists every form
                )
    plan = Plan(
        envs=envs,
        scenarios=scs,
        seeds=seeds,
        policies=pols,
        resolved=resolved,
        imports=imports,
        travel_budget=budget,
        episode_timeout=timeout,
        oracle=getattr(args, "oracle", DEFAULT_ENGINE),
        parsed=parsed,
    )
    if not args.no_mismatch and mismatch.SCENARIO in scs:
        for env_id in envs:
            plan.variants[env_id] = mismatch.labels(env_id)
            for label in plan.variants[env_id]:
                resolved[env_id, label] = resolved[env_id, mismatch.SCENARIO]
    for env_id in envs:
        source = specs.source_digest(env_id)
        digests = {n: parsed[n].digest(env_id, plan.oracle) for n in pols[env_id]}  # per env
        for sc in scs:
            try:
                plan.envs_made[env_id, sc] = gym.make(env_id, scenario=resolved[env_id, sc])
            except Exception as exc:  # noqa: BLE001
                ap.error(
                    f"argument --scenarios: {tail(sc, 80)!r} for {env_id}: "
                    f"{type(exc).__name__}: {head(str(exc), EXCERPT)}"
                )
        for sc in plan.scenarios_of(env_id):
            params = plan.variants.get(env_id, {}).get(sc)
            for name in plan.policies_of(env_id, sc):
                plan.fingerprints[env_id, sc, name] = fingerprint(
                    env_id, resolved[env_id, sc], digests[name], source, params
                )
    return plan
