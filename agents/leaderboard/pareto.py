"""The leaderboard's score-against-travel figure: per plant, each policy's IQM of the
normalized score against its valve travel over the reference's, the travel budget, and
the Pareto front of the admissible policies (:func:`pareto_front`) joined and labelled;
colours, line styles and sizes those of agents/leaderboard/plots.py.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from agents import stats
from agents.leaderboard import report
from agents.leaderboard.plots import (
    BASELINE_COLORS,
    RC,
    REFERENCE_COLORS,
    figure_order,
    policy_colors,
    pyplot,
    save,
    short_env,
    short_name,
    subplot_grid,
)
from agents.leaderboard.report import INADMISSIBLE, ratio
from agents.leaderboard.summary import ONE, REFERENCES, ZERO


def pareto_front(points: dict[str, tuple[float, float]]) -> list[str]:
    """The policies of ``points`` (name -> (travel ratio, score)) that no other beats on
    both: none has as little travel or less and as high a score or higher, one of them
    strictly. In order of travel; of equal points, the first by name."""
    front, best = [], -np.inf
    for name in sorted(points, key=lambda n: (points[n][0], -points[n][1], n)):
        if points[name][1] > best:
            front.append(name)
            best = points[name][1]
    return front


#: The file name of the score-against-travel figure in a run's plots/.
PARETO = "pareto.png"
#: The Pareto figure's score axis: at least the score's 0 and 1 and a little around.
PARETO_SCORES = (-0.3, 1.1)
#: Lowest score the Pareto figure shows; a point below it sits at the edge with its value.
PARETO_FLOOR = -1.0


def _points(pols: dict[str, Any]) -> dict[str, tuple[float, float]]:
    """Name -> (travel ratio, IQM score) of the plant's policies that have both."""
    return {
        p: (e["travel_ratio"], e["normalized_score"]["iqm"]["value"])
        for p, e in pols.items()
        if "travel_ratio" in e and "normalized_score" in e
    }


def _dark(color: str) -> tuple[float, float, float]:
    """``color`` darkened for text on white (light greens and teals stay readable)."""
    from matplotlib.colors import to_rgb

    return tuple(0.65 * c for c in to_rgb(color))


def _samples(ax: Any, lines: Sequence[np.ndarray], step: float = 4.0) -> list[np.ndarray]:
    """Points every ``step`` pixels along polylines given in data coordinates."""
    out = []
    for line in lines:
        xy = ax.transData.transform(np.asarray(line, dtype=float))
        for a, b in zip(xy[:-1], xy[1:], strict=True):
            n = max(int(np.hypot(*(b - a)) / step), 1)
            out += [a + (b - a) * k / n for k in range(n + 1)]
    return out


def _place_labels(
    ax: Any,
    anchors: list[tuple[float, float, str, dict[str, Any]]],
    lines: Sequence[np.ndarray] = (),
) -> None:
    """Write each label next to its point (data coordinates) where it overlaps no label
    already placed, no point and none of ``lines`` (polylines in data coordinates), trying
    offsets around the point from near to far; a label set apart is joined to its point by
    a thin line."""
    fig = ax.figure
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    box = ax.get_window_extent(renderer)
    taken = []
    pts = [ax.transData.transform((x, y)) for x, y, _, _ in anchors] + _samples(ax, lines)
    offsets = [
        (dx * r, dy * r)
        for r in (1, 2, 3, 4.5)
        for dx, dy in ((1, 0), (1, 1), (1, -1), (-1, 0), (-1, 1), (-1, -1), (0, 1.6), (0, -1.6))
    ]
    for x, y, text, style in anchors:
        best = None
        for dx, dy in offsets:
            ha = "left" if dx > 0 else "right" if dx < 0 else "center"
            t = ax.annotate(
                text,
                (x, y),
                xytext=(7 * dx, 6 * dy),
                textcoords="offset points",
                ha=ha,
                va="center",
                **style,
            )
            bb = t.get_window_extent(renderer).expanded(1.05, 1.15)
            inside = bb.x0 >= box.x0 and bb.x1 <= box.x1 and bb.y0 >= box.y0 and bb.y1 <= box.y1
            hits = sum(bb.overlaps(o) for o in taken) + sum(bb.contains(qx, qy) for qx, qy in pts)
            cost = hits + (0 if inside else 10)
            if best is None or cost < best[0]:
                if best is not None:
                    best[1].remove()
                best = (cost, t, bb, (dx, dy))
            else:
                t.remove()
            if cost == 0:
                break
        _, t, bb, (dx, dy) = best
        if abs(dx) > 1 or abs(dy) > 1.6:
            t.arrow_patch = None
            ax.annotate(
                "",
                (x, y),
                xytext=(7 * dx, 6 * dy),
                textcoords="offset points",
                arrowprops={
                    "arrowstyle": "-",
                    "lw": 0.5,
                    "color": "0.5",
                    "shrinkA": 0,
                    "shrinkB": 3,
                },
            )
        taken.append(bb)


def _pareto_keys(limit: float) -> list[Any]:
    """The legend of :func:`pareto`: what each mark means."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    dot = {"ls": "none", "marker": "o", "ms": 6}
    return [
        Line2D(
            [],
            [],
            color="k",
            lw=1.4,
            label="Pareto front: the admissible policies that no\nother beats on "
            "both score and travel (labelled)",
        ),
        Line2D([], [], color="0.6", **{**dot, "ms": 4}, label="another policy (grey, unlabelled)"),
        Line2D(
            [],
            [],
            color="0.3",
            mfc="white",
            mew=1.2,
            **dot,
            label=f"{INADMISSIBLE} not admissible (hollow; labelled where no\n"
            "admissible policy beats it on both)",
        ),
        Patch(color="#d62728", alpha=0.15, label=f"over the travel budget ({limit:g}x {ZERO}'s)"),
        Line2D(
            [],
            [],
            color=BASELINE_COLORS[0],
            ls="none",
            marker="s",
            ms=6,
            label=f"{ZERO}, the score's 0",
        ),
        Line2D(
            [],
            [],
            color=REFERENCE_COLORS[ONE],
            ls="none",
            marker="*",
            ms=9,
            label=f"{ONE}, the score's 1",
        ),
        Line2D(
            [],
            [],
            color="0.5",
            ls="none",
            marker="v",
            ms=6,
            label="beyond the axis, at its edge (travel, score)",
        ),
    ]


def pareto(path: Path, summary: dict[str, Any]) -> Path:
    """Score against valve travel, one panel per plant: each policy's IQM normalized score
    with its 95 % CI against its valve travel over the reference's; the travel budget as a
    vertical line; the Pareto front of the admissible policies (:func:`pareto_front`: the
    most score for the travel) joined by a staircase and labelled, as are the references and
    any policy over the budget that no admissible one beats on both; the others small and
    grey, hollow where not admissible. A score below :data:`PARETO_FLOOR` or a travel beyond
    the axis sits at the edge with its value."""
    plt = pyplot()
    plants = list(summary["plants"])
    rows, cols = subplot_grid(len(plants))
    colors = policy_colors(figure_order(summary))
    limit = float(summary["run"].get("travel_budget", stats.TRAVEL_BUDGET))
    with plt.rc_context(RC):
        fig, axes = plt.subplots(rows, cols, figsize=(5.8 * cols, 4.8 * rows), squeeze=False)
        for ax, env_id in zip(axes.flat, plants, strict=False):
            _pareto_panel(ax, env_id, summary["plants"][env_id]["policies"], colors, limit)
        spare = list(axes.flat)[len(plants) :]
        for ax in spare:
            ax.axis("off")
        legend = {"handles": _pareto_keys(limit), "title": "key"}
        if spare:
            spare[0].legend(loc="center", **legend)
        else:
            fig.legend(loc="upper center", bbox_to_anchor=(0.5, 0.0), ncol=3, **legend)
        n_seeds = len(summary["run"]["seeds"])
        fig.suptitle(f"Score against valve travel per plant: {report.stat_label(n_seeds)}")
        fig.tight_layout()
        save(fig, path, bbox_inches="tight")
    return path


def _pareto_panel(
    ax: Any, env_id: str, pols: dict[str, Any], colors: dict[str, str], limit: float
) -> None:
    """One plant's panel of :func:`pareto`: its policies ``pols`` (the summary's) against
    the travel budget ``limit``, the Pareto front joined, the labels placed."""
    pts = _points(pols)
    ranked = {p: v for p, v in pts.items() if p not in REFERENCES}
    ok = {p: v for p, v in ranked.items() if pols[p].get("admissible") is not False}
    front = pareto_front(ok)
    over = [p for p in pareto_front(ranked) if p not in ok]  # beats the front, † only
    cis = [pols[p]["normalized_score"]["iqm"]["ci95"] for p in ranked]
    lo = max(min([PARETO_SCORES[0], *(c[0] for c in cis)]), PARETO_FLOOR) - 0.05
    hi = max([PARETO_SCORES[1], *(c[1] + 0.05 for c in cis)])
    far = max([limit * 1.25, *(v[0] for v in pts.values())])
    view = (lo, hi, min(far, limit * 2.0) * 1.06)
    _draw_budget(ax, limit, view)
    lines = _draw_front(ax, [ok[p] for p in front], limit)
    anchors = []
    for p, xy in pts.items():
        labelled = p in front or p in over or p in REFERENCES or p == ZERO
        color = colors[p] if labelled else "0.6"
        _draw_point(ax, p, xy, pols[p], color, labelled, limit, view, anchors, lines)
    lines.append([(limit, lo), (limit, hi)])
    _place_labels(ax, anchors, lines)
    ax.set_title(short_env(env_id))
    ax.set_xlabel(f"valve travel over {ZERO}'s [ratio, ×]")
    ax.set_ylabel(f"IQM normalized score\n(0 = {ZERO}, 1 = {ONE})")
    ax.grid(alpha=0.3)


def _draw_budget(ax: Any, limit: float, view: tuple[float, float, float]) -> None:
    """Set the panel's axes to ``view`` (lowest and highest score, right edge of the travel)
    and draw the travel budget ``limit`` (the region over it shaded) and the score's 0 and 1."""
    lo, hi, right = view
    ax.set_xlim(0.0, right)
    ax.set_ylim(lo, hi)
    ax.axvspan(limit, right, color="#d62728", alpha=0.06, lw=0)
    ax.axvline(limit, color="#d62728", lw=1.2, ls="--")
    ax.text(limit, hi, f" budget {limit:g}x", color="#d62728", ha="left", va="top", fontsize=8)
    ax.axhline(0, color="k", lw=0.6)
    ax.axhline(1, color="k", lw=0.6, ls=":")


def _draw_front(ax: Any, front: list[tuple[float, float]], limit: float) -> list[Any]:
    """Draw the Pareto front (its points' (travel ratio, score) in order of travel) as a
    staircase to the budget ``limit``; its corners as the one polyline the labels avoid
    (none without a front)."""
    if not front:
        return []
    xs = [x for x, _ in front] + [limit]
    ys = [y for _, y in front]
    ax.step(
        xs,
        [*ys, ys[-1]],
        where="post",
        color="k",
        lw=1.4,
        zorder=2,
        label="Pareto front of the admissible policies",
    )
    return [[c for k, y in enumerate(ys) for c in ((xs[k], y), (xs[k + 1], y))]]


def _draw_point(
    ax: Any,
    p: str,
    xy: tuple[float, float],
    pe: dict[str, Any],
    color: str,
    labelled: bool,
    limit: float,
    view: tuple[float, float, float],
    anchors: list[Any],
    lines: list[Any],
) -> None:
    """Draw policy ``p`` at ``xy`` (travel ratio, score) with its 95 % CI (``pe``: its
    summary entry), hollow where not admissible; a point beyond ``view`` sits at its edge
    as a triangle. Adds its CI bar to ``lines`` and, if ``labelled``, its label to
    ``anchors`` (a label at the edge first: it has fewer places)."""
    lo, hi, right = view
    x, y = xy
    shown_x, shown_y = min(x, right), min(max(y, lo), hi)
    ci = pe["normalized_score"]["iqm"]["ci95"]
    hollow = pe.get("admissible") is False
    marker = "*" if p == ONE else "s" if p in (ZERO, *REFERENCES) else "o"
    edge = x > right or y < lo
    if edge:
        marker = ">" if x > right else "v"
    ax.errorbar(
        [shown_x],
        [shown_y],
        yerr=None if edge else [[y - max(ci[0], lo)], [min(ci[1], hi) - y]],
        fmt=marker,
        ms=9 if marker == "*" else 6 if labelled else 4,
        color=color,
        mfc="white" if hollow else color,
        mew=1.2,
        elinewidth=0.9,
        capsize=2,
        zorder=3 if labelled else 1,
        clip_on=False,
    )
    if not edge:
        lines.append([(shown_x, max(ci[0], lo)), (shown_x, min(ci[1], hi))])
    if labelled:
        text = short_name(p) + (f" {INADMISSIBLE}" if hollow else "")
        if hollow and x > limit and not edge:
            text += f" {ratio(x, limit)}"
        if edge:
            text += f" ({x:.1f}x, {y:.2f})"
        anchor = (shown_x, shown_y, text, {"fontsize": 8, "color": _dark(color)})
        anchors.insert(0 if edge else len(anchors), anchor)  # fewer places first
