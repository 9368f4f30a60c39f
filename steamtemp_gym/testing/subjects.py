"""What a check runs on (a registered env id or an env factory; a baseline name or a policy
factory) and how a failure is reported (what failed, where, and the line that reproduces it).
"""

from __future__ import annotations

import functools
import unittest
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
from gymnasium.vector import SyncVectorEnv

from steamtemp_gym import policy_sources
from steamtemp_gym.envs import ids, resolve_id
from steamtemp_gym.testing import guard


class CheckSkipped(unittest.SkipTest):
    """A check that cannot run here (a missing optional library, a factory without a native
    vector env). pytest reports it as skipped; ``steamtemp-check`` as ``skip``."""


def steamtemp_ids() -> list[str]:
    """Every registered id built by SteamTempEnv: the suite's ids and registered variants."""
    return ids()


def short_id(env_id: str) -> str:
    """``SupercriticalFSH-v0`` for ``steamtemp/SupercriticalFSH-v0`` (readable test ids)."""
    return env_id.split("/", 1)[-1]


@dataclass(frozen=True)
class EnvTarget:
    """An env under check: a registered id, or a factory ``make(**options) -> Env`` taking
    the options of ``gym.make`` (``scenario``, ``render_mode``, ``reward``, ``params``)."""

    label: str
    env_id: str | None
    factory: Callable[..., gym.Env] | None

    def make(self, **options: Any) -> gym.Env:
        """A single env with ``options``."""
        if self.env_id is not None:
            return gym.make(self.env_id, **options)
        return self.factory(**options)

    @property
    def has_native_vector_env(self) -> bool:
        return self.env_id is not None and gym.spec(self.env_id).vector_entry_point is not None

    def make_vec(self, num_envs: int, **options: Any) -> gym.vector.VectorEnv:
        """The native vector env of an id; Gymnasium's SyncVectorEnv over a factory's envs."""
        if self.has_native_vector_env:
            return gym.make_vec(
                self.env_id, num_envs=num_envs, vectorization_mode="vector_entry_point", **options
            )
        return SyncVectorEnv([functools.partial(self.make, **options)] * num_envs)

    def repro(self) -> str:
        """How to name this env in a reproducing call."""
        return repr(self.env_id) if self.env_id is not None else "<your env factory>"


def resolve_env(env: str | Callable[..., gym.Env] | EnvTarget) -> EnvTarget:
    """An EnvTarget of an id or a factory; ValueError listing the registered ids otherwise."""
    if isinstance(env, EnvTarget):
        return env
    if isinstance(env, str):
        env_id = resolve_id(env)  # also the name without the namespace
        return EnvTarget(env_id, env_id, None)
    if callable(env):
        return EnvTarget(getattr(env, "__name__", repr(env)), None, env)
    raise ValueError(f"env must be a registered id or an env factory, got {env!r}")


@dataclass(frozen=True)
class PolicyTarget:
    """A policy under check: a policy name (steamtemp_gym/policy_sources.py) or a factory
    ``make(env) -> Policy`` (env: a single or a vector env)."""

    label: str
    name: str | None
    factory: Callable[[Any], Any]

    def make(self, env: Any) -> Any:
        return self.factory(env)

    def repro(self) -> str:
        return repr(self.name) if self.name is not None else "<your policy factory>"


def resolve_policy(policy: str | Callable[[Any], Any] | PolicyTarget) -> PolicyTarget:
    """A PolicyTarget of a policy name or a factory (ValueError listing the names otherwise).

    Names are looked up in the installed policy source (steamtemp_gym/policy_sources.py;
    steamtemp-gym's own takes the names of ``steamtemp-leaderboard --policies``: a baseline
    name, a shipped trained agent ``sb3:<algo>`` (the plant's own), ``zoo:DIR`` or a path
    to a trained agent's files, or ``module:callable``). A name not available for an env's
    plant (an agent trained on another plant) skips the checks there."""
    if isinstance(policy, PolicyTarget):
        return policy
    if isinstance(policy, str):
        policy_sources.parse(policy)  # a bad name fails here, listing every form
        return PolicyTarget(policy, policy, functools.partial(_make_named, policy))
    if callable(policy):
        return PolicyTarget(getattr(policy, "__name__", repr(policy)), None, policy)
    raise ValueError(f"policy must be a policy name or a policy factory, got {policy!r}")


def _make_named(name: str, env: Any) -> Any:
    """The policy ``name`` for the env: for its registered id, else for its plant's (a
    variant's base); CheckSkipped where it is available for neither."""
    spec = policy_sources.parse(name)
    u = env.unwrapped
    ids = [i for i in (getattr(getattr(u, "spec", None), "id", None), u.plant.id) if i]
    env_id = next((i for i in ids if spec.available(i)), None)
    if env_id is None:
        raise CheckSkipped(
            f"{name} is not available for {ids[0]} (only for {sorted(spec.envs or ())})"
        )
    try:
        return spec.make(env_id, env)
    except ImportError as exc:
        if not spec.needs_extra:
            raise
        raise CheckSkipped(f"{name} needs the agents extra ({exc})") from exc


def _failure(check: str, subject: str, call: str, exc: BaseException) -> AssertionError:
    what = str(exc) if isinstance(exc, AssertionError) else guard.describe(exc)
    return AssertionError(
        f"{check} failed on {subject}: {what}\n"
        f"  reproduce: from steamtemp_gym.testing import {check}; {check}({call})"
    )


def _quick_arg(kwargs: dict[str, Any]) -> str:
    """The keyword arguments of a reproducing call (``quick`` and a check's own)."""
    out = ", quick=True" if kwargs.get("quick") else ""
    return out + "".join(f", {k}={v!r}" for k, v in kwargs.items() if k != "quick")


def env_check(fn: Callable[..., None]) -> Callable[..., None]:
    """Make ``fn(target: EnvTarget, quick=False)`` an env check taking an id or a factory
    whose AssertionError names the check, the env and the call that reproduces it."""

    @functools.wraps(fn)
    def check(env: str | Callable[..., gym.Env] | EnvTarget, **kwargs: Any) -> None:
        target = resolve_env(env)
        try:
            fn(target, **kwargs)
        except unittest.SkipTest:
            raise
        except BaseException as exc:  # an error inside a check is a failed contract
            if not guard.own_failure(exc):  # Ctrl-C: stop
                raise
            call = target.repro() + _quick_arg(kwargs)
            raise _failure(fn.__name__, target.label, call, exc) from exc

    check.kind = "env"
    return check


def policy_check(fn: Callable[..., None]) -> Callable[..., None]:
    """Make ``fn(policy: PolicyTarget, env: EnvTarget, quick=False)`` a policy check taking
    (name or factory, id or factory), reporting failures as :func:`env_check` does."""

    @functools.wraps(fn)
    def check(policy: Any, env: Any, **kwargs: Any) -> None:
        p, target = resolve_policy(policy), resolve_env(env)
        try:
            fn(p, target, **kwargs)
        except unittest.SkipTest:
            raise
        except BaseException as exc:  # SystemExit, KeyboardInterrupt of the policy included
            if not guard.own_failure(exc):  # Ctrl-C: stop
                raise
            call = f"{p.repro()}, {target.repro()}{_quick_arg(kwargs)}"
            raise _failure(fn.__name__, f"{p.label} on {target.label}", call, exc) from exc

    check.kind = "policy"
    return check
