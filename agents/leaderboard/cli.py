"""steamtemp-leaderboard: every policy on every env, scenario and seed.

Policies: by default the baselines (``baselines.NAMES``), the shipped trained agents
(``agents.shipped()``, named ``sb3:<algo>``) and two references that are listed but never
ranked: ``oracle`` (agents/oracle.py, the clairvoyant NMPC on the true plant, the 1 of
the normalized score; ``--no-oracle`` leaves it out, and the score with it) and
``frozen_valve``. The score's 0, ``cascade_pi_ff``, and the references join every run.
A shipped agent with several training runs in the zoo runs as one policy per run,
``sb3:<algo>@run<k>`` (``sb3:<algo>`` in ``--policies`` means all of them), and is
reported as one row over its runs (agents/leaderboard/summary.py).
Model mismatch: when ``load_ramp_100_50`` is among the scenarios, every policy but the
references is also commissioned on the nominal plant and run unchanged on each perturbed
variant of the plant (rows ``mismatch:<variant>``, agents/leaderboard/mismatch.py): the
robustness column, kept out of the scores; ``--no-mismatch`` leaves them out.
``--policies`` also takes your own (agents/specs.py; examples/README.md): a trained
agent's files (``zoo:DIR``, or a path: a directory or model .zip written by
``steamtemp-train --out`` or an RL Zoo run) and ``module:callable``, a factory
``env -> Policy`` (``module`` a dotted name, with ``PYTHONPATH=.`` for the current
directory, or a .py file), scored like the shipped ones. ``--import MODULE`` imports a
module first (one that calls ``baselines.register`` or ``scenarios.register``).

Every flag is checked before anything runs: env ids, policies, scenarios (names and YAML
paths, resolved and built for each env with ``gym.make``), seeds and the output directory.
A bad value is an argparse error (usage, the flag, the valid choices; exit code 2) and nothing is
written (no output directory is created).

Where: ``--jobs`` local worker processes (default), or ``--backend ray``: one Ray task
per env, scenario and policy, on a new local Ray with ``--jobs`` CPUs or on an existing
cluster (``--ray-address``; the ``ray`` extra). The rows are the same either way.

Lists (``--envs``, ``--policies``, ``--scenarios``, ``--seeds``) are comma
separated; blanks around items and empty items are ignored; duplicates are dropped
(first occurrence kept, a note on stderr). Seeds are integers >= 0, or inclusive
ranges ``a-b`` (``0-4`` = ``0,1,2,3,4``), at most 10,000 in all.

Outputs in ``--out``:

- ``episodes.jsonl``: the record. One JSON object per line, appended, flushed and
  synced as each episode finishes (a crash or Ctrl-C loses nothing): ``env``,
  ``scenario`` (as given), ``policy``, ``seed``, ``fingerprint`` (a hash of the
  configuration: schema version, env id, the resolved scenario, policy name, the
  source of steamtemp_gym, baselines and agents/evaluation.py, and a trained agent's
  file), ``metrics`` (steamtemp_gym.metrics plus ``return`` and ``tripped``; a metric
  that does not apply, e.g. settling time without a setpoint step, is ``null``) and,
  for a failed episode, ``metrics: null``, ``error`` and ``traceback``.
- ``leaderboard.json``: the rows of this run's grid (env x scenario x policy x seed,
  in that order), rebuilt from ``episodes.jsonl`` at the end: the last line of each
  episode with the current fingerprint, without ``traceback``.
- ``leaderboard.md``: means over seeds per env, scenario and policy; failed episodes
  are listed below the tables.
- ``plots/``: one trend plot per env and scenario (the first seed; cascade_pi_ff, the oracle,
  cascade_pi and the plant's three best-ranked policies, every policy with
  ``--trend-all``), the scores (``scores.png``) and performance profiles (``profiles.png``).

All JSON is strict (no NaN or Infinity tokens).

An episode that raises (a policy error, a plant failure) is recorded as a row with
an ``error`` and the run goes on: a long run is not lost to one bad policy. At the end
the failures are listed and the exit code is 1. A policy that is not shipped (a factory,
a trained agent's files, a registered baseline) runs in a process of its own, built by
its factory on an env of its own: its SystemExit, KeyboardInterrupt or a hang longer than
``--episode-timeout`` fails its episodes, and it cannot reach the env it is scored on
(docs/leaderboard.md, "Failures, timeouts and isolation").

Cost: the score's 1 is the clairvoyant optimum of each episode (agents/oracle.py). The
package stores it for every plant, named and held-out scenario and default seed
(agents/optima.py); the oracle replays a stored sequence on a copy of the row and takes it
where the replay gives the stored return bit for bit, so its episodes cost two rollouts.
An episode that is not stored (a YAML scenario, other seeds, a plant whose dynamics
changed) is solved in the run, about a minute of one core each, with a line on stderr
per episode; ``--oracle cem`` takes the receding-horizon search instead (a lower bound of
the 1, labelled so in every output).

``--resume`` continues in an existing ``--out``: episodes already in
``episodes.jsonl`` with the same env, scenario, policy, seed and fingerprint and no
error are skipped; failed ones and ones whose configuration changed run again; the
outputs are rebuilt. A last line cut off by a crash is dropped. Without
``--resume`` an existing non-empty ``episodes.jsonl`` is an error (pass
``--resume``, choose another ``--out``, or move the file aside). ``--resume`` on a
new directory is an ordinary run.

One run at a time writes to an ``--out``: a second run started on it while the first
goes on is an argparse error (a lock on the directory). SIGTERM (``timeout``, CI runners,
schedulers) stops a run as Ctrl-C does (exit code 143 instead of 130), and the worker
processes end with it; they also end within a second of their parent's death by SIGKILL.
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import os
import signal
import sys
import threading
import time
from pathlib import Path
from typing import Any

import steamtemp_gym
from agents import ray_backend, stats
from agents.leaderboard import report, sandbox
from agents.leaderboard.backends import execute
from agents.leaderboard.episodes import pending
from agents.leaderboard.isolated import OUT_ENV
from agents.leaderboard.outputs import Plots, rebuild
from agents.leaderboard.plan import (
    DEFAULT_SCENARIOS,
    DEFAULT_SEEDS,
    EPISODE_TIMEOUT_S,
    EXCERPT,
    build_plan,
)
from agents.leaderboard.records import EPISODES, Record, latest_rows, read_record
from agents.oracle import DEFAULT_ENGINE, ENGINES
from steamtemp_gym.checks import head
from steamtemp_gym.testing import guard

#: --out directories this process locked (resolved path -> descriptor)
_LOCKS: dict[str, int] = {}


def _lock_out(out: Path) -> int | None:
    """An exclusive lock on the directory ``out``, held until this process ends or runs
    again on it (a run in this process has ended by then), as its descriptor; None if
    another process holds it. No lock (-1) where there is no flock."""
    try:
        import fcntl
    except ImportError:  # not a POSIX system
        return -1
    key = os.path.realpath(out)
    if key in _LOCKS:
        os.close(_LOCKS.pop(key))
    fd = os.open(out, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        os.close(fd)
        return None
    _LOCKS[key] = fd
    return fd


class Terminated(KeyboardInterrupt):
    """SIGTERM (``timeout``, CI runners, schedulers): the run stops as on Ctrl-C."""


def _on_sigterm(signum: int, frame: Any) -> None:
    guard.stop_asked()
    raise Terminated


@contextlib.contextmanager
def _sigterm_stops():
    """SIGTERM raises :class:`Terminated` in this block (the handler before is restored)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    before = signal.signal(signal.SIGTERM, _on_sigterm)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, before)


def make_parser() -> argparse.ArgumentParser:
    """The CLI's argument parser."""
    doc = __doc__ or ""
    ap = argparse.ArgumentParser(
        prog="steamtemp-leaderboard",
        description=doc.split("\n")[0],
        epilog=doc.split("\n", 2)[2],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ap.add_argument(
        "--envs",
        default=",".join(steamtemp_gym.ENV_IDS),
        help="comma list of env ids, with or without the steamtemp/ namespace "
        "(default: all: %(default)s)",
    )
    ap.add_argument(
        "--policies",
        default=None,
        help="comma list of baseline names, sb3:<algo>, zoo:DIR or paths to a "
        "trained agent's files, and module:callable factories (default: every "
        "baseline of baselines.NAMES and every shipped agent sb3:<algo> of "
        "agents.shipped(); cascade_pi_ff, oracle and frozen_valve are always "
        "added)",
    )
    ap.add_argument(
        "--import",
        dest="modules",
        action="append",
        default=[],
        metavar="MODULE",
        help="import this module first, in every worker too (one that registers "
        "baselines, scenarios or env variants; repeatable)",
    )
    _add_scoring_arguments(ap)
    ap.add_argument(
        "--episode-timeout",
        default=f"{EPISODE_TIMEOUT_S:g}",
        metavar="S",
        help="a policy that is not shipped (a factory, a trained agent's files, a "
        "registered baseline) runs in a process of its own; an episode of it that "
        "takes longer than S seconds fails (rerun by --resume), and so does "
        "building it; 0: no limit (default: %(default)s, about 10 times the "
        "longest episode of a shipped policy)",
    )
    ap.add_argument(
        "--scenarios",
        default=",".join(DEFAULT_SCENARIOS),
        help="comma list of scenario names, heldout:<name>, random (the seeded "
        "training distribution) or YAML paths, as gym.make(..., scenario=...) "
        "takes them (default: %(default)s)",
    )
    ap.add_argument(
        "--seeds", default=DEFAULT_SEEDS, help="integers >= 0 or ranges a-b (default: %(default)s)"
    )
    ap.add_argument(
        "--out", default="leaderboard_out", help="output directory (default: %(default)s)"
    )
    ap.add_argument(
        "--trend-all",
        action="store_true",
        help="trend plots show every policy (default: cascade_pi_ff, the oracle, "
        "cascade_pi and the plant's three best-ranked policies)",
    )
    ap.add_argument(
        "--resume",
        action="store_true",
        help="continue in --out: skip the episodes already in its episodes.jsonl (default: off)",
    )
    _add_worker_arguments(ap)
    return ap


def _add_scoring_arguments(ap: argparse.ArgumentParser) -> None:
    """The options of what scores a policy: the oracle (the score's 1), the model-mismatch
    episodes and the travel budget of admissibility."""
    ap.add_argument(
        "--oracle",
        choices=ENGINES,
        default=DEFAULT_ENGINE,
        help="what makes the score's 1: 'optimum', the certified clairvoyant "
        "optimum of each episode (stored for the default scenarios and seeds, "
        "replayed; any other episode is solved, a few minutes of one core each), "
        "or 'cem', the receding-horizon CEM search (faster; a lower bound of "
        "the optimum, and every output says so) (default: %(default)s)",
    )
    ap.add_argument(
        "--no-oracle",
        action="store_true",
        help="leave the oracle out (its episodes are the run's longest); the "
        "normalized score is then not computed (default: off)",
    )
    ap.add_argument(
        "--no-mismatch",
        action="store_true",
        help="leave out the model-mismatch episodes (every policy but the "
        "references, commissioned on the nominal plant, on each variant of "
        "the model-mismatch set under load_ramp_100_50; run when load_ramp_100_50 is "
        "among --scenarios) and the robustness column (default: off)",
    )
    ap.add_argument(
        "--travel-budget",
        type=str,
        default=str(stats.TRAVEL_BUDGET),
        metavar="X",
        help="a policy is admissible on a plant when its mean valve "
        "travel there is at most X times cascade_pi_ff's and it never trips; "
        "rankings list admissible policies first (default: %(default)s)",
    )


def _add_worker_arguments(ap: argparse.ArgumentParser) -> None:
    """The options of where the episodes run: worker processes, a local pool or Ray."""
    ap.add_argument(
        "--jobs",
        type=int,
        default=os.cpu_count() or 1,
        help="worker processes (CPUs of a new local Ray); 1 runs in this "
        "process (default: the number of CPUs, %(default)s)",
    )
    ap.add_argument(
        "--backend",
        choices=("local", "ray"),
        default="local",
        help="local: a process pool; ray: one Ray task per env, scenario and "
        "policy (needs the ray extra: pip install 'steamtemp-gym[ray]'); rows "
        "are the same (default: %(default)s)",
    )
    ap.add_argument(
        "--ray-address",
        default=None,
        metavar="ADDRESS",
        help="with --backend ray: an existing Ray cluster (e.g. ray://host:10001 "
        "or auto); default: start a local Ray with --jobs CPUs",
    )


class _Stderr(logging.StreamHandler):
    """A handler writing to whatever ``sys.stderr`` is when a line is logged (a stream
    bound once would outlive a caller's redirection of stderr and write to a closed file)."""

    @property
    def stream(self):  # type: ignore[override]
        return sys.stderr

    @stream.setter
    def stream(self, value) -> None:
        pass


def show_library_log() -> None:
    """steamtemp_gym's INFO lines (e.g. the notice while kernels compile) on stderr."""
    log = logging.getLogger("steamtemp_gym")
    if not log.handlers:
        handler = _Stderr()
        handler.setFormatter(logging.Formatter("%(message)s"))  # lines name steamtemp_gym
        log.addHandler(handler)
    log.setLevel(logging.INFO)


def _say_what_walls_hold(plan: Any) -> None:
    """A note at the start of a run with a policy in a process of its own where the OS
    allows no namespaces (agents/leaderboard/sandbox.py): what does not hold then."""
    if not any(plan.spec(p).own_process for pols in plan.policies.values() for p in pols):
        return
    why = sandbox.available()
    if why:
        print(
            f"note: no sandbox for the policies that run in a process of their own ({why}): "
            "they run in a session of their own under a memory limit, but could signal "
            "this run and write its --out directory (docs/leaderboard.md, isolation)",
            file=sys.stderr,
        )


def main(argv: list[str] | None = None) -> None:
    """Run the leaderboard (see the module docstring)."""
    with guard.watch():  # a policy module's own KeyboardInterrupt is not a Ctrl-C
        _main(argv)


def _main(argv: list[str] | None) -> None:
    show_library_log()
    ap = make_parser()
    args = ap.parse_args(argv)
    if args.jobs < 1:
        ap.error(f"argument --jobs: must be >= 1, got {args.jobs}")
    if args.ray_address is not None and args.backend != "ray":
        ap.error("argument --ray-address: only with --backend ray")
    if args.backend == "ray" and not ray_backend.installed():
        ap.error(f"argument --backend: ray is not installed; {ray_backend.INSTALL}")
    os.environ[OUT_ENV] = str(Path(args.out).resolve())  # read-only to a policy's process
    plan = build_plan(ap, args)
    _say_what_walls_hold(plan)
    out = Path(args.out)
    try:
        out.mkdir(parents=True, exist_ok=True)
        lock = _lock_out(out)
    except OSError as exc:
        ap.error(f"argument --out: cannot write {str(out)!r}: {exc.strerror or exc}")
    if lock is None:
        ap.error(
            f"argument --out: {str(out)!r} is in use by another steamtemp-leaderboard "
            "run; wait for it to end or choose another --out"
        )
    try:
        done = latest_rows(read_record(out / EPISODES)) if args.resume else {}
    except (OSError, ValueError) as exc:
        ap.error(f"argument --resume: {head(str(exc), EXCERPT)}")
    try:
        record = Record(out / EPISODES)
    except OSError as exc:
        ap.error(f"argument --out: cannot write {str(out)!r}: {exc.strerror or exc}")
    t0 = time.time()
    units = pending(plan, done)
    figures = Plots(out, plan, units, every=args.trend_all)
    try:
        with _sigterm_stops():
            execute(plan, units, args.jobs, record, figures.add, args.backend, args.ray_address)
            for key in figures.missing():
                figures.draw(*key)
    except KeyboardInterrupt as exc:
        record.close()
        rebuild(out, plan, figures=False)
        print(
            f"\ninterrupted: finished episodes are in {out / EPISODES}; "
            "run the same command with --resume to continue",
            file=sys.stderr,
        )
        raise SystemExit(143 if isinstance(exc, Terminated) else 130) from None
    record.close()
    rows, summary = rebuild(out, plan)
    if summary is not None:
        print(report.console(summary))
    bad = [r for r in rows if r.get("error")]
    n_run = sum(len(u.seeds) for u in units)
    print(
        f"wrote {out / 'leaderboard.json'}, {out / 'leaderboard.md'} and plots/ "
        f"({len(rows)} episodes, {n_run} run now, {time.time() - t0:.0f} s)"
    )
    if bad:
        print(f"{len(bad)} of {len(rows)} episodes failed:", file=sys.stderr)
        for r in bad[:10]:
            print(
                f"  {r['env']} {r['scenario']} {r['policy']} seed {r['seed']}: {r['error']}",
                file=sys.stderr,
            )
        print(
            "fix the cause and run the same command with --resume to run only those again",
            file=sys.stderr,
        )
        raise SystemExit(1)
