"""Packing scenarios into the padded breakpoint tables the compiled kernels read."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from steamtemp_gym.scenarios.model import CHANNELS, Scenario


def pack(scenario: Scenario, bp_t: np.ndarray, bp_v: np.ndarray, bp_n: np.ndarray) -> None:
    """Write one scenario's breakpoints into rows of the kernel's padded tables.

    Args:
        scenario: The scenario.
        bp_t: Breakpoint times, shape (n_channels, K), written in place.
        bp_v: Breakpoint values, shape (n_channels, K), written in place.
        bp_n: Breakpoint counts, shape (n_channels,), written in place.
    """
    for c, ch in enumerate(CHANNELS):
        pts = getattr(scenario, ch)
        if len(pts) > bp_t.shape[1]:
            raise ValueError(
                f"scenario {scenario.name!r}: channel {ch!r} has {len(pts)} breakpoints, "
                f"more than the {bp_t.shape[1]} supported"
            )
        bp_n[c] = len(pts)
        for k, (t, v) in enumerate(pts):
            bp_t[c, k] = t
            bp_v[c, k] = v


def max_breakpoints(scenarios: Sequence[Scenario]) -> int:
    """Largest breakpoint count over channels of the given scenarios."""
    return max(len(getattr(s, ch)) for s in scenarios for ch in CHANNELS)
