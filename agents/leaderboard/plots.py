"""The leaderboard's figures (150 dpi, 10-11 pt text), written by
agents/leaderboard/outputs.py, with the colours, line styles and text sizes they and the
trend plots (agents/leaderboard/trends.py) share.

- :func:`trend_policies`: the policies a trend plot shows (by default the reference
  ``cascade_pi_ff``, the oracle, ``cascade_pi`` and the plant's three best-scoring policies).
- :func:`bars`: per plant, the IQM of the normalized score of each policy with its 95 %
  stratified-bootstrap confidence interval.
- :func:`profiles`: per plant, performance profiles (fraction of runs above a normalized
  score, averaged over scenarios) over the scores that matter, :data:`PROFILE_RANGE`; the
  share of a policy's runs beyond it is given in the legend and marked at the axis edge.
- the score against the valve travel per plant: agents/leaderboard/pareto.py.

Colours (:func:`policy_colors`): baselines (``baselines.NAMES``) in blues and greens, trained
agents and other policies in oranges, reds and purples, the references in grey and black;
each policy its own colour within a figure.
"""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

import baselines
from agents import stats
from agents.leaderboard.report import INADMISSIBLE, ratio
from agents.leaderboard.summary import ONE, REFERENCES, ZERO, agent_names

DPI = 150
RC = {
    "font.size": 10,
    "axes.titlesize": 11,
    "axes.labelsize": 10,
    "legend.fontsize": 9,
    "xtick.labelsize": 9,
    "ytick.labelsize": 9,
}
#: The baselines' colours (blues, greens, teals; the first is the reference's), in order.
BASELINE_COLORS = (
    "#08306b",
    "#1f77b4",
    "#2ca02c",
    "#17becf",
    "#74c476",
    "#00695c",
    "#6baed6",
    "#00a087",
    "#1b5e20",
    "#4dd0e1",
    "#80cbc4",
)
#: The other policies' colours (trained agents, your own: oranges, reds, purples), in order.
AGENT_COLORS = (
    "#ff7f0e",
    "#d62728",
    "#9467bd",
    "#e377c2",
    "#8c564b",
    "#6a1b9a",
    "#c2185b",
    "#fdae6b",
    "#7f0000",
    "#b39ddb",
)
#: HSV hue ranges of the two families (extra colours are drawn from them; agents' wraps 1).
BASELINE_HUES, AGENT_HUES = (0.30, 0.68), (0.72, 1.10)
#: The references: the oracle near black, the frozen valve mid grey.
REFERENCE_COLORS = {ONE: "#1a1a1a", "frozen_valve": "#8c8c8c"}
#: Normalized scores shown by the profiles: the score's 0 and 1 and a little around.
PROFILE_RANGE = (-0.5, 1.25)
#: How many of the best-scoring policies a trend shows besides the fixed ones.
TREND_TOP = 3


def kind(name: str) -> str:
    """``"reference"`` (oracle, frozen valve), ``"baseline"`` (``baselines.NAMES``) or
    ``"agent"`` (a trained agent or any other policy)."""
    if name in REFERENCES:
        return "reference"
    return "baseline" if name in baselines.NAMES else "agent"


def _extra(hues: tuple[float, float], k: int) -> str:
    """The k-th colour beyond a family's list: hues spread over its range, two shades."""
    from matplotlib.colors import hsv_to_rgb, to_hex

    golden = 0.381966  # spreads successive hues evenly over the range
    lo, hi = hues[0] + 0.02, hues[1] - 0.02  # inside the range after rounding to hex
    h = (lo + (hi - lo) * ((k * golden) % 1.0)) % 1.0
    return to_hex(hsv_to_rgb((h, 0.75, 0.45 + 0.4 * (k % 2))))


def policy_colors(names: Sequence[str]) -> dict[str, str]:
    """One colour per policy, unique among ``names``: baselines from :data:`BASELINE_COLORS`
    (``cascade_pi_ff`` always its first), the others from :data:`AGENT_COLORS`, in the
    order given (so the first, e.g. the best-ranked, get the most distinct colours); beyond
    the lists, further shades of the same family."""
    out: dict[str, str] = {}
    used: set[str] = set()
    counts = {"baseline": 1, "agent": 0}  # the reference's colour is kept for it
    for name in names:
        if name in out:
            continue
        k = kind(name)
        if k == "reference":
            color = REFERENCE_COLORS.get(name, "#8c8c8c")
        elif name == ZERO:
            color = BASELINE_COLORS[0]
        else:
            pal, hues = (
                (BASELINE_COLORS, BASELINE_HUES) if k == "baseline" else (AGENT_COLORS, AGENT_HUES)
            )
            color = None
            while color is None or color in used:
                i = counts[k]
                counts[k] += 1
                color = pal[i] if i < len(pal) else _extra(hues, i - len(pal))
        out[name] = color
        used.add(color)
    return out


def line_style(name: str, color: str) -> dict[str, Any]:
    """Line style of a policy: the reference bold, the oracle dash-dot, the frozen valve
    dotted."""
    if name == ZERO:
        return {"color": color, "lw": 2.2, "ls": "-"}
    if name == ONE:
        return {"color": color, "lw": 1.3, "ls": "-."}
    if kind(name) == "reference":
        return {"color": color, "lw": 1.2, "ls": ":"}
    return {"color": color, "lw": 1.4, "ls": "-"}


def trend_policies(
    plant: dict[str, Any], available: Sequence[str], every: bool = False
) -> list[str]:
    """The policies a plant's trend plots show, in legend order.

    By default the reference ``cascade_pi_ff``, the ``oracle``, ``cascade_pi`` and the
    :data:`TREND_TOP` best ranked of the other admissible policies (by rank: the IQM of the
    normalized score; in a run without the score, by the IQM of the return; a policy over
    the valve-travel budget, with a trip or a failed episode is left out); with ``every``,
    all of ``available``, ranked ones first.

    Args:
        plant: The plant's summary (``summary["plants"][env_id]``; an empty dict for none).
        available: The policies run on the plant.
        every: Show every policy.
    """
    pols = plant.get("policies", {})

    def key(p: str) -> tuple[float, str]:
        e = pols.get(p, {})
        if "rank" in e:
            return (e["rank"], p)
        iqm = e.get("return", {}).get("iqm", {}).get("value")
        return (1e6 - iqm if iqm is not None else 2e6, p)

    fixed = [p for p in (ZERO, ONE, "cascade_pi") if p in available]
    rest = sorted((p for p in available if p not in fixed and kind(p) != "reference"), key=key)
    if every:
        return fixed + rest + [p for p in available if p not in fixed and p not in rest]
    return fixed + [p for p in rest if pols.get(p, {}).get("admissible") is not False][:TREND_TOP]


def pyplot():
    """matplotlib.pyplot on the Agg backend (files only, no display)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save(fig: Any, path: Path, **kw: Any) -> None:
    """Write ``fig`` to ``path`` (its folder made if missing) at :data:`DPI` and close it."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=DPI, **kw)
    pyplot().close(fig)


def short_env(env_id: str) -> str:
    """An env id without its namespace (figure titles)."""
    return env_id.split("/")[-1]


def figure_order(summary: dict[str, Any]) -> list[str]:
    """Every policy of a run in colour order: the reference, ``cascade_pi``, then by the
    overall ranking, then the rest as run."""
    run_pols = agent_names([p for pols in summary["run"]["policies"].values() for p in pols])
    ranked = [e["policy"] for e in summary.get("ranking", [])]
    order = [p for p in (ZERO, "cascade_pi") if p in run_pols] + ranked + run_pols
    return list(dict.fromkeys(order))


def subplot_grid(n: int):
    """(rows, columns) of a figure of ``n`` panels, at most three a row."""
    cols = min(n, 3)
    rows = (n + cols - 1) // cols
    return rows, cols


#: Longest policy name on a bar's label; a longer one (a path) keeps its end.
LABEL_CHARS = 28


def short_name(name: str, n: int = LABEL_CHARS) -> str:
    """``name`` in at most ``n`` characters: a longer one (an agent's path, a factory)
    keeps its last ``n - 1`` characters after an ellipsis."""
    return name if len(name) <= n else "…" + name[-(n - 1) :]


def _bar_label(name: str, pe: dict[str, Any], limit: float | None = None) -> str:
    """A bar's label: the policy, its valve travel over the reference's (with the digits
    that tell it from the budget ``limit``) and, when it is not admissible on the plant,
    the report's mark."""
    travel = f"  {ratio(pe['travel_ratio'], limit)}" if "travel_ratio" in pe else ""
    mark = f" {INADMISSIBLE}" if pe.get("admissible") is False else ""
    return f"{short_name(name)}{mark}{travel}"


def bars(path: Path, summary: dict[str, Any]) -> Path:
    """IQM normalized score with 95 % CIs, one panel per plant, policies by rank (admissible
    ones first), each labelled with its valve travel over the reference's and the
    inadmissible mark; the axis spans :data:`PROFILE_RANGE` and the scores of the ranked
    policies down to -1, a bar beyond it ends at the edge with its value written there."""
    plt = pyplot()
    plants = list(summary["plants"])
    rows, cols = subplot_grid(len(plants))
    colors = policy_colors(figure_order(summary))
    with plt.rc_context(RC):
        width = max(5.2 * cols, 8.0)  # one plant: room for the title and the labels
        fig, axes = plt.subplots(rows, cols, figsize=(width, 3.6 * rows), squeeze=False)
        for ax, env_id in zip(axes.flat, plants, strict=False):
            pols = summary["plants"][env_id]["policies"]
            ranked = sorted((p for p in pols if "rank" in pols[p]), key=lambda p: pols[p]["rank"])
            vals = [pols[p]["normalized_score"]["iqm"] for p in ranked]
            y = np.arange(len(ranked))
            x = np.array([v["value"] for v in vals])
            lo_all = min([PROFILE_RANGE[0]] + [v["ci95"][0] for v in vals])
            lo = max(lo_all, -1.0) - 0.05
            hi = PROFILE_RANGE[1]
            shown = np.clip(x, lo, hi)
            err = np.array(
                [
                    [max(s - max(v["ci95"][0], lo), 0.0), max(min(v["ci95"][1], hi) - s, 0.0)]
                    for s, v in zip(shown, vals, strict=True)
                ]
            )
            ax.barh(
                y,
                shown,
                xerr=err.T if len(vals) else None,
                color=[colors[p] for p in ranked],
                alpha=0.85,
                capsize=3,
            )
            for k in np.flatnonzero(x < lo):
                ax.text(lo, y[k], f" ◀ {x[k]:.2f}", va="center", ha="left", fontsize=8)
            ax.set_xlim(lo, hi)
            ax.set_yticks(
                y, [_bar_label(p, pols[p], summary["run"].get("travel_budget")) for p in ranked]
            )
            ax.invert_yaxis()
            ax.axvline(0, color="k", lw=0.8)
            ax.axvline(1, color="k", lw=0.8, ls="--")
            ax.set_title(short_env(env_id))
            ax.set_xlabel(f"IQM normalized score\n(0 = {ZERO}, 1 = {ONE})")
            ax.grid(axis="x", alpha=0.3)
        for ax in list(axes.flat)[len(plants) :]:
            ax.axis("off")
        n_seeds = summary["run"]["seeds"]
        budget = summary["run"].get("travel_budget")
        note = (
            (
                f"\nlabels: valve travel over {ZERO}'s; {INADMISSIBLE}: not admissible "
                f"(travel above {budget:g}x, a trip or a failure), ranked last"
            )
            if budget
            else ""
        )
        title = (
            f"IQM over scenario × seed ({len(n_seeds)} seeds), 95 % stratified-bootstrap "
            f"CI; blue/green: baselines, orange/red/purple: trained agents{note}"
        )
        fig.suptitle("\n".join(textwrap.fill(line, int(width * 13)) for line in title.split("\n")))
        fig.tight_layout()
        save(fig, path)
    return path


def profiles(
    path: Path,
    scores: dict[str, dict[str, list[np.ndarray]]],
    n_seeds: int,
    order: Sequence[str] | None = None,
    highlight: dict[str, Sequence[str]] | None = None,
) -> Path:
    """Performance profiles: ``scores[env][policy]`` = normalized scores per scenario.

    The axis spans :data:`PROFILE_RANGE`; where a policy has runs beyond it, a triangle
    at that edge marks that its curve goes on (its height there is the share of runs above
    the edge). ``order`` gives the colour order (default: as in ``scores``); the policies of
    ``highlight[env]`` (e.g. those of the trend plots) are drawn bold, the others thin.
    """
    plt = pyplot()
    plants = list(scores)
    rows, cols = subplot_grid(len(plants))
    names = list(dict.fromkeys([*(order or []), *(p for e in scores.values() for p in e)]))
    colors = policy_colors(names)
    lo, hi = PROFILE_RANGE
    taus = np.linspace(lo, hi, 351)
    handles: dict[str, Any] = {}
    with plt.rc_context(RC):
        fig, axes = plt.subplots(rows, cols, figsize=(5.6 * cols, 4.0 * rows), squeeze=False)
        for ax, env_id in zip(axes.flat, plants, strict=False):
            bold = set(highlight[env_id]) if highlight and env_id in highlight else set(names)
            for pol in sorted(scores[env_id], key=lambda p: (p in bold, -names.index(p))):
                tasks = scores[env_id][pol]
                if not any(len(t) for t in tasks):
                    continue
                style = line_style(pol, colors[pol])
                if pol not in bold:
                    style.update(lw=0.8, alpha=0.6)
                prof = stats.performance_profile(tasks, taus)
                (line,) = ax.plot(taus, prof, label=pol, **style)
                handles.setdefault(pol, line)
                for x, y, edge, marker in (
                    (lo, prof[0], prof[0] < 1.0, "<"),
                    (hi, prof[-1], prof[-1] > 0.0, ">"),
                ):
                    if edge:
                        ax.plot(
                            [x],
                            [y],
                            marker=marker,
                            ms=6,
                            ls="none",
                            clip_on=False,
                            color=style["color"],
                            alpha=style.get("alpha", 1.0),
                        )
            ax.set_xlim(lo, hi)
            ax.set_ylim(0.0, 1.02)
            ax.axvline(0, color="k", lw=0.8)
            ax.axvline(1, color="k", lw=0.8, ls="--")
            ax.set_title(short_env(env_id))
            ax.set_xlabel("normalized score τ")
            ax.set_ylabel("fraction of runs > τ")
            ax.grid(alpha=0.3)
        from matplotlib.lines import Line2D

        labels = [p for p in names if p in handles]
        proxies = [Line2D([], [], **line_style(p, colors[p])) for p in labels]
        spare = list(axes.flat)[len(plants) :]
        for ax in spare:
            ax.axis("off")
        legend_args = {"handles": proxies, "labels": labels}
        if spare:
            spare[0].legend(
                loc="center", ncol=2, title="bold: the plant's trend-plot policies", **legend_args
            )
        else:
            fig.legend(loc="center left", bbox_to_anchor=(1.0, 0.5), **legend_args)
        fig.suptitle(
            f"Performance profiles over scenario × seed ({n_seeds} seeds); "
            f"0 = {ZERO}, 1 = {ONE}; ◀ ▶: the curve goes on beyond the axis"
        )
        fig.tight_layout()
        save(fig, path, bbox_inches="tight")
    return path
