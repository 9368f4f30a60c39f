"""``steamtemp-check``: run the contract checks outside pytest and print a pass/fail table.

    steamtemp-check                                  # every env check on every steamtemp id
    steamtemp-check steamtemp/SupercriticalFSH-v0 --quick
    steamtemp-check my/FSH12-v0 --import my_plants --policy cascade_pi --policy lqi
    steamtemp-check steamtemp/Cascade300MW-v0 --check check_determinism

Exit status 0 when every check passed or was skipped, 1 on any failure or when every check
of a subject (an env's env checks, a policy's checks) was skipped, 2 on bad arguments.

The command (:func:`console`) runs the checks in a child process and takes their status
from it: code under check that ends its process (``os._exit(0)`` in an imported module or
in ``predict``, a signal) fails the run, exit 1, instead of ending it with the code's own
status. :func:`main` runs them in the calling process.
"""

from __future__ import annotations

import argparse
import importlib
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence

import gymnasium as gym

import steamtemp_gym
from steamtemp_gym import policy_sources, scenarios
from steamtemp_gym.envs import resolve_id
from steamtemp_gym.testing import guard
from steamtemp_gym.testing.runner import CHECK_NAMES, Result, bound_checks, run, unchecked
from steamtemp_gym.testing.subjects import short_id


def make_parser() -> argparse.ArgumentParser:
    source = policy_sources.find()
    names = (
        "a policy factory module:callable (env -> Policy; module a dotted name or a .py "
        "file): no policy source is installed"
        if source is None
        else f"{source.FORMS}; 'all' for {', '.join(source.everyday_names())}"
    )
    p = argparse.ArgumentParser(
        prog="steamtemp-check",
        description="Check that env ids (plants, variants) and controllers honour every "
        "contract of steamtemp_gym (docs/checking.md). Prints one row per check and the "
        "message of each failure; exits 1 if any check fails.",
    )
    p.add_argument(
        "ids",
        nargs="*",
        metavar="ID",
        help="env ids to check, with or without the steamtemp/ namespace (default: "
        "every steamtemp id, steamtemp_gym.ENV_IDS)",
    )
    p.add_argument(
        "--policy",
        action="append",
        default=[],
        metavar="NAME",
        help="also run the policy checks of this policy on each id (repeatable): " + names,
    )
    p.add_argument(
        "--scenario",
        action="append",
        default=[],
        metavar="SCENARIO",
        help="run check_completes_a_scenario under this scenario instead of "
        "setpoint_step (repeatable): a scenario name, heldout:<name>, random or a "
        "YAML path, as gym.make(..., scenario=...) and steamtemp-leaderboard "
        "--scenarios take them",
    )
    p.add_argument(
        "--quick",
        action="store_true",
        help="shorter runs, slow checks skipped (about 10-20 s per id from a warm kernel cache)",
    )
    p.add_argument(
        "--check",
        action="append",
        default=None,
        metavar="NAME",
        help="run only this check (repeatable): one of " + ", ".join(CHECK_NAMES),
    )
    p.add_argument(
        "--no-env-checks", action="store_true", help="only the policy checks of --policy"
    )
    p.add_argument(
        "--import",
        dest="modules",
        action="append",
        default=[],
        metavar="MODULE",
        help="import this module first (one that registers your variants)",
    )
    return p


def _table(results: list[Result]) -> str:
    rows = [("env", "policy", "check", "result", "s")]
    rows += [
        (short_id(r.env), r.policy or "-", r.check, r.status.upper(), f"{r.seconds:.1f}")
        for r in results
    ]
    widths = [max(len(row[i]) for row in rows) for i in range(5)]
    return "\n".join(
        "  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)).rstrip() for row in rows
    )


def _env_id(parser: argparse.ArgumentParser, name: str) -> str:
    """The registered id of an ID argument (the namespace may be left out)."""
    try:
        return resolve_id(name)
    except ValueError as exc:
        parser.error(f"{exc}; register a variant and pass --import MODULE")


def _check_scenarios(parser: argparse.ArgumentParser, specs: list[str], ids: list[str]) -> None:
    """Every --scenario resolves for every id's plant (steamtemp_gym.scenarios.resolve)."""
    for spec in specs:
        for env_id in ids:
            try:
                scenarios.resolve(spec, gym.spec(env_id).kwargs.get("plant_id", env_id))
            except ValueError as exc:
                parser.error(f"--scenario {spec!r} for {env_id}: {exc}")


def _check_policies(parser: argparse.ArgumentParser, policies: list[str], ids: list[str]) -> None:
    """Every --policy parses (the installed policy source, steamtemp_gym/policy_sources.py);
    a factory's policy is built on the first id and must have predict and reset."""
    for name in policies:
        try:
            spec = policy_sources.parse(name)
        except ValueError as exc:
            parser.error(f"--policy: {exc} (or 'all')")
        if spec.is_factory:
            env_id = (ids or steamtemp_gym.ENV_IDS)[0]
            try:
                spec.make(env_id, gym.make(env_id))
            except BaseException as exc:  # any failure is a bad --policy value; SystemExit too
                if not guard.own_failure(exc):
                    raise
                parser.error(f"--policy {name}: on {env_id}: {guard.describe(exc, 'the factory')}")


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``steamtemp-check``; returns the exit status. A check's code (the
    policy's, the env's) that raises ``SystemExit`` or ``KeyboardInterrupt`` fails that
    check; Ctrl-C stops the run."""
    with guard.watch():
        return _main(argv)


def _main(argv: Sequence[str] | None) -> int:
    parser = make_parser()
    args = parser.parse_args(argv)
    for module in args.modules:
        try:
            importlib.import_module(module)
        except ImportError as exc:
            parser.error(f"--import {module}: {exc}")
        except BaseException as exc:  # the module's own failure, SystemExit included
            if not guard.own_failure(exc):
                raise
            parser.error(f"--import {module}: {guard.describe(exc, 'the module')}")
    args.ids = [_env_id(parser, i) for i in args.ids]
    policies = args.policy
    if "all" in policies:
        source = policy_sources.find()
        if source is None:
            parser.error("--policy all: no policy source is installed")
        policies = source.everyday_names()
    _check_policies(parser, policies, args.ids)
    bad = [c for c in args.check or () if c not in CHECK_NAMES]
    if bad:
        parser.error(f"unknown check {bad}; valid: {', '.join(CHECK_NAMES)}")

    ids = args.ids or list(steamtemp_gym.ENV_IDS)
    _check_scenarios(parser, args.scenario, ids)
    checks = bound_checks(
        policies, args.quick, env=not args.no_env_checks, only=args.check, scenarios=args.scenario
    )
    if not checks:
        parser.error(
            "nothing to check: --no-env-checks leaves the env's checks out and no "
            "--policy (or --check) selects a policy's; drop --no-env-checks or "
            "name a policy"
        )
    t0, results = time.perf_counter(), []
    for env_id in ids:
        for check in checks:
            results.append(run(env_id, check, skip_slow=args.quick))
            print(_table(results[-1:]).splitlines()[-1], file=sys.stderr, flush=True)
    print(_table(results))
    failed = [r for r in results if r.status == "fail"]
    for r in failed:
        print(f"\nFAIL {r.check} on {r.env}" + (f" / {r.policy}" if r.policy else ""))
        print("  " + r.message.replace("\n", "\n  "))
    nothing = unchecked(results)
    for subject, reasons in nothing.items():
        print(f"\nNOT CHECKED {subject}: every check was skipped")
        print("  " + "\n  ".join(reasons))
    counts = {s: sum(r.status == s for r in results) for s in ("pass", "fail", "skip")}
    print(
        f"\n{counts['pass']} passed, {counts['fail']} failed, {counts['skip']} skipped "
        f"in {time.perf_counter() - t0:.1f} s"
        + (f"; {len(nothing)} subject(s) not checked at all" if nothing else "")
    )
    return 1 if failed or nothing else 0


#: Set in the child process that :func:`console` starts: the file its exit status goes to.
STATUS_ENV = "STEAMTEMP_CHECK_STATUS"


def console() -> None:
    """Entry point of the ``steamtemp-check`` command: :func:`main` in a child process, whose
    exit status counts only when it wrote it at its end; a child that ended otherwise (the
    code under check ended its process) fails the run with exit status 1."""
    status_file = os.environ.get(STATUS_ENV)
    if status_file:  # the child
        code: int | str | None = 1
        try:
            code = main()
        except SystemExit as exc:  # argparse's exit 2, --help's 0
            code = exc.code
            raise
        finally:
            with open(status_file, "w") as f:
                f.write(str(code if isinstance(code, int) else 0 if code is None else 1))
        sys.exit(code)
    with tempfile.TemporaryDirectory(prefix="steamtemp-check-") as tmp:
        status_file = os.path.join(tmp, "status")
        # as the command's own process: the working directory is not put on sys.path
        start = "import sys; sys.path.pop(0); import steamtemp_gym.testing.cli as c; c.console()"
        argv = [sys.executable, "-c", start, *sys.argv[1:]]
        try:
            child = subprocess.run(argv, env={**os.environ, STATUS_ENV: status_file})
        except KeyboardInterrupt:  # the child got Ctrl-C too
            sys.exit(130)
        written = open(status_file).read() if os.path.exists(status_file) else ""
    if written.isdigit():
        sys.exit(int(written))
    print(
        f"steamtemp-check: the process running the checks ended before they finished (exit "
        f"status {child.returncode}): code under check ended it (os._exit, a signal). "
        "That fails the run.",
        file=sys.stderr,
    )
    sys.exit(1)


if __name__ == "__main__":
    console()
