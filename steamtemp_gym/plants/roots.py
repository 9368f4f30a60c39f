"""The secant iteration the plants' calibrations share (sizing a gas side, a firing or
enthalpy schedule so that a design temperature is met). Each caller keeps its own test
of the result: what residual it accepts and what it reports when it cannot."""

from __future__ import annotations

from collections.abc import Callable


def secant(
    fun: Callable[[float], float], a: float, b: float, tol: float, floor: float | None = None
) -> tuple[float, float]:
    """(x, fun(x)) after the secant iteration from a, b: it stops at ``|fun(x)| < tol``, at a
    stall (two equal residuals) or after 80 steps. With ``floor``, a step never goes below
    ``floor * |x|`` of the previous iterate (keeps a positive unknown positive)."""
    fa, fb = fun(a), fun(b)
    for _ in range(80):
        if abs(fb) < tol or fb == fa:
            break
        step = b - fb * (b - a) / (fb - fa)
        a, b, fa = b, step if floor is None else max(step, floor * abs(b)), fb
        fb = fun(b)
    return b, fb
