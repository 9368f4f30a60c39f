"""The lists of checks, binding them to a policy and an env, running them, and the pytest
decorator (scikit-learn's ``parametrize_with_checks`` is the model)."""

from __future__ import annotations

import time
import unittest
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import steamtemp_gym
from steamtemp_gym.testing import env_checks as ec
from steamtemp_gym.testing import guard
from steamtemp_gym.testing import policy_checks as pc
from steamtemp_gym.testing.subjects import resolve_env, resolve_policy, short_id
from steamtemp_gym.testing.vector_checks import check_vector_env_matches_single_env

#: Every env contract, in the order they run.
ENV_CHECKS: tuple[Callable[..., None], ...] = (
    ec.check_gymnasium_env,
    ec.check_sb3_env,
    ec.check_spaces_match_signals,
    ec.check_info_keys_and_units,
    ec.check_determinism,
    check_vector_env_matches_single_env,
    ec.check_pickle_and_deepcopy,
    ec.check_named_scenarios_run_to_end,
    ec.check_bad_inputs_rejected,
    ec.check_physical_under_random_and_corner_runs,
    ec.check_render_frame,
)
#: Every policy contract, in the order they run.
POLICY_CHECKS: tuple[Callable[..., None], ...] = (
    pc.check_predict_signature,
    pc.check_batched_equals_unbatched,
    pc.check_policy_determinism,
    pc.check_reset_clears_state,
    pc.check_actions_in_bounds,
    pc.check_bad_observations_rejected,
    pc.check_completes_a_scenario,
    pc.check_completes_every_scenario,
)
#: Checks too slow for the default test run and ``--quick`` (pytest marker ``slow``).
SLOW_CHECKS = frozenset({pc.check_completes_every_scenario})
CHECK_NAMES: tuple[str, ...] = tuple(c.__name__ for c in ENV_CHECKS + POLICY_CHECKS)


@dataclass(frozen=True)
class BoundCheck:
    """A check bound to a policy (for policy checks) and a mode: ``bound(env)`` runs it."""

    check: Callable[..., None]
    policy: Any = None
    quick: bool = False
    #: The check's own keyword arguments, e.g. (("scenario", "heldout:mill_trip"),).
    options: tuple[tuple[str, Any], ...] = ()

    @property
    def name(self) -> str:
        return self.check.__name__

    @property
    def label(self) -> str:
        """The name, with the check's own arguments: ``check_completes_a_scenario[random]``."""
        args = ",".join(str(v) for _, v in self.options)
        return f"{self.name}[{args}]" if args else self.name

    @property
    def slow(self) -> bool:
        return self.check in SLOW_CHECKS

    @property
    def policy_label(self) -> str | None:
        return None if self.policy is None else resolve_policy(self.policy).label

    def __call__(self, env: Any) -> None:
        kwargs = {"quick": True} if self.quick else {}
        kwargs.update(self.options)
        if self.policy is None:
            self.check(env, **kwargs)
        else:
            self.check(self.policy, env, **kwargs)

    def __repr__(self) -> str:
        return self.label if self.policy is None else f"{self.policy_label}-{self.label}"


def bound_checks(
    policies: Iterable[Any] = (),
    quick: bool = False,
    env: bool = True,
    only: Sequence[str] | None = None,
    scenarios: Sequence[Any] = (),
) -> list[BoundCheck]:
    """The env checks (if ``env``) then each policy's checks; ``only``: these names;
    ``scenarios``: the scenarios of ``check_completes_a_scenario`` (one check each; default
    its own, ``setpoint_step``)."""
    unknown = sorted(set(only or ()) - set(CHECK_NAMES))
    if unknown:
        raise ValueError(f"unknown check(s) {unknown}; valid names: {list(CHECK_NAMES)}")
    out = [BoundCheck(c, None, quick) for c in ENV_CHECKS] if env else []
    for p in policies:
        resolve_policy(p)  # a bad name fails here, listing the valid ones
        for c in POLICY_CHECKS:
            if c is pc.check_completes_a_scenario and scenarios:
                out += [BoundCheck(c, p, quick, (("scenario", s),)) for s in scenarios]
            else:
                out.append(BoundCheck(c, p, quick))
    return [b for b in out if only is None or b.name in only]


def parametrize_with_checks(
    ids: Iterable[Any] | None = None,
    policies: Iterable[Any] = (),
    env: bool = True,
    quick: bool = False,
):
    """A pytest decorator parametrizing a test ``(env_id, check)`` over every contract.

    ``ids``: env ids or factories (default :data:`steamtemp_gym.ENV_IDS`); ``policies``:
    baseline names or policy factories whose checks run on each id; ``env=False`` leaves
    out the env checks; ``quick=True`` shortens the runs and leaves out the slow checks.
    Test ids read ``SupercriticalFSH-v0-check_determinism`` and
    ``SupercriticalFSH-v0-cascade_pi-check_reset_clears_state``; slow checks carry the
    ``slow`` marker. Use::

        @parametrize_with_checks(ids=["my/FSH12-v0"], policies=["cascade_pi"])
        def test_contract(env_id, check):
            check(env_id)
    """
    import pytest

    params = []
    for env_id in steamtemp_gym.ENV_IDS if ids is None else ids:
        label = short_id(resolve_env(env_id).label)
        for b in bound_checks(policies, quick, env):
            if quick and b.slow:
                continue
            marks = [pytest.mark.slow] if b.slow else []
            params.append(pytest.param(env_id, b, id=f"{label}-{b!r}", marks=marks))
    return pytest.mark.parametrize(("env_id", "check"), params)


@dataclass(frozen=True)
class Result:
    """One check's outcome: ``status`` is "pass", "fail" or "skip"."""

    env: str
    policy: str | None
    check: str
    status: str
    seconds: float
    message: str = ""


def run(env: Any, check: BoundCheck, skip_slow: bool = False) -> Result:
    """Run one bound check on one env, catching its failure into a Result."""
    label = resolve_env(env).label
    if skip_slow and check.slow:
        return Result(
            label, check.policy_label, check.label, "skip", 0.0, "slow; run without --quick"
        )
    t0 = time.perf_counter()
    try:
        with guard.watch():  # the checked code's own KeyboardInterrupt fails the check
            check(env)
        status, msg = "pass", ""
    except unittest.SkipTest as exc:
        status, msg = "skip", str(exc)
    except AssertionError as exc:
        status, msg = "fail", str(exc)
    return Result(label, check.policy_label, check.label, status, time.perf_counter() - t0, msg)


def unchecked(results: Iterable[Result]) -> dict[str, list[str]]:
    """The subjects whose every check was skipped, with the reasons (each once): an env's
    env checks (``env checks of <id>``), a policy's checks over every env (``policy
    <label>``). A run that checked nothing of a subject has not checked it."""
    subjects: dict[str, list[Result]] = {}
    for r in results:
        key = f"env checks of {r.env}" if r.policy is None else f"policy {r.policy}"
        subjects.setdefault(key, []).append(r)
    return {
        key: list(dict.fromkeys(r.message or "no reason given" for r in rs))
        for key, rs in subjects.items()
        if all(r.status == "skip" for r in rs)
    }


def _raise_failures(results: list[Result]) -> list[Result]:
    failed = [r for r in results if r.status == "fail"]
    if failed:
        raise AssertionError(
            f"{len(failed)} of {len(results)} checks failed:\n"
            + "\n".join(r.message for r in failed)
        )
    return results


def check_env_id(env: Any, quick: bool = False) -> list[Result]:
    """Run every env check on ``env`` (an id or a factory); AssertionError listing every
    failure, else the results (skips included)."""
    return _raise_failures([run(env, b, skip_slow=quick) for b in bound_checks((), quick)])


def check_policy(policy: Any, env: Any, quick: bool = False) -> list[Result]:
    """Run every policy check of ``policy`` (a baseline name or a factory) on ``env``;
    AssertionError listing every failure, else the results."""
    checks = bound_checks([policy], quick, env=False)
    return _raise_failures([run(env, b, skip_slow=quick) for b in checks])
