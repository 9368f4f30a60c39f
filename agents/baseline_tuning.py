"""Tune the baselines on equal terms: one search, one budget, one objective for all.

``python -m agents.baseline_tuning [NAME ...] [--env ID ...]`` tunes each tunable baseline
(a controller class with ``KNOBS``, baselines/tuning.py) on each env and writes
``baselines/tuned/<name>.json``; with no NAME it tunes every one of :data:`TUNABLE`.

Every controller gets the same terms:

- **Training episodes**: :data:`EPISODES` episodes of the ``random`` training distribution
  (the one the agents train on), seeds ``TUNING_SEED + k``. No named or held-out
  scenario is ever seen.
- **Objective**: the leaderboard's normalized score, averaged over those episodes, with
  the leaderboard's ends: 0 = ``cascade_pi_ff``'s return, 1 = the oracle's, on the same
  episodes (:func:`ends`, computed once per env and stored in ``baselines/tuned/ends.json``).
- **Constraints**: no trip, and a mean valve travel of at most
  :data:`TUNING_TRAVEL_BUDGET` times ``cascade_pi_ff``'s on the same episodes (the
  leaderboard's budget :data:`TRAVEL_BUDGET` less a margin for unseen scenarios); the
  robustness check (:func:`agents.tuning_terms.robustness`: on the plants at the corners of
  the documented parameter ranges less a margin, on training episodes and on both
  commissioning checks, a cost at most :data:`ROBUST_COST_MAX` times that on the nominal
  plant in the same episode, and in the checks no trip, limit cycle or travel beyond the
  realism bound); and the commissioning checks at the two ends
  of the load range (:data:`COMMISSIONING_CHECKS`, episodes held at each of
  :data:`CHECK_LOADS` with a setpoint and a heat-absorption step, one per seed of
  :data:`CHECK_SEEDS`): in every one no trip, no limit cycle
  and a valve travel within ``stats.REALISM_TRAVEL_MAX`` times the reference's on that
  episode (:func:`agents.stats.realism_breach`), as a unit is commissioned with step tests
  over its whole load range. The training episodes move the load all the time, so they
  have no quiet stretch in which a limit cycle would show; the checks have one. A
  candidate that breaks the constraints ranks below every one that keeps them, by how far
  it breaks them (so a start outside them is walked in). The checks run on the start and
  on every candidate that would otherwise be accepted: one that does not improve the
  objective cannot be accepted whatever the checks say, so the search is the same as
  checking all. The robustness check runs the same way, after the commissioning checks
  pass.
- **Search**: a deterministic compass search on the unit cube of the knobs (log or
  linear, :class:`baselines.tuning.Knob`) from the controller's defaults: each round tries
  +- the step along every knob in turn, moves to the first candidate that improves the
  objective, and halves the step when none does, from :data:`STEP0` down to
  :data:`MIN_STEP`.
- **Budget**: :data:`EVALUATIONS` evaluations (each one batch of the training episodes)
  per controller and env, the start included.

Cost: a batch of :data:`EPISODES` one-hour episodes takes 1-10 s for the classical loops
and up to about a minute for the MPCs on one core, so a controller takes minutes to an hour
per env; the ends (the oracle's episodes) take a few minutes per env the first time.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

import baselines
import steamtemp_gym
from agents import stats
from agents.tuning_terms import (
    CHECK_LOADS,
    CHECK_SEEDS,
    EPISODES,
    ROBUST_COST_MAX,
    ROBUST_EPISODES,
    ROBUST_MARGIN,
    TRAVEL_BUDGET,
    TUNING_SEED,
    TUNING_TRAVEL_BUDGET,
    ZERO,
    check_breach,
    check_metrics,
    code_digest,
    corner_check_metrics,
    ends,
    robustness,
    run_episodes,
    seeds,
)
from baselines import tuning

#: The baselines with knobs, tuned by default.
TUNABLE = (
    "cascade_pi",
    "cascade_pi_ff",
    "fuzzy_p2id",
    "mpc_linear",
    "lqi",
    "fao_sf",
    "fao_fac",
    "neuro_pid_mee",
    "neuro_pid_mse",
    "mpc_evarx",
    "mpc_arx",
)
EVALUATIONS = 48
STEP0 = 0.25
MIN_STEP = 1.0 / 64.0


@dataclass(frozen=True)
class Evaluation:
    """One candidate's result on the training episodes and, once run, the commissioning
    checks (``check``: None if not run, "" if passed, else what broke;
    ``check_travel_ratio``: the largest valve-travel ratio to the reference's over them)
    and the robustness check (``robust_ratio``: the worst corner plant's cost over the
    nominal's in the same episode, NaN if not run; ``robust_breach``: what broke in the
    commissioning checks on the corner plants, "" if nothing)."""

    knobs: dict[str, float]
    score: float  # mean normalized score
    travel_ratio: float  # mean travel / the reference's
    trips: int
    check: str | None = None
    check_travel_ratio: float = float("nan")
    robust_ratio: float = float("nan")
    robust_breach: str = ""
    mean_return: float = float("nan")  # on the training episodes (NaN where replayed)

    @property
    def robust_excess(self) -> float:
        """How far the robustness check's ratio exceeds its bound (0 if kept or not run)."""
        r = self.robust_ratio
        return max(r - ROBUST_COST_MAX, 0.0) if r == r else 0.0

    @property
    def feasible(self) -> bool:
        return (
            self.trips == 0
            and self.travel_ratio <= TUNING_TRAVEL_BUDGET
            and not self.check
            and self.robust_excess == 0.0
            and not self.robust_breach
        )

    @property
    def merit(self) -> float:
        """The search's objective: the score if feasible, else below every feasible one: by
        trips and travel above the bound, then a broken commissioning check below every
        candidate that passed it, and a robustness check not kept by how far it is above
        its bound (plus 1 for a broken check on a corner plant). Never raised by running
        the checks, so a candidate is judged before it is checked."""
        if self.feasible:
            return self.score
        base = -1e6 - self.trips - max(self.travel_ratio - TUNING_TRAVEL_BUDGET, 0.0)
        if self.check:
            return base - 1e3
        return base - min(self.robust_excess + (1.0 if self.robust_breach else 0.0), 100.0)


def evaluate(name: str, env_id: str, values: dict[str, float], e: dict[str, Any]) -> Evaluation:
    """Score controller ``name`` with knob ``values`` on the training episodes of ``env_id``
    against the ends ``e``."""
    r = run_episodes(env_id, lambda v: baselines.make(name, v, **values))
    score = np.mean(
        [stats.normalize(x, z, o) for x, z, o in zip(r["return"], e["zero"], e["one"], strict=True)]
    )
    return Evaluation(
        dict(values),
        float(score),
        float(r["travel"].mean() / e["travel"]),
        int(r["tripped"].sum()),
        mean_return=float(r["return"].mean()),
    )


def defaults(factory: Any, env_id: str) -> dict[str, float]:
    """The knobs' start values: the class's ``knob_defaults(env_id)`` if it has one, else
    each knob's geometric (log) or arithmetic midpoint clipped into its box."""
    ks = tuning.knobs(factory)
    given = factory.knob_defaults(env_id) if hasattr(factory, "knob_defaults") else {}
    return {k.name: float(given[k.name]) if k.name in given else k.from_unit(0.5) for k in ks}


def alternatives(factory: Any, env_id: str) -> list[dict[str, float]]:
    """Further starts of the search the class declares (``knob_alternatives(env_id)``: knob
    values over the defaults, e.g. a robust design), judged like the start."""
    return list(factory.knob_alternatives(env_id)) if hasattr(factory, "knob_alternatives") else []


def compass(
    x0: np.ndarray,
    evaluate_at: Any,
    budget: int = EVALUATIONS,
    step0: float = STEP0,
    min_step: float = MIN_STEP,
    confirm: Any = None,
    first: Any = None,
) -> list[tuple[np.ndarray, Any]]:
    """Deterministic compass search on the unit cube (module docstring).

    Args:
        x0: Start, in unit coordinates.
        evaluate_at: ``u -> result`` with a ``merit`` attribute (higher is better).
        budget: Evaluations in all, the start's included.
        confirm: ``(u, result) -> result``, a further check run on the start and on a
            candidate only when its merit beats the best's; it may lower the merit, never
            raise it (None: no check).
        first: The start's result if already judged (evaluated and confirmed).

    Returns:
        Every (point, result) evaluated, in order; the best is the last accepted move.
    """
    confirm = confirm or (lambda u, r: r)
    x = np.asarray(x0, dtype=float)
    best = confirm(x, evaluate_at(x)) if first is None else first
    history = [(x, best)]
    step = step0
    while len(history) < budget and step >= min_step:
        moved = False
        for i in range(len(x)):
            for sign in (1.0, -1.0):
                u = x.copy()
                u[i] = min(max(u[i] + sign * step, 0.0), 1.0)
                if u[i] == x[i] or len(history) >= budget:
                    continue
                cand = evaluate_at(u)
                if cand.merit > best.merit:
                    cand = confirm(u, cand)
                history.append((u, cand))
                if cand.merit > best.merit:
                    best, x, moved = cand, u, True
                    break
            if moved:
                break
        if not moved:
            step /= 2.0
    return history


def best_of(history: list[tuple[np.ndarray, Any]]) -> Any:
    """The result with the highest merit (the first of equals) among those the search
    judged in full (an :class:`Evaluation` whose check ran)."""
    judged = [r for _, r in history if getattr(r, "check", "") is not None]
    return max(judged, key=lambda r: r.merit)


def search(
    name: str, env_id: str, log: Any = None, replay: list[dict[str, Any]] | None = None
) -> dict[str, Any]:
    """Compass search of controller ``name``'s knobs on ``env_id`` (module docstring).

    ``replay``: the ``history`` of an earlier search of the same controller and env. Where
    the search meets knobs evaluated there, their result on the training episodes is taken
    from it instead of run again (the commissioning checks always run). Valid while the
    training episodes' dynamics are unchanged: the start is evaluated again and must give
    the stored result bit for bit, else nothing is replayed.
    """
    factory = baselines.factory(name)
    ks = tuning.knobs(factory)
    if not ks:
        raise ValueError(f"baseline {name!r} has no KNOBS to tune")
    e = ends(env_id)
    start = defaults(factory, env_id)
    x0 = np.array([k.to_unit(start[k.name]) for k in ks])
    stored = {knobs_key(r["knobs"]): r for r in replay or ()}
    replayed = 0
    confirm = _confirmer(name, env_id, log)

    def evaluate_at(u: np.ndarray) -> Evaluation:
        nonlocal replayed
        if np.array_equal(u, x0):
            values = dict(start)  # the start exactly
        else:
            values = {k.name: k.from_unit(ui) for k, ui in zip(ks, u, strict=True)}
        r = None if np.array_equal(u, x0) else stored.get(knobs_key(values))
        if r is not None:
            replayed += 1
            return Evaluation(dict(values), r["score"], r["travel_ratio"], r["trips"])
        res = evaluate(name, env_id, values, e)
        if np.array_equal(u, x0) and stored:
            r = stored.get(knobs_key(values))
            got = (res.score, res.travel_ratio, res.trips)
            same = r is not None and (r["score"], r["travel_ratio"], r["trips"]) == got
            if not same:
                stored.clear()
            if log:
                log(f"{name} {env_id}: replay {'valid' if same else 'refused: start differs'}")
        if log:
            log(
                f"{name} {env_id}: score {res.score:.4f} travel x{res.travel_ratio:.2f} "
                f"trips {res.trips}"
            )
        return res

    # the controller's alternative starts (a robust design), each judged in full; the
    # search begins at the best of them and the defaults
    pre = [(x0, confirm(x0, evaluate_at(x0)))]
    for alt in alternatives(factory, env_id):
        u = np.array([k.to_unit({**start, **alt}[k.name]) for k in ks])
        pre.append((u, confirm(u, evaluate_at(u))))
    i = max(range(len(pre)), key=lambda j: pre[j][1].merit)
    walk = compass(
        pre[i][0], evaluate_at, budget=EVALUATIONS - len(pre) + 1, confirm=confirm, first=pre[i][1]
    )
    history = pre + walk[1:]  # the defaults first
    return _search_result(history, replayed)


def _search_result(history: list[tuple[np.ndarray, Evaluation]], replayed: int) -> dict[str, Any]:
    """A search's result as stored: the best evaluation's knobs, results and checks, the
    evaluations made and replayed, the start's results and every evaluation in order."""
    best = best_of(history)
    start = history[0][1]
    return {
        "knobs": best.knobs,
        "score": best.score,
        "travel_ratio": best.travel_ratio,
        "trips": best.trips,
        "feasible": best.feasible,
        "evaluations": len(history),
        "replayed": replayed,
        "check_travel_ratio": _finite(best.check_travel_ratio),
        "robust_ratio": _finite(best.robust_ratio),
        "robust_breach": best.robust_breach,
        "start": {
            **{k: v for k, v in start.__dict__.items() if k != "mean_return"},
            "check_travel_ratio": _finite(start.check_travel_ratio),
            "robust_ratio": _finite(start.robust_ratio),
        },
        "history": [_row(r) for _, r in history],
    }


def _confirmer(name: str, env_id: str, log: Any) -> Any:
    """:func:`compass`'s ``confirm`` for controller ``name`` on ``env_id``: the commissioning
    checks against the reference's and, once they pass, the robustness check."""
    refs = check_metrics(env_id, lambda env: baselines.make(ZERO, env))
    corner_refs = corner_check_metrics(env_id, lambda env: baselines.make(ZERO, env))[1]

    def confirm(u: np.ndarray, res: Evaluation) -> Evaluation:
        ms = check_metrics(env_id, lambda env: baselines.make(name, env, **res.knobs))
        breach, ratio = check_breach(ms, refs)
        if log:
            log(f"{name} {env_id}: commissioning checks {breach or 'passed'}")
        res = replace(res, check=breach, check_travel_ratio=ratio)
        if breach:
            return res
        robust, breach = robustness(
            env_id, lambda env: baselines.make(name, env, **res.knobs), corner_refs
        )
        if log:
            log(
                f"{name} {env_id}: robustness: worst corner plant's cost x{robust:.2f} the "
                f"nominal's{'; ' + breach if breach else ''}"
            )
        return replace(res, robust_ratio=robust, robust_breach=breach)

    return confirm


def knobs_key(knobs: dict[str, float]) -> tuple[tuple[str, float], ...]:
    """A knob setting as the key of its stored row: names and values, sorted."""
    return tuple(sorted((k, float(v)) for k, v in knobs.items()))


def _finite(v: float) -> float | None:
    """A ratio as stored: None where it was not measured (NaN), so the file is strict JSON."""
    return None if v != v else v


def _row(r: Evaluation) -> dict[str, Any]:
    """One evaluation as stored: its knobs, score, travel ratio, trips and checks."""
    return {
        "knobs": r.knobs,
        "score": r.score,
        "travel_ratio": r.travel_ratio,
        "trips": r.trips,
        "check": r.check,
        "robust_ratio": _finite(r.robust_ratio),
        "robust_breach": r.robust_breach,
    }


def write(name: str, env_ids: list[str], log: Any = None, replay: bool = False) -> dict[str, Any]:
    """Tune ``name`` on ``env_ids`` and merge the results into its stored file (``replay``:
    reuse the stored search's evaluations on the training episodes, :func:`search`)."""
    f = tuning.path(name)
    data = json.loads(f.read_text()) if f.is_file() else {"controller": name, "plants": {}}
    for env_id in env_ids:
        t0 = time.perf_counter()
        old = data["plants"].get(env_id, {}).get("history") if replay else None
        res = search(name, env_id, log, replay=old)
        res["seconds"] = round(time.perf_counter() - t0, 1)
        res["code"] = code_digest(env_id, name)
        data["plants"][env_id] = res
        data["terms"] = {
            "episodes": EPISODES,
            "tuning_seed": TUNING_SEED,
            "evaluations": EVALUATIONS,
            "step0": STEP0,
            "min_step": MIN_STEP,
            "travel_budget": TUNING_TRAVEL_BUDGET,
            "admissibility_budget": TRAVEL_BUDGET,
            "reference": ZERO,
            "robustness": {
                "plants": "corners of the parameter ranges",
                "episodes": ROBUST_EPISODES,
                "margin": ROBUST_MARGIN,
                "cost_max": ROBUST_COST_MAX,
            },
            "commissioning_checks": {
                "loads": list(CHECK_LOADS),
                "seeds": list(CHECK_SEEDS),
                "travel_max": stats.REALISM_TRAVEL_MAX,
            },
        }
        data.pop("code", None)  # per plant since the provenance digests are scoped
        tuning.TUNED.mkdir(exist_ok=True)
        f.write_text(json.dumps(data, indent=1, sort_keys=True) + "\n")  # after every env
    return data


def markdown(names: tuple[str, ...] = TUNABLE) -> str:
    """The stored tunings as a markdown table: per controller and env, the training score and
    travel ratio at the start and at the result, evaluations used, and the knobs."""
    lines = [
        "| controller | plant | start: score, travel | tuned: score, travel, worst corner's "
        "cost | evaluations | knobs |",
        "|---|---|---|---|---|---|",
    ]
    for name in names:
        f = tuning.path(name)
        if not f.is_file():
            continue
        for env_id, r in json.loads(f.read_text())["plants"].items():
            st = r["start"]
            knobs = ", ".join(f"{k} {v:.3g}" for k, v in sorted(r["knobs"].items()))
            rob = r.get("robust_ratio")
            tuned = f"{r['score']:.3f}, {r['travel_ratio']:.2f}x, "
            tuned += f"{rob:.2f}x" if rob is not None else "not checked"
            tuned += "" if r.get("feasible", True) else " (no candidate kept every term)"
            lines.append(
                f"| `{name}` | {env_id.split('/')[-1]} | {st['score']:.3f}, "
                f"{st['travel_ratio']:.2f}x | {tuned} | {r['evaluations']} | "
                f"{knobs} |"
            )
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m agents.baseline_tuning",
        description="Tune baselines on equal terms (same search, budget, objective and "
        "travel budget) and write baselines/tuned/<name>.json. Takes minutes to an hour "
        "per controller and env.",
    )
    ap.add_argument("names", nargs="*", help=f"baselines to tune (default: {', '.join(TUNABLE)})")
    ap.add_argument(
        "--env",
        action="append",
        dest="envs",
        metavar="ID",
        help="env id (repeatable; default: every registered env)",
    )
    ap.add_argument(
        "--ends",
        action="store_true",
        help="only (re)compute the score's ends on the training episodes "
        "(baselines/tuned/ends.json; the oracle's episodes: minutes per env)",
    )
    ap.add_argument(
        "--replay",
        action="store_true",
        help="reuse the stored searches' evaluations on the training episodes "
        "where the new search meets the same knobs (after a change of the "
        "constraints only; refused per search if its start does not reproduce)",
    )
    ap.add_argument(
        "--markdown",
        action="store_true",
        help="print the stored tunings as a markdown table and exit",
    )
    args = ap.parse_args(argv)
    if args.markdown:
        print(markdown(tuple(args.names) or TUNABLE), end="")
        return 0
    names = [] if args.ends and not args.names else (args.names or list(TUNABLE))
    for n in names:
        try:
            if not tuning.knobs(baselines.factory(n)):
                ap.error(f"baseline {n!r} has no KNOBS; tunable: {list(TUNABLE)}")
        except ValueError as exc:
            ap.error(str(exc))
    env_ids = []
    for e in args.envs or list(steamtemp_gym.ENV_IDS):
        try:
            env_ids.append(steamtemp_gym.envs.resolve_id(e))
        except ValueError as exc:
            ap.error(f"argument --env: {exc}")
    if args.ends:
        for e in env_ids:
            ends(e)
            print(f"ends of {e} in {tuning.TUNED / 'ends.json'}")
    for n in names:
        write(n, env_ids, log=lambda s: print(s, file=sys.stderr, flush=True), replay=args.replay)
        print(f"wrote {tuning.path(n)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

__all__ = [
    "EPISODES",
    "EVALUATIONS",
    "TUNABLE",
    "Evaluation",
    "ends",
    "evaluate",
    "knobs_key",
    "search",
    "seeds",
    "write",
]
