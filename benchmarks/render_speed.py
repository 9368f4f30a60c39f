"""Cost of ``render_mode="rgb_array"`` per frame, for every env id.

Each id: one episode of the ``load_ramp_100_50`` scenario with a random-walk action,
``render()`` after every step; the median and worst frame in ms, and the whole episode
(steps plus a frame each, as Gymnasium's ``RecordVideo`` asks for them) in s, and the
reset, which draws the display's axes and legends once per episode.
Reference, measured in the same run: one matplotlib Agg redraw of the same-size figure
(what a display that redraws its plot per frame pays; the suite did so until 2026-11).

Usage: ``python benchmarks/render_speed.py [--steps N]``.
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import steamtemp_gym
from steamtemp_gym.envs.render import DPI, HEIGHT, WIDTH


def matplotlib_redraw_ms(repeats: int = 20) -> float:
    """Median ms of one Agg draw of a 3-panel figure of the display's size with 5 lines."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(WIDTH / DPI, HEIGHT / DPI), dpi=DPI)
    axes = fig.subplots(3, 1, sharex=True)
    t = np.linspace(0, 60, 900)
    for ax in axes:
        for k in range(2):
            ax.plot(t, np.sin(t / 7 + k))
        ax.legend(["a", "b"], fontsize=7)
    canvas = FigureCanvasAgg(fig)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        canvas.draw()
        np.asarray(canvas.buffer_rgba())[:, :, :3].copy()
        times.append(time.perf_counter() - t0)
    return 1e3 * float(np.median(times))


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=int, default=900, help="steps per episode (default 900)")
    args = ap.parse_args(argv)
    if args.steps < 1:
        ap.error("--steps must be >= 1")
    ref = matplotlib_redraw_ms()
    print(f"reference: one matplotlib redraw of the figure, {ref:.1f} ms\n")
    print(
        "| id | frame, median ms | x reference | worst frame, ms | reset with display, ms | "
        f"{args.steps} steps with frames, s |"
    )
    print("|---|---|---|---|---|---|")
    for env_id in steamtemp_gym.ENV_IDS:
        env = gym.make(env_id, scenario="load_ramp_100_50", render_mode="rgb_array")
        env.reset(seed=0)
        env.step(np.zeros(env.action_space.shape, dtype=np.float32))
        env.render()  # warm-up: kernels compiled
        rng = np.random.default_rng(0)
        a = np.zeros(env.action_space.shape, dtype=np.float32)
        t0 = time.perf_counter()
        env.reset(seed=1)
        setup = time.perf_counter() - t0
        frames, t_ep = [], time.perf_counter()
        for _ in range(args.steps):
            a = np.clip(a + rng.normal(0.0, 0.05, a.shape), -1, 1).astype(np.float32)
            _, _, term, trunc, _ = env.step(a)
            t0 = time.perf_counter()
            frame = env.render()
            frames.append(time.perf_counter() - t0)
            if term or trunc:
                env.reset()
        t_ep = time.perf_counter() - t_ep
        assert frame.shape == (HEIGHT, WIDTH, 3)
        med = 1e3 * float(np.median(frames))
        print(
            f"| {env_id.split('/')[-1]} | {med:.3f} | {med / ref:.4f} | "
            f"{1e3 * max(frames):.2f} | {1e3 * setup:.0f} | {t_ep:.2f} |"
        )


if __name__ == "__main__":
    main()
