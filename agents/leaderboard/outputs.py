"""The outputs of a leaderboard run rebuilt from episodes.jsonl: leaderboard.json,
leaderboard.md and the figures of plots/ (:func:`rebuild`), and the trend plots drawn for a
plant as soon as all its episodes have finished (:class:`Plots`).
"""

from __future__ import annotations

import sys
from collections import Counter
from pathlib import Path
from typing import Any

import steamtemp_gym
from agents import specs, stats
from agents.evaluation import run_episode
from agents.leaderboard import episodes, mismatch, pareto, plots, report, trends
from agents.leaderboard.episodes import Unit
from agents.leaderboard.plan import Plan
from agents.leaderboard.records import EPISODES, dumps, latest_rows, read_record
from agents.leaderboard.summary import REFERENCE, SCHEMA_VERSION, VERSUS, agent_names, summarize


def _plot_path(out: Path, env_id: str, scenario: str) -> Path:
    stem = Path(scenario).stem if _is_file(scenario) else scenario.replace(":", "_")
    return out / "plots" / f"{env_id.split('/')[-1]}__{stem}.png"


def _is_file(spec: str) -> bool:
    return spec.lower().endswith((".yaml", ".yml"))


class Plots:
    """Trend plots per env and scenario, drawn for a plant as soon as all its episodes have
    finished (the policies shown depend on the plant's scores: plots.trend_policies). A
    trained agent with several training runs is shown by its first run."""

    def __init__(self, out: Path, plan: Plan, units: list[Unit], every: bool = False) -> None:
        self.out, self.plan, self.every = out, plan, every
        self.pending = Counter(u.env_id for u in units)
        self.traces: dict[tuple[str, str], dict[str, dict]] = {}
        self.trace_run: dict[tuple[str, str, str], int] = {}  # the run of a trace kept
        self._shown: dict[str, tuple[list[str], dict[str, str]]] = {}

    def add(self, u: Unit, trace: dict | None) -> None:
        name, run = specs.split_run(u.policy)
        key = (u.env_id, u.spec, name)
        if trace is not None and (run or 0) <= self.trace_run.get(key, run or 0):
            self.trace_run[key] = run or 0
            self.traces.setdefault((u.env_id, u.spec), {})[name] = trace
        self.pending[u.env_id] -= 1
        if self.pending[u.env_id] == 0:
            for sc in self.plan.scenarios:
                self.draw(u.env_id, sc)

    def shown(self, env_id: str) -> tuple[list[str], dict[str, str]]:
        """The policies a plant's trends show and their legend notes (rank and score),
        summarized once per plant: its plots are drawn when all its episodes have finished."""
        if env_id not in self._shown:
            self._shown[env_id] = self._summarize_shown(env_id)
        return self._shown[env_id]

    def _summarize_shown(self, env_id: str) -> tuple[list[str], dict[str, str]]:
        rows = [r for r in _grid_rows(self.out, self.plan) if r["env"] == env_id]
        ok = [r for r in rows if not r.get("error")]
        plant = summarize(ok, _run_info(self.plan, [env_id]))[0]["plants"][env_id] if ok else {}
        names = plots.trend_policies(plant, agent_names(self.plan.policies[env_id]), self.every)
        notes = {}
        for name in names:
            e = plant.get("policies", {}).get(name, {})
            iqm = e.get("normalized_score", {}).get("iqm", {}).get("value")
            if iqm is not None:
                notes[name] = (f"#{e['rank']}, " if "rank" in e else "") + f"score {iqm:.2f}"
        return names, notes

    def draw(self, env_id: str, sc: str) -> None:
        """The trend plot of one env and scenario (traces missing after a resume re-run)."""
        traces = self.traces.pop((env_id, sc), {})
        seed = self.plan.seeds[0]
        env = self.plan.envs_made[env_id, sc]
        names, notes = self.shown(env_id)
        for name in names:
            if name not in traces:
                try:
                    runs = [r for r in self.plan.policies[env_id] if specs.split_run(r)[0] == name]
                    pol = episodes.make_policy(
                        self.plan.spec(runs[0] if runs else name),
                        env_id,
                        env,
                        self.plan.resolved[env_id, sc],
                        imports=self.plan.imports,
                        timeout=self.plan.episode_timeout,
                        oracle=self.plan.oracle,
                    )
                    try:
                        traces[name] = run_episode(env, pol, seed)["trace"]
                    finally:
                        episodes.close(pol)
                except Exception as exc:  # noqa: BLE001 - that episode is in the record
                    print(
                        f"note: no trace of {name} seed {seed} for the plot: {exc}", file=sys.stderr
                    )
        order = [n for n in names if n in traces]
        if order:
            title = self.plan.resolved[env_id, sc].name if _is_file(sc) else sc
            trends.trend(
                _plot_path(self.out, env_id, sc),
                env,
                env_id,
                title,
                {n: traces[n] for n in order},
                seed,
                colors=plots.policy_colors(names),
                notes=notes,
            )

    def missing(self) -> list[tuple[str, str]]:
        """Groups without a plot file (after a resume with nothing left to run)."""
        groups = [(e, s) for e in self.plan.envs for s in self.plan.scenarios]
        return [
            g for g in groups if g[0] not in self.pending and not _plot_path(self.out, *g).exists()
        ]


def _grid_rows(out: Path, plan: Plan) -> list[dict]:
    """The rows of the run's grid from episodes.jsonl: the last line of each episode with
    the current fingerprint, without its traceback."""
    latest = latest_rows(read_record(out / EPISODES))
    rows = []
    for key in plan.grid():
        r = latest.get((key, plan.fingerprints[key[:3]]))
        if r is not None:
            rows.append({k: v for k, v in r.items() if k != "traceback"})
    return rows


def _run_info(plan: Plan, envs: list[str] | None = None) -> dict[str, Any]:
    """leaderboard.json's ``run``: what ran, with the statistics' settings."""
    return {
        "envs": envs or plan.envs,
        "scenarios": plan.scenarios,
        "policies": plan.policies,
        "seeds": plan.seeds,
        "steamtemp_gym_version": steamtemp_gym.__version__,
        "n_bootstrap": stats.N_BOOTSTRAP,
        "confidence": stats.CONFIDENCE,
        "reference": REFERENCE,
        "versus": VERSUS,
        "travel_budget": plan.travel_budget,
        "oracle": plan.oracle,
        "mismatch": {
            e: [v.removeprefix(mismatch.PREFIX) for v in plan.variants.get(e, {})]
            for e in envs or plan.envs
            if plan.variants.get(e)
        },
    }


def rebuild(out: Path, plan: Plan, figures: bool = True) -> tuple[list[dict], dict | None]:
    """leaderboard.json, leaderboard.md and the summary figures from episodes.jsonl."""
    rows = _grid_rows(out, plan)
    run = _run_info(plan)
    summary, norm = (None, {})
    if any(not r.get("error") for r in rows):
        summary, norm = summarize(rows, run)
    doc = dict(
        summary or {"schema_version": SCHEMA_VERSION, "run": run, "plants": {}, "ranking": []}
    )
    doc["episodes"] = rows
    (out / "leaderboard.json").write_text(dumps(doc, indent=1) + "\n")
    (out / "leaderboard.md").write_text(report.markdown(doc, rows))
    if figures and summary is not None:
        (out / "plots").mkdir(parents=True, exist_ok=True)
        plots.bars(out / "plots" / "scores.png", summary)
        if any(norm.values()):
            pareto.pareto(out / "plots" / pareto.PARETO, summary)
            plots.profiles(
                out / "plots" / "profiles.png",
                norm,
                len(plan.seeds),
                order=plots.figure_order(summary),
                highlight={
                    e: plots.trend_policies(summary["plants"][e], agent_names(plan.policies[e]))
                    for e in summary["plants"]
                },
            )
    return rows, summary
