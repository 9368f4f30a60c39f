"""DCS-style trend display: outlet temperature against setpoint with +-5 / +-8 K
bands, load, and valve openings / spray flow over the episode so far."""

from __future__ import annotations

from typing import Any

import numpy as np

BANDS_K = (5.0, 8.0)


def trend_figure(history: list[dict[str, Any]], title: str = ""):
    """A matplotlib Figure of an episode's info dicts (one per step)."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    t = np.array([h["time_s"] for h in history]) / 60.0
    fig = Figure(figsize=(8, 6), dpi=80)
    ax1, ax2, ax3 = fig.subplots(3, 1, sharex=True, gridspec_kw={"height_ratios": [2, 1, 1]})
    sp = np.array([h["setpoint_C"] for h in history])
    for band, alpha in zip(BANDS_K, (0.25, 0.12), strict=True):
        ax1.fill_between(t, sp - band, sp + band, color="tab:green", alpha=alpha, lw=0,
                         label=f"+-{band:g} K")  # fmt: skip
    ax1.plot(t, sp, "k--", lw=1, label="setpoint")
    ax1.plot(t, [h["outlet_temp_C"] for h in history], "tab:red", lw=1.5, label="outlet (true)")
    ax1.plot(t, [h["measured_temp_C"] for h in history], "tab:orange", lw=0.8, label="measured")
    ax1.set_ylabel("main steam [C]")
    ax1.legend(loc="upper right", fontsize=7, ncol=3)
    ax1.grid(alpha=0.3)
    ax2.plot(t, 100 * np.array([h["load"] for h in history]), "tab:blue")
    ax2.set_ylabel("load demand [%]")
    ax2.grid(alpha=0.3)
    valves = np.array([np.atleast_1d(h["spray_valve"]) for h in history]) * 100
    for j in range(valves.shape[1] if valves.ndim == 2 else 0):
        ax3.plot(t, valves[:, j], lw=1.2, label=f"valve {j + 1} [%]")
    ax3b = ax3.twinx()
    ax3b.plot(t, [h["spray_flow_kg_s"] for h in history], "tab:gray", lw=0.8)
    ax3b.set_ylabel("spray [kg/s]", color="tab:gray")
    ax3.set_ylabel("valve [%]")
    ax3.set_ylim(-5, 105)
    ax3.set_xlabel("time [min]")
    ax3.grid(alpha=0.3)
    if title:
        ax1.set_title(title, fontsize=9)
    fig.tight_layout()
    return fig


def figure_to_rgb(fig) -> np.ndarray:
    """Render a Figure to an (H, W, 3) uint8 array."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[:, :, :3].copy()


def trend_image(history: list[dict[str, Any]], plant: Any, scenario: Any) -> np.ndarray:
    """The trend display of an env's episode so far as an RGB array."""
    name = getattr(scenario, "name", "")
    return figure_to_rgb(trend_figure(history, f"{plant.id}  scenario: {name}"))
