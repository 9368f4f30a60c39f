"""The leaderboard's figures (150 dpi, 10-11 pt text), written by agents/leaderboard.py.

- :func:`trend`: one plant and scenario, one episode (seed stated in the title) of every
  policy: the true outlet temperature against the setpoint with the +-5 / +-8 K bands
  (and the thermocouple reading of the first policy, labelled as such), the plant's
  secondary temperatures (reheat), one panel per actuator (names from
  ``env.unwrapped.signals.action``), the load demand and the disturbances that act in
  the scenario.
- :func:`bars`: per plant, the IQM of the normalized score of each policy with its 95 %
  stratified-bootstrap confidence interval.
- :func:`profiles`: per plant, performance profiles (fraction of runs above a normalized
  score, averaged over scenarios).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from agents import stats
from agents.leaderboard_report import ONE, ZERO
from steamtemp_gym.envs.render import BANDS_K

DPI = 150
_RC = {"font.size": 10, "axes.titlesize": 11, "axes.labelsize": 10, "legend.fontsize": 9,
       "xtick.labelsize": 9, "ytick.labelsize": 9}  # fmt: skip
_BAND_ALPHA = (0.22, 0.10)
#: Disturbances shown when they vary: key -> (label, scale to the plotted unit, offset).
_DIST = {
    "heat_absorption_bias": ("heat-absorption\ndisturbance [%]", 100.0, 0.0),
    "fouling": ("gas-side heat-transfer multiplier - 1 [%]", 100.0, -1.0),
    "spray_water_temp_offset_C": ("spray-water temperature offset [K]", 1.0, 0.0),
}


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _short(env_id: str) -> str:
    return env_id.split("/")[-1]


def actuator_labels(env: Any) -> list[str]:
    """The description of each action signal (e.g. 'secondary spray SP2 valve')."""
    out = []
    for s in env.unwrapped.signals.action:
        text = (getattr(s, "description", "") or s.name).removesuffix(" command")
        out.append(text)
    return out


def trend(
    path: Path, env: Any, env_id: str, scenario: str, traces: dict[str, dict], seed: int,
    reference: tuple[str, ...] = ("frozen_valve", "oracle"),
) -> Path:
    """The trend overlay of one plant and scenario (see the module docstring)."""
    plt = _plt()
    plant = env.unwrapped.plant
    acts = actuator_labels(env)
    first = next(iter(traces.values()))
    varying = [k for k in _DIST if k != "heat_absorption_bias" and np.ptp(first[k]) > 1e-9]
    n = 1 + len(plant.secondary) + len(acts) + 1 + (1 if varying else 0)
    ratios = [2.4] + [1.2] * (n - 1)
    with plt.rc_context(_RC):
        fig, axes = plt.subplots(n, 1, figsize=(10, 2.0 + 1.7 * n), sharex=True,
                                 gridspec_kw={"height_ratios": ratios})  # fmt: skip
        ax = axes[0]
        t = first["time_s"] / 60.0
        sp = first["setpoint_C"]
        for band, alpha in zip(BANDS_K, _BAND_ALPHA, strict=True):
            ax.fill_between(t, sp - band, sp + band, color="tab:green", alpha=alpha, lw=0,
                            label=f"setpoint ±{band:g} K band")  # fmt: skip
        ax.plot(t, sp, "k--", lw=1.2, label="setpoint")
        # one distinct colour per policy: tab10 repeats after ten, tab20 holds twenty
        n_pol = sum(name != reference for name in traces)
        palette = plt.get_cmap("tab10" if n_pol <= 10 else "tab20").colors
        colors = {}
        k = 0
        for name, tr in traces.items():
            ref = name == reference
            colors[name] = "0.45" if ref else palette[k % len(palette)]
            k += 0 if ref else 1
            ax.plot(tr["time_s"] / 60, tr["outlet_temp_C"], lw=1.2 if ref else 1.4,
                    color=colors[name], ls=":" if ref else "-",
                    label=f"{name}: true" + (" (reference)" if ref else ""))  # fmt: skip
        # y range: the controllers and the bands; the reference may leave the axes
        ctrl = [tr["outlet_temp_C"] - tr["setpoint_C"] for n, tr in traces.items()
                if n != reference] or [first["outlet_temp_C"] - sp]  # fmt: skip
        dev = max(BANDS_K[-1] + 2.0, 1.1 * max(float(np.max(np.abs(e))) for e in ctrl))
        ax.set_ylim(float(sp.min()) - dev, float(sp.max()) + dev)
        name0 = next(iter(traces))
        ax.plot(first["time_s"] / 60, first["measured_temp_C"], color=colors[name0], lw=0.6,
                alpha=0.5, label=f"{name0}: measured (thermocouple)")  # fmt: skip
        ax.set_ylabel("main steam outlet [°C]")
        # outside the axes and out of tight_layout (a tall legend would spread the panels);
        # savefig is told to keep it in the image
        legends = [ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)]
        ax.set_title(f"{_short(env_id)} - {scenario}: one episode per policy (seed {seed})")
        i = 1
        for (key, sp2), axk in zip(plant.secondary, axes[1:], strict=False):
            for band, alpha in zip(BANDS_K, _BAND_ALPHA, strict=True):
                axk.axhspan(sp2 - band, sp2 + band, color="tab:green", alpha=alpha, lw=0)
            axk.axhline(sp2, color="k", ls="--", lw=1)
            for name, tr in traces.items():
                axk.plot(tr["time_s"] / 60, tr[key], lw=1.2, color=colors[name],
                         ls=":" if name == reference else "-")  # fmt: skip
            axk.set_ylabel(key.replace("_temp_C", "").replace("_", " ") + " (true) [°C]")
            e2 = [tr[key] - sp2 for n, tr in traces.items() if n != reference] or [first[key] - sp2]
            d2 = max(BANDS_K[-1] + 2.0, 1.1 * max(float(np.max(np.abs(e))) for e in e2))
            axk.set_ylim(sp2 - d2, sp2 + d2)
            i += 1
        for j, label in enumerate(acts):
            axk = axes[i + j]
            for name, tr in traces.items():
                v = np.asarray(tr["spray_valve"]).reshape(len(tr["time_s"]), -1)
                axk.plot(tr["time_s"] / 60, 100 * v[:, j], lw=1.1, color=colors[name],
                         ls=":" if name == reference else "-")  # fmt: skip
            axk.set_ylabel("opening [%]")
            axk.text(0.01, 0.95, label, transform=axk.transAxes, va="top", fontsize=10,
                     bbox={"facecolor": "white", "alpha": 0.8, "lw": 0})  # fmt: skip
            axk.set_ylim(-5, 105)
        i += len(acts)
        axk = axes[i]
        axk.plot(t, 100 * first["load"], color="tab:blue", lw=1.4, label="load demand [%]")
        axk.set_ylabel("load demand [%]", color="tab:blue")
        axk.set_ylim(0, 110)
        lab, scale, off = _DIST["heat_absorption_bias"]
        axd = axk.twinx()
        axd.plot(t, scale * (first["heat_absorption_bias"] + off), color="tab:brown", lw=0.9)
        axd.set_ylabel(lab, color="tab:brown")
        if varying:
            axv = axes[i + 1]
            for k in varying:
                lab, scale, off = _DIST[k]
                axv.plot(t, scale * (first[k] + off), lw=1.4, label=lab)
            axv.set_ylabel("disturbance")
            legends.append(axv.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0),
                                      borderaxespad=0))  # fmt: skip
        for a in axes:
            a.grid(alpha=0.3)
        axes[-1].set_xlabel("time [min]")
        fig.align_ylabels(axes)
        for leg in legends:
            leg.set_in_layout(False)
        fig.tight_layout()
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=DPI, bbox_inches="tight", bbox_extra_artists=legends)
        plt.close(fig)
    return path


def _grid(n: int):
    cols = min(n, 3)
    rows = (n + cols - 1) // cols
    return rows, cols


def bars(path: Path, summary: dict[str, Any]) -> Path:
    """IQM normalized score with 95 % CIs, one panel per plant, policies by rank."""
    plt = _plt()
    plants = list(summary["plants"])
    rows, cols = _grid(len(plants))
    with plt.rc_context(_RC):
        fig, axes = plt.subplots(rows, cols, figsize=(5.2 * cols, 3.6 * rows), squeeze=False)
        for ax, env_id in zip(axes.flat, plants, strict=False):
            pols = summary["plants"][env_id]["policies"]
            ranked = sorted((p for p in pols if "rank" in pols[p]), key=lambda p: pols[p]["rank"])
            vals = [pols[p]["normalized_score"]["iqm"] for p in ranked]
            y = np.arange(len(ranked))
            x = [v["value"] for v in vals]
            err = np.array([[v["value"] - v["ci95"][0], v["ci95"][1] - v["value"]] for v in vals])
            ax.barh(y, x, xerr=err.T if len(vals) else None, color="tab:blue", alpha=0.75,
                    capsize=3)  # fmt: skip
            ax.set_yticks(y, ranked)
            ax.invert_yaxis()
            ax.axvline(0, color="k", lw=0.8)
            ax.axvline(1, color="k", lw=0.8, ls="--")
            ax.set_title(_short(env_id))
            ax.set_xlabel(f"IQM normalized score (0 = {ZERO}, 1 = {ONE})")
            ax.grid(axis="x", alpha=0.3)
        for ax in list(axes.flat)[len(plants):]:
            ax.axis("off")
        n_seeds = summary["run"]["seeds"]
        fig.suptitle(f"IQM over scenario × seed ({len(n_seeds)} seeds), "
                     "95 % stratified-bootstrap CI")  # fmt: skip
        fig.tight_layout()
        fig.savefig(path, dpi=DPI)
        plt.close(fig)
    return path


def profiles(
    path: Path, scores: dict[str, dict[str, list[np.ndarray]]], n_seeds: int,
    reference: tuple[str, ...] = ("frozen_valve", "oracle"),
) -> Path:
    """Performance profiles: ``scores[env][policy]`` = normalized scores per scenario."""
    plt = _plt()
    plants = list(scores)
    rows, cols = _grid(len(plants))
    with plt.rc_context(_RC):
        fig, axes = plt.subplots(rows, cols, figsize=(5.2 * cols, 3.6 * rows), squeeze=False)
        for ax, env_id in zip(axes.flat, plants, strict=False):
            ctrl = [np.concatenate(t) for p, t in scores[env_id].items() if p not in reference]
            lo = min([0.0] + [float(c.min()) for c in ctrl if c.size])
            hi = max([1.0] + [float(c.max()) for c in ctrl if c.size])
            pad = 0.05 * (hi - lo)
            taus = np.linspace(lo - pad, hi + pad, 401)
            for pol, tasks in scores[env_id].items():
                if any(len(t) for t in tasks):
                    ref = pol in reference
                    ax.plot(taus, stats.performance_profile(tasks, taus), lw=1.4, label=pol,
                            color="0.45" if ref else None, ls=":" if ref else "-")  # fmt: skip
            ax.axvline(0, color="k", lw=0.8)
            ax.axvline(1, color="k", lw=0.8, ls="--")
            ax.set_title(_short(env_id))
            ax.set_xlabel("normalized score τ")
            ax.set_ylabel("fraction of runs > τ")
            ax.grid(alpha=0.3)
        handles, labels = axes.flat[0].get_legend_handles_labels()
        spare = list(axes.flat)[len(plants):]
        for ax in spare:
            ax.axis("off")
        if spare:
            spare[0].legend(handles, labels, loc="center", ncol=2)
        else:
            fig.legend(handles, labels, loc="center left", bbox_to_anchor=(1.0, 0.5))
        fig.suptitle(f"Performance profiles over scenario × seed ({n_seeds} seeds); "
                     f"0 = {ZERO}, 1 = {ONE}")  # fmt: skip
        fig.tight_layout()
        fig.savefig(path, dpi=DPI, bbox_inches="tight")
        plt.close(fig)
    return path
