"""DCS-style trend display of ``render_mode="rgb_array"``: the main-steam temperature
(true and measured) against its setpoint with the +-5 / +-8 K bands, every other scored
temperature (``Plant.secondary``, e.g. the reheat) against its setpoint with the same
bands, the load demand, and every actuator's opening (sprays, dampers; named as in
``signals.action``) with the total spray flow, over the whole episode.

Like a DCS trend, the axes are fixed for the episode (time over the scenario's duration,
each temperature over its setpoint at reset +-30 K, openings 0-100 %, spray flow 0 to the
plant's spray range), so matplotlib draws the frame, its labels and legends once per
episode (:class:`TrendDisplay`); each step then rasterizes only its new segments into
the image (a few pixel columns), and ``render()`` returns a copy: ~0.2 ms per frame
instead of ~160 ms for a matplotlib redraw (benchmarks/render_speed.py). Values outside
an axis are drawn at its edge.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

BANDS_K = (5.0, 8.0)
#: frame size (pixels): 8 x 6 in at 80 dpi
WIDTH, HEIGHT, DPI = 640, 480, 80
#: temperature axis half-width around the setpoint at reset, K
SPAN_K = 30.0
_BAND_COLORS = ("#bfe3bf", "#e5f3e5")  # +-5 K, +-8 K (green at alpha 0.25 / 0.12 on white)
VALVE_COLORS = ("tab:purple", "tab:brown", "tab:olive", "tab:cyan", "tab:pink", "tab:green")


def rgb(color: str) -> np.ndarray:
    from matplotlib.colors import to_rgb

    return np.array([round(255 * c) for c in to_rgb(color)], dtype=np.uint8)


class _Axis:
    """Pixel mapping of one matplotlib axes (data -> image column / row)."""

    def __init__(self, ax, xlim: tuple[float, float], ylim: tuple[float, float]) -> None:
        box = ax.get_window_extent()
        self.left, self.right = box.x0, box.x1
        self.top, self.bottom = HEIGHT - box.y1, HEIGHT - box.y0
        self.xlim, self.ylim = xlim, ylim
        self.rows = (math.ceil(self.top), math.floor(self.bottom))

    def x(self, v: float) -> float:
        return self.left + (v - self.xlim[0]) / (self.xlim[1] - self.xlim[0]) * (
            self.right - self.left
        )

    def y(self, v: float) -> float:
        y = self.bottom - (v - self.ylim[0]) / (self.ylim[1] - self.ylim[0]) * (
            self.bottom - self.top
        )
        return min(max(y, self.top), self.bottom) if math.isfinite(y) else self.bottom


class TrendDisplay:
    """One episode's trend image, drawn incrementally.

    Args:
        title: Figure title (plant id and scenario).
        duration_s: Episode length (the time axis).
        first: The info dict at reset (setpoint, valves, secondary temperatures).
        spray_max_kg_s: Top of the spray-flow axis.
        valve_names: Legend names of the actuators (``info["spray_valve"]`` order).
        secondary: The other scored temperatures as (info key, setpoint in °C), one panel
            each (``Plant.secondary``).
    """

    def __init__(
        self,
        title: str,
        duration_s: float,
        first: dict[str, Any],
        spray_max_kg_s: float,
        valve_names: tuple[str, ...] = (),
        secondary: tuple[tuple[str, float], ...] = (),
    ) -> None:
        n_valves = np.atleast_1d(first["spray_valve"]).size
        self.secondary = tuple(secondary)
        self.t_max = max(duration_s, 1.0) / 60.0
        self.valve_names = tuple(
            valve_names[j] if j < len(valve_names) else f"actuator {j + 1}" for j in range(n_valves)
        )
        self.background, frame = self._draw_frame(title, float(first["setpoint_C"]), spray_max_kg_s)
        xl = (0.0, self.t_max)
        self.axes = [_Axis(ax, xl, ylim) for ax, ylim in frame]
        self.colors = {
            "true": rgb("tab:red"),
            "meas": rgb("tab:orange"),
            "sp": rgb("black"),
            "load": rgb("tab:blue"),
            "spray": rgb("tab:gray"),
        }
        self.valve_colors = [rgb(VALVE_COLORS[j % len(VALVE_COLORS)]) for j in range(n_valves)]
        self.bands = [rgb(c) for c in _BAND_COLORS]
        self.image = self.background.copy()
        self.last: dict[str, Any] | None = None
        self.filled = -1  # last image column with bands drawn
        self.add(first)

    def _draw_frame(
        self, title: str, sp0: float, spray_max_kg_s: float
    ) -> tuple[np.ndarray, list[tuple[Any, tuple[float, float]]]]:
        """What stays fixed over the episode (axes, labels, legends), drawn once: the image,
        (HEIGHT, WIDTH, 3) uint8, and each axes with its y-limits in the order of
        ``self.axes`` (main steam, the secondary temperatures, load, openings, spray flow)."""
        import matplotlib

        matplotlib.use("Agg", force=False)
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        fig = Figure(figsize=(WIDTH / DPI, HEIGHT / DPI), dpi=DPI)
        n_sec = len(self.secondary)
        ratios = [2.0] + [1.1] * n_sec + [0.8, 1.3]
        axs = fig.subplots(len(ratios), 1, sharex=True, gridspec_kw={"height_ratios": ratios})
        ax1, sec_axes, ax2, ax3 = axs[0], list(axs[1 : 1 + n_sec]), axs[-2], axs[-1]
        ax3b = ax3.twinx()
        temps = [(ax1, (sp0 - SPAN_K, sp0 + SPAN_K))] + [
            (ax, (sp2 - SPAN_K, sp2 + SPAN_K))
            for ax, (_, sp2) in zip(sec_axes, self.secondary, strict=True)
        ]
        frame = [
            *temps,
            (ax2, (0.0, 110.0)),
            (ax3, (-5.0, 105.0)),
            (ax3b, (0.0, max(spray_max_kg_s, 1e-3))),
        ]
        for ax, ylim in frame:
            ax.set_xlim(0.0, self.t_max)
            ax.set_ylim(*ylim)
        for ax in (ax1, *sec_axes, ax2, ax3):
            ax.grid(alpha=0.3)
        ax1.set_ylabel("main steam [°C]")
        for ax, (key, _) in zip(sec_axes, self.secondary, strict=True):
            ax.set_ylabel(key.removesuffix("_temp_C").replace("_", " ") + " [°C]")
        ax2.set_ylabel("load [%]")
        ax3.set_ylabel("opening [%]")
        ax3b.set_ylabel("spray [kg/s]", color="tab:gray")
        ax3.set_xlabel("time [min]")
        ax1.set_title(title, fontsize=9)
        self._draw_legends(ax1, ax3)
        fig.tight_layout(h_pad=0.3)
        canvas = FigureCanvasAgg(fig)
        canvas.draw()
        return np.asarray(canvas.buffer_rgba())[:, :, :3].copy(), frame

    def _draw_legends(self, ax1: Any, ax3: Any) -> None:
        """The legends: the main-steam panel's lines and bands over it, the actuators'
        openings and the spray flow above the bottom panel."""
        from matplotlib.lines import Line2D
        from matplotlib.patches import Patch

        small = {
            "fontsize": 7,
            "frameon": False,
            "borderaxespad": 0.1,
            "handlelength": 1.5,
            "columnspacing": 1.0,
        }
        ax1.legend(
            handles=[
                Line2D([], [], color="tab:red", lw=2, label="true"),
                Line2D([], [], color="tab:orange", lw=1, label="measured"),
                Line2D([], [], color="k", lw=1, label="setpoint"),
                Patch(color=_BAND_COLORS[0], label="±5 K"),
                Patch(color=_BAND_COLORS[1], label="±8 K"),
            ],
            loc="lower right",
            ncol=5,
            **dict(small, frameon=True),
        )
        ax3.legend(
            handles=[
                *(
                    Line2D([], [], color=VALVE_COLORS[j % len(VALVE_COLORS)], lw=1, label=name)
                    for j, name in enumerate(self.valve_names)
                ),
                Line2D([], [], color="tab:gray", lw=1, label="spray flow"),
            ],
            loc="lower left",
            bbox_to_anchor=(0.0, 1.0),
            ncol=min(len(self.valve_names) + 1, 4),
            **small,
        )

    def frame(self) -> np.ndarray:
        """The image so far, (HEIGHT, WIDTH, 3) uint8 (a copy)."""
        return self.image.copy()

    def add(self, info: dict[str, Any]) -> None:
        """Draw the segment from the previous step to ``info``."""
        prev = self.last or info
        t0, t1 = prev["time_s"] / 60.0, info["time_s"] / 60.0
        temp, *sec, load, act, spray = self.axes
        c1 = self._columns(temp, t1)
        self._bands(temp, c1, float(info["setpoint_C"]))
        pairs = [
            (temp, "setpoint_C", self.colors["sp"], 1, 1.0),
            (temp, "measured_temp_C", self.colors["meas"], 1, 1.0),
            (temp, "outlet_temp_C", self.colors["true"], 2, 1.0),
            (load, "load", self.colors["load"], 1, 100.0),
            (spray, "spray_flow_kg_s", self.colors["spray"], 1, 1.0),
        ]
        for ax, (key, sp2) in zip(sec, self.secondary, strict=True):
            self._bands(ax, c1, sp2)
            self._segment(ax, t0, sp2, t1, sp2, self.colors["sp"], 1)
            pairs.append((ax, key, self.colors["true"], 2, 1.0))
        self.filled = max(self.filled, c1)
        for ax, key, color, width, scale in pairs:
            self._segment(
                ax, t0, scale * float(prev[key]), t1, scale * float(info[key]), color, width
            )
        v0, v1 = np.atleast_1d(prev["spray_valve"]), np.atleast_1d(info["spray_valve"])
        for j, color in enumerate(self.valve_colors):
            self._segment(act, t0, 100.0 * v0[j], t1, 100.0 * v1[j], color, 1)
        self.last = info

    def _columns(self, ax: _Axis, t1: float) -> int:
        """The last image column up to time t1 (all temperature panels share the columns)."""
        return min(round(ax.x(t1)), math.floor(ax.right))

    def _bands(self, ax: _Axis, c1: int, sp: float) -> None:
        """The +-8 / +-5 K bands around ``sp`` in the columns not yet filled up to c1."""
        c0 = max(self.filled + 1, math.ceil(ax.left))
        if c1 < c0:
            return
        for band, color in zip(reversed(BANDS_K), reversed(self.bands), strict=True):
            r0, r1 = round(ax.y(sp + band)), round(ax.y(sp - band))
            self.image[r0 : r1 + 1, c0 : c1 + 1] = color

    def _segment(
        self, ax: _Axis, t0: float, v0: float, t1: float, v1: float, color: np.ndarray, width: int
    ) -> None:
        """A line from (t0, v0) to (t1, v1): per image column, a vertical run joining the
        previous column's height to this one's (continuous at any slope)."""
        x0, x1 = ax.x(t0), ax.x(t1)
        y0, y1 = ax.y(v0), ax.y(v1)
        c0, c1 = max(round(x0), math.ceil(ax.left)), min(round(x1), math.floor(ax.right))
        lo_row, hi_row = ax.rows
        y_prev = y0
        for c in range(c0, c1 + 1):
            y = y1 if x1 <= x0 else y0 + (y1 - y0) * min(max((c - x0) / (x1 - x0), 0.0), 1.0)
            a = max(math.floor(min(y, y_prev) - (width - 1) / 2), lo_row)
            b = min(math.ceil(max(y, y_prev) + (width - 1) / 2), hi_row)
            self.image[a : b + 1, c] = color
            y_prev = y


def spray_range(plant: Any) -> float:
    """Top of the spray-flow axis: the sum of the plant's spray signals' ranges (kg/s)."""
    sig = {s.name: s for s in plant.outputs}
    return float(sum(sig[n].center + sig[n].scale for n in plant.sprays if n in sig))
