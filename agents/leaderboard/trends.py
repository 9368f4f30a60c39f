"""The trend figure of the leaderboard (150 dpi, 10-11 pt text), written by
agents/leaderboard/outputs.py: one plant and scenario, one episode (seed stated in the title)
of each policy shown (agents/leaderboard/plots.py ``trend_policies``): the true outlet
temperature against the setpoint with the +-5 / +-8 K bands (and the thermocouple reading of
the first policy, labelled as such), the plant's secondary temperatures (reheat), one panel
per actuator (names from ``env.unwrapped.signals.action``), the load demand and the
disturbances that act in the scenario. Colours and line styles are those of
agents/leaderboard/plots.py.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from agents.leaderboard import plots
from steamtemp_gym.envs.render import BANDS_K

_BAND_ALPHA = (0.22, 0.10)
#: Disturbances shown when they vary: key -> (label, scale to the plotted unit, offset).
_DIST = {
    "heat_absorption_bias": ("heat-absorption\ndisturbance [%]", 100.0, 0.0),
    "fouling": ("gas-side heat-transfer multiplier - 1 [%]", 100.0, -1.0),
    "spray_water_temp_offset_C": ("spray-water temperature offset [K]", 1.0, 0.0),
}
#: Colours of the disturbances (yellows and browns, outside both policy families).
_DIST_COLORS = ("#b8860b", "#808000", "#d4a017")


def actuator_labels(env: Any) -> list[str]:
    """The description of each action signal (e.g. 'secondary spray SP2 valve')."""
    out = []
    for s in env.unwrapped.signals.action:
        text = (getattr(s, "description", "") or s.name).removesuffix(" command")
        out.append(text)
    return out


def trend(
    path: Path,
    env: Any,
    env_id: str,
    scenario: str,
    traces: dict[str, dict],
    seed: int,
    colors: dict[str, str] | None = None,
    notes: dict[str, str] | None = None,
) -> Path:
    """The trend overlay of one plant and scenario (see the module docstring).

    Args:
        path: The PNG to write.
        env: The env (its plant's secondary temperatures and actuators label the panels).
        env_id: The env id (title).
        scenario: The scenario's name (title).
        traces: Policy name -> the trace of its episode (``run_episode``), in legend order.
        seed: The episode's seed (title).
        colors: Policy name -> colour (default: ``plots.policy_colors`` of ``traces``).
        notes: Policy name -> a note for its legend entry (e.g. its score).
    """
    plt = plots.pyplot()
    plant = env.unwrapped.plant
    acts = actuator_labels(env)
    colors = colors or plots.policy_colors(list(traces))
    notes = notes or {}
    styles = {name: plots.line_style(name, colors[name]) for name in traces}
    first = next(iter(traces.values()))
    varying = [k for k in _DIST if k != "heat_absorption_bias" and np.ptp(first[k]) > 1e-9]
    n = 1 + len(plant.secondary) + len(acts) + 1 + (1 if varying else 0)
    ratios = [2.4] + [1.2] * (n - 1)
    # y ranges: the controllers and the bands; the frozen valve may leave the axes
    ranged = [name for name in traces if name != "frozen_valve"] or list(traces)
    with plt.rc_context(plots.RC):
        fig, axes = plt.subplots(
            n, 1, figsize=(10, 2.0 + 1.7 * n), sharex=True, gridspec_kw={"height_ratios": ratios}
        )
        legends = [_outlet_panel(axes[0], traces, styles, colors, notes, ranged)]
        axes[0].set_title(
            f"{plots.short_env(env_id)} - {scenario}: one episode per policy (seed {seed})"
        )
        i = 1
        for (key, sp2), axk in zip(plant.secondary, axes[1:], strict=False):
            _secondary_panel(axk, key, sp2, traces, styles, ranged)
            i += 1
        for j, label in enumerate(acts):
            _actuator_panel(axes[i + j], j, label, traces, styles)
        i += len(acts)
        _load_panel(axes[i], first)
        if varying:
            legends.append(_disturbance_panel(axes[i + 1], first, varying))
        for a in axes:
            a.grid(alpha=0.3)
        axes[-1].set_xlabel("time [min]")
        fig.align_ylabels(axes)
        for leg in legends:
            leg.set_in_layout(False)
        fig.tight_layout()
        plots.save(fig, path, bbox_inches="tight", bbox_extra_artists=legends)
    return path


def _outlet_panel(
    ax: Any,
    traces: dict[str, dict],
    styles: dict[str, dict],
    colors: dict[str, str],
    notes: dict[str, str],
    ranged: list[str],
) -> Any:
    """The trend's top panel: the main steam outlet temperature of each policy against the
    setpoint and its bands, with the first policy's thermocouple reading; its legend."""
    first = next(iter(traces.values()))
    t = first["time_s"] / 60.0
    sp = first["setpoint_C"]
    for band, alpha in zip(BANDS_K, _BAND_ALPHA, strict=True):
        ax.fill_between(
            t,
            sp - band,
            sp + band,
            color="tab:green",
            alpha=alpha,
            lw=0,
            label=f"setpoint ±{band:g} K band",
        )
    ax.plot(t, sp, "k--", lw=1.2, label="setpoint")
    for name, tr in traces.items():
        note = f" ({notes[name]})" if notes.get(name) else ""
        ax.plot(tr["time_s"] / 60, tr["outlet_temp_C"], label=f"{name}{note}: true", **styles[name])
    dev = max(
        BANDS_K[-1] + 2.0,
        1.1
        * max(
            float(np.max(np.abs(traces[k]["outlet_temp_C"] - traces[k]["setpoint_C"])))
            for k in ranged
        ),
    )
    ax.set_ylim(float(sp.min()) - dev, float(sp.max()) + dev)
    name0 = next(iter(traces))
    ax.plot(
        first["time_s"] / 60,
        first["measured_temp_C"],
        color=colors[name0],
        lw=0.6,
        alpha=0.5,
        label=f"{name0}: measured (thermocouple)",
    )
    ax.set_ylabel("main steam outlet [°C]")
    # outside the axes and out of tight_layout (a tall legend would spread the panels);
    # savefig is told to keep it in the image
    return ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)


def _secondary_panel(
    axk: Any,
    key: str,
    sp2: float,
    traces: dict[str, dict],
    styles: dict[str, dict],
    ranged: list[str],
) -> None:
    """A panel of one of the plant's secondary temperatures (reheat) against its setpoint."""
    for band, alpha in zip(BANDS_K, _BAND_ALPHA, strict=True):
        axk.axhspan(sp2 - band, sp2 + band, color="tab:green", alpha=alpha, lw=0)
    axk.axhline(sp2, color="k", ls="--", lw=1)
    for name, tr in traces.items():
        axk.plot(tr["time_s"] / 60, tr[key], **dict(styles[name], lw=1.2))
    axk.set_ylabel(key.replace("_temp_C", "").replace("_", " ") + " (true) [°C]")
    d2 = max(
        BANDS_K[-1] + 2.0, 1.1 * max(float(np.max(np.abs(traces[k][key] - sp2))) for k in ranged)
    )
    axk.set_ylim(sp2 - d2, sp2 + d2)


def _actuator_panel(
    axk: Any, j: int, label: str, traces: dict[str, dict], styles: dict[str, dict]
) -> None:
    """A panel of actuator ``j``'s opening, labelled ``label``."""
    for name, tr in traces.items():
        v = np.asarray(tr["spray_valve"]).reshape(len(tr["time_s"]), -1)
        axk.plot(tr["time_s"] / 60, 100 * v[:, j], **dict(styles[name], lw=1.1))
    axk.set_ylabel("opening [%]")
    axk.text(
        0.01,
        0.95,
        label,
        transform=axk.transAxes,
        va="top",
        fontsize=10,
        bbox={"facecolor": "white", "alpha": 0.8, "lw": 0},
    )
    axk.set_ylim(-5, 105)


def _load_panel(axk: Any, first: dict) -> None:
    """The load demand, with the heat-absorption disturbance on a second axis."""
    t = first["time_s"] / 60.0
    axk.plot(t, 100 * first["load"], color="0.25", lw=1.4, label="load demand [%]")
    axk.set_ylabel("load demand [%]", color="0.25")
    axk.set_ylim(0, 110)
    lab, scale, off = _DIST["heat_absorption_bias"]
    axd = axk.twinx()
    axd.plot(t, scale * (first["heat_absorption_bias"] + off), color=_DIST_COLORS[0], lw=0.9)
    axd.set_ylabel(lab, color=_DIST_COLORS[0])


def _disturbance_panel(axv: Any, first: dict, varying: list[str]) -> Any:
    """The other disturbances that vary in the scenario; the panel's legend."""
    t = first["time_s"] / 60.0
    for k, color in zip(varying, _DIST_COLORS[1:], strict=False):
        lab, scale, off = _DIST[k]
        axv.plot(t, scale * (first[k] + off), lw=1.4, color=color, label=lab)
    axv.set_ylabel("disturbance")
    return axv.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
