"""The leaderboard's figures (agents/leaderboard/plots.py, agents/leaderboard/trends.py) and
leaderboard.md's numbers: colours unique per figure and by kind, the trend plots' policy
selection, the profiles' focused axis with the clipped runs marked, display precision and units
in the markdown.

Figures are inspected before they are written (``plots.save`` replaced); synthetic traces and
scores keep these in seconds.
"""

from __future__ import annotations

import colorsys
from types import SimpleNamespace

import numpy as np
import pytest
from matplotlib.colors import to_rgb

import baselines
from agents.leaderboard import pareto, plots, report, trends
from agents.leaderboard.summary import REFERENCES, TABLE_METRICS, ZERO, summarize

AGENTS = ("sb3:ppo", "sb3:sac", "sb3:sac_caps", "zoo:runs/a", "mine:make")


@pytest.fixture
def figures(monkeypatch):
    """The figures the plot functions would write, in order, instead of the files."""
    out = []

    def keep(fig, path, **kw):
        out.append(fig)

    monkeypatch.setattr(plots, "save", keep)
    monkeypatch.setattr(pareto, "save", keep)
    yield out
    import matplotlib.pyplot as plt

    for fig in out:
        plt.close(fig)


def _hue(color) -> float:
    return colorsys.rgb_to_hsv(*to_rgb(color))[0]


def _in(hue: float, hues: tuple[float, float]) -> bool:
    lo, hi = hues
    return lo <= hue <= hi or lo <= hue + 1.0 <= hi


def _colors(lines) -> list[str]:
    return [tuple(round(c, 4) for c in to_rgb(ln.get_color())) for ln in lines]


def test_colours_are_unique_and_by_family(monkeypatch):
    extra = tuple(f"my_baseline_{k}" for k in range(6))  # beyond the listed colours
    monkeypatch.setattr(baselines, "NAMES", (*baselines.NAMES, *extra))
    agents = (*AGENTS, *(f"zoo:runs/{k}" for k in range(12)))
    names = [*baselines.NAMES, *agents, *REFERENCES]
    colors = plots.policy_colors(names)
    assert list(colors) == names
    assert len({to_rgb(c) for c in colors.values()}) == len(names)
    for name in baselines.NAMES:
        assert _in(_hue(colors[name]), plots.BASELINE_HUES), (name, colors[name])
    for name in agents:
        assert _in(_hue(colors[name]), plots.AGENT_HUES), (name, colors[name])
    for name in REFERENCES:  # grey: no hue at all
        r, g, b = to_rgb(colors[name])
        assert r == g == b
    # the reference keeps its colour wherever it stands
    assert plots.policy_colors(["sb3:ppo", "mpc_linear", ZERO])[ZERO] == plots.BASELINE_COLORS[0]


def _plant(ranks: dict[str, int]) -> dict:
    return {"policies": {p: {"rank": k} for p, k in ranks.items()}}


def test_trend_shows_the_reference_the_oracle_cascade_pi_and_the_top_three():
    available = [*baselines.NAMES, *AGENTS[:3], *REFERENCES]
    order = ["mpc_linear", "cascade_pi_ff", "sb3:ppo", "lqi", "fao_fac", "cascade_pi", "sb3:sac"]
    ranks = {p: k for k, p in enumerate(order, 1)}
    shown = plots.trend_policies(_plant(ranks), available)
    assert shown == ["cascade_pi_ff", "oracle", "cascade_pi", "mpc_linear", "sb3:ppo", "lqi"]
    plant = _plant(ranks)
    plant["policies"]["sb3:ppo"]["admissible"] = False  # over the valve-travel budget
    assert plots.trend_policies(plant, available)[3:] == ["mpc_linear", "lqi", "fao_fac"]
    every = plots.trend_policies(_plant(ranks), available, every=True)
    assert sorted(every) == sorted(available) and every[:6] == shown
    # without the score (no oracle): by the IQM of the return
    rets = {
        p: {"return": {"iqm": {"value": v}}}
        for p, v in (("lqi", -5.0), ("fao_sf", -1.0), ("sb3:sac", -3.0), ("mpc_arx", -9.0))
    }
    shown = plots.trend_policies(
        {"policies": rets}, ["cascade_pi_ff", "cascade_pi", "lqi", "fao_sf", "sb3:sac", "mpc_arx"]
    )
    assert shown == ["cascade_pi_ff", "cascade_pi", "fao_sf", "sb3:sac", "lqi"]


def _trace(n: int, offset: float, n_act: int, secondary: bool) -> dict:
    t = np.arange(n) * 2.0
    tr = {
        "time_s": t,
        "outlet_temp_C": 540.0 + offset * np.sin(t / 100),
        "measured_temp_C": 540.0 + offset * np.sin(t / 100),
        "setpoint_C": np.full(n, 540.0),
        "load": np.linspace(1.0, 0.5, n),
        "spray_valve": np.full((n, n_act), 0.4),
        "spray_flow_kg_s": np.full(n, 5.0),
        "heat_absorption_bias": np.zeros(n),
        "fouling": np.ones(n),
        "spray_water_temp_offset_C": np.zeros(n),
    }
    if secondary:
        tr["reheat_temp_C"] = 566.0 + offset * np.cos(t / 100)
    return tr


def _env(n_act: int, secondary: bool):
    plant = SimpleNamespace(secondary=(("reheat_temp_C", 566.0),) if secondary else ())
    acts = [SimpleNamespace(name=f"v{j}", description=f"valve {j} command") for j in range(n_act)]
    return SimpleNamespace(
        unwrapped=SimpleNamespace(plant=plant, signals=SimpleNamespace(action=acts))
    )


def test_trend_colours_are_unique_and_the_title_names_the_scenario(figures, tmp_path):
    names = [
        "cascade_pi_ff",
        "oracle",
        "cascade_pi",
        "mpc_linear",
        "sb3:ppo",
        "lqi",
        "sb3:sac",
        "frozen_valve",
    ]
    traces = {n: _trace(50, 1.0 + k, 3, True) for k, n in enumerate(names)}
    trends.trend(
        tmp_path / "x.png",
        _env(3, True),
        "steamtemp/BoilerTurbineMIMO-v0",
        "my_test",
        traces,
        0,
        notes={"mpc_linear": "#1, score 0.75"},
    )
    (fig,) = figures
    main = fig.axes[0]
    lines = [ln for ln in main.get_lines() if ln.get_label().endswith(": true")]
    assert [ln.get_label().removesuffix(": true").split(" (")[0] for ln in lines] == names
    assert len(set(_colors(lines))) == len(names)
    assert "mpc_linear (#1, score 0.75): true" in [ln.get_label() for ln in lines]
    assert main.get_title().startswith("BoilerTurbineMIMO-v0 - my_test:")
    # the same colour for a policy in every panel: main steam, reheat, three actuators
    for ax in fig.axes[1:5]:
        assert _colors(ax.get_lines()[-len(names) :]) == _colors(lines)


def test_profiles_span_the_score_range_and_mark_clipped_runs(figures, tmp_path):
    lo, hi = plots.PROFILE_RANGE
    rng = np.random.default_rng(0)
    scores = {
        "steamtemp/A-v0": {
            "cascade_pi_ff": [rng.normal(0.0, 0.1, 5) for _ in range(3)],
            "sb3:sac": [np.array([-9.0, -4.0, 0.2, 0.3, -0.1]) for _ in range(3)],
            "mpc_linear": [np.array([0.7, 0.8, 0.9, 3.0, 0.75]) for _ in range(3)],
            "oracle": [np.ones(5) for _ in range(3)],
        }
    }
    plots.profiles(tmp_path / "p.png", scores, 5)
    (fig,) = figures
    ax = fig.axes[0]
    assert ax.get_xlim() == (lo, hi)
    marks = {
        (m.get_marker(), to_rgb(m.get_color()))
        for m in ax.get_lines()
        if m.get_marker() in ("<", ">")
    }
    colors = plots.policy_colors(list(scores["steamtemp/A-v0"]))
    assert marks == {("<", to_rgb(colors["sb3:sac"])), (">", to_rgb(colors["mpc_linear"]))}
    curves = [ln for ln in ax.get_lines() if ln.get_label() in scores["steamtemp/A-v0"]]
    assert len(set(_colors(curves))) == len(curves) == 4


def test_bars_colour_by_family(figures, tmp_path):
    scores = {"mpc_linear": 0.8, "sb3:ppo": 0.3, "cascade_pi": -0.2, "sb3:sac": -3.0}
    pols = {
        p: {"rank": k, "normalized_score": {"iqm": {"value": v, "ci95": [v - 0.1, v + 0.1]}}}
        for k, (p, v) in enumerate(scores.items(), 1)
    }
    summary = {
        "run": {"seeds": [0, 1], "policies": {"e": list(pols)}},
        "plants": {"steamtemp/A-v0": {"policies": pols}},
        "ranking": [],
    }
    plots.bars(tmp_path / "s.png", summary)
    (fig,) = figures
    ax = fig.axes[0]
    fills = [tuple(round(c, 4) for c in p.get_facecolor()[:3]) for p in ax.patches]
    assert len(set(fills)) == 4
    for p, c in zip(("mpc_linear", "sb3:ppo", "cascade_pi", "sb3:sac"), fills, strict=True):
        fam = plots.BASELINE_HUES if p in baselines.NAMES else plots.AGENT_HUES
        assert _in(colorsys.rgb_to_hsv(*c)[0], fam), p
    assert ax.get_xlim()[0] >= -1.05  # the -3.0 bar is cut at the edge, its value written
    assert any("-3.00" in t.get_text() for t in ax.texts)


def test_bars_label_travel_and_the_inadmissible_mark(figures, tmp_path):
    pols = {
        "mpc_linear": {"rank": 1, "travel_ratio": 1.24, "admissible": True},
        "sb3:sac": {"rank": 2, "travel_ratio": 9.5, "admissible": False},
    }
    for k, p in enumerate(pols):
        pols[p]["normalized_score"] = {"iqm": {"value": 0.5 - k, "ci95": [0.4 - k, 0.6 - k]}}
    summary = {
        "run": {"seeds": [0], "policies": {"e": list(pols)}, "travel_budget": 2.0},
        "plants": {"steamtemp/A-v0": {"policies": pols}},
        "ranking": [],
    }
    plots.bars(tmp_path / "s.png", summary)
    (fig,) = figures
    labels = [t.get_text() for t in fig.axes[0].get_yticklabels()]
    assert labels == ["mpc_linear  1.2x", f"sb3:sac {report.INADMISSIBLE}  9.5x"]
    assert "above 2x" in fig.texts[0].get_text()  # the suptitle explains the labels


# --------------------------------------------------------------------------- markdown
def test_numbers_are_rounded_to_display_precision():
    assert report.num(-6.661e-17) == "0.00"
    assert report.num(-0.004) == "0.00"
    assert report.num(-0.006) == "-0.01"
    assert report.num(12345.678, 0) == "12346"
    assert report.num(79750.0, 1, 1e-3) == "79.8"
    assert report.num(None) == report.num(float("nan")) == "-"


def _rows() -> list[dict]:
    rows = []
    for p, base in (("cascade_pi_ff", -100.1), ("oracle", -40.0), ("mpc_linear", -50.0)):
        for seed in range(3):
            ret = base - 0.1 * seed  # the reference's mean normalized score: 7.9e-17, not 0
            rows.append(
                {
                    "env": "steamtemp/A-v0",
                    "scenario": "s",
                    "policy": p,
                    "seed": seed,
                    "metrics": {
                        "return": ret,
                        "tripped": 0.0,
                        "iae_K_s": 1234.5678,
                        "max_abs_dev_K": 3.14159,
                        "spray_used_kg": 79750.0,
                        "valve_travel": 3e-9,
                        "time_outside_5K_s": 0.0,
                    },
                }
            )
    return rows


def test_markdown_has_no_exponents_and_carries_units():
    run = {
        "envs": ["steamtemp/A-v0"],
        "scenarios": ["s"],
        "seeds": [0, 1, 2],
        "policies": {"steamtemp/A-v0": ["cascade_pi_ff", "oracle", "mpc_linear"]},
    }
    summary, _ = summarize(_rows(), run)
    text = report.markdown(summary, [])
    import re

    assert not re.search(r"\d[eE][+-]?\d", text), re.findall(r"\S*\d[eE][+-]?\d\S*", text)
    assert "-0.00" not in text
    header = next(ln for ln in text.splitlines() if ln.startswith("| policy | seeds"))
    for unit in (
        "IAE [K s]",
        "max\\|dev\\| [K]",
        "spray [t]",
        "valve travel [strokes]",
        "t>5K [s]",
    ):
        assert unit in header, header
    assert "| 1235 |" in text and "| 79.8 |" in text and "| 3.14 |" in text


def test_report_columns_cover_the_tables():
    assert set(TABLE_METRICS) <= set(report.COLUMNS)
    assert set(report.RANK_METRICS) <= set(report.COLUMNS)


def test_long_policy_names_keep_their_end_on_the_bars():
    """An agent's path or a factory is cut to its last characters on a bar's label."""
    path = "/home/me/runs/steamtemp__Cascade300MW-v0__ppo_residual__run2.zip"
    label = plots.short_name(path)
    assert len(label) == plots.LABEL_CHARS and label.startswith("…")
    assert label.endswith("ppo_residual__run2.zip")
    assert plots.short_name("cascade_pi_ff_tuned") == "cascade_pi_ff_tuned"


# --------------------------------------------------------------------------- pareto
def test_the_pareto_front_keeps_the_policies_no_other_beats_on_both():
    points = {
        "cheap": (0.5, -0.3),
        "ref": (1.0, 0.0),
        "worse": (1.2, -0.1),  # ref beats it
        "good": (1.5, 0.4),
        "same_travel_less": (1.5, 0.2),
        "best": (1.9, 0.8),
        "costly_no_gain": (1.95, 0.8),
        "twin": (1.5, 0.4),
    }
    assert pareto.pareto_front(points) == ["cheap", "ref", "good", "best"]  # "good" < "twin"
    assert pareto.pareto_front({}) == []
    assert pareto.pareto_front({"a": (1.0, 0.0)}) == ["a"]


def _pareto_summary(budget: float = 2.0) -> dict:
    """One plant: the reference, the oracle, the frozen valve (far below the axis), two
    policies on the front, one behind it, one over the budget that no admissible one beats
    and one over the budget that is beaten."""
    pts = {
        ZERO: (1.0, 0.0),
        "oracle": (0.6, 1.0),
        "frozen_valve": (0.0, -10.0),
        "cascade_pi_ff_tuned": (1.4, 0.25),
        "mpc_linear": (2.04, 0.76),
        "lqi": (2.1, 0.15),
        "fao_sf": (0.9, -0.5),
        "cascade_pi": (0.7, -0.4),
    }
    pols = {}
    for p, (travel, v) in pts.items():
        est = {"value": v, "ci95": [v - 0.05, v + 0.05]}
        pols[p] = {
            "travel_ratio": travel,
            "trips": 0,
            "failed": 0,
            "normalized_score": {"iqm": est},
        }
        if p not in REFERENCES:
            pols[p]["admissible"] = travel <= budget
            pols[p]["rank"] = 1
    return {
        "run": {"seeds": [0, 1], "travel_budget": budget, "policies": {"e": list(pols)}},
        "plants": {"steamtemp/A-v0": {"policies": pols}},
        "ranking": [],
    }


def test_the_pareto_figure_draws_the_budget_the_front_and_its_labels(figures, tmp_path):
    pareto.pareto(tmp_path / pareto.PARETO, _pareto_summary())
    (fig,) = figures
    ax = fig.axes[0]
    labels = {t.get_text() for t in ax.texts if t.get_text()}
    front = ["cascade_pi", ZERO, "cascade_pi_ff_tuned"]
    assert set(front) <= labels and "oracle" in labels
    assert f"mpc_linear {report.INADMISSIBLE} 2.04x" in labels  # over the budget, unbeaten
    assert "fao_sf" not in labels and not any(t.startswith("lqi") for t in labels)
    assert "frozen_valve (0.0x, -10.00)" in labels  # below the axis: at its edge, its value
    assert ax.get_ylim()[0] >= pareto.PARETO_FLOOR - 0.05
    budget = [ln for ln in ax.get_lines() if list(ln.get_xdata()) == [2.0, 2.0]]
    assert len(budget) == 1 and budget[0].get_linestyle() == "--"
    (stairs,) = [ln for ln in ax.get_lines() if ln.get_label().startswith("Pareto front")]
    xs, ys = stairs.get_xdata(), stairs.get_ydata()
    assert list(xs) == [0.7, 1.0, 1.4, 2.0] and list(ys) == [-0.4, 0.0, 0.25, 0.25]
    assert "valve travel" in ax.get_xlabel() and "normalized score" in ax.get_ylabel()


def test_the_labels_of_the_pareto_figure_do_not_overlap(figures, tmp_path):
    """Eight front policies crowded together: every label is placed apart from the others."""
    s = _pareto_summary()
    pols = s["plants"]["steamtemp/A-v0"]["policies"]
    for k in range(8):
        v = 0.05 * k
        est = {"value": 0.26 + v, "ci95": [0.25 + v, 0.27 + v]}
        pols[f"policy_{k}"] = {
            "travel_ratio": 1.45 + 0.02 * k,
            "trips": 0,
            "failed": 0,
            "admissible": True,
            "rank": 1,
            "normalized_score": {"iqm": est},
        }
    s["run"]["policies"]["e"] = list(pols)
    pareto.pareto(tmp_path / pareto.PARETO, s)
    (fig,) = figures
    ax = fig.axes[0]
    renderer = fig.canvas.get_renderer()
    boxes = [
        t.get_window_extent(renderer)
        for t in ax.texts
        if t.get_text() and not t.get_text().startswith(" budget")
    ]
    assert len(boxes) >= 11
    overlaps = [(a, b) for i, a in enumerate(boxes) for b in boxes[i + 1 :] if a.overlaps(b)]
    assert not overlaps


def test_the_rebuild_writes_the_pareto_figure(tmp_path):
    """A real file from the summary of hand-made rows, as outputs.rebuild draws it."""
    run = {
        "envs": ["steamtemp/A-v0"],
        "scenarios": ["s"],
        "seeds": [0, 1, 2],
        "policies": {"steamtemp/A-v0": ["cascade_pi_ff", "oracle", "mpc_linear"]},
        "travel_budget": 2.0,
    }
    rows = _rows()
    for r in rows:
        r["metrics"]["valve_travel"] = 1.0 if r["policy"] != "mpc_linear" else 2.5
    summary, _ = summarize(rows, run)
    path = pareto.pareto(tmp_path / "plots" / pareto.PARETO, summary)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
