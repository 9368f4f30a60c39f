"""Cubic Hermite cells: the basis on a unit cell and on a cell of any width, its slope,
and the safeguarded root of a cell's cubic."""

from __future__ import annotations

from steamtemp_gym._jit import njit


@njit(cache=True, error_model="numpy")
def hermite(t: float) -> tuple[float, float, float, float]:
    """Cubic Hermite basis on a unit cell: weights of f(0), f'(0), f(1), f'(1)."""
    t2 = t * t
    t3 = t2 * t
    return 2.0 * t3 - 3.0 * t2 + 1.0, t3 - 2.0 * t2 + t, 3.0 * t2 - 2.0 * t3, t3 - t2


@njit(cache=True, error_model="numpy")
def hermite_cell(t: float, w: float) -> tuple[float, float, float, float]:
    """Cubic Hermite basis at local coordinate t of a cell of width w: weights of f(0),
    f'(0), f(1), f'(1) with the derivatives per unit of the axis (not of the cell)."""
    a0, a1, a2, a3 = hermite(t)
    return a0, a1 * w, a2, a3 * w


@njit(cache=True, error_model="numpy")
def hermite_slope(t: float, w: float) -> tuple[float, float, float, float]:
    """d/dx of the weights of :func:`hermite_cell` (x = w t along the axis)."""
    t2 = t * t
    d0 = (6.0 * t2 - 6.0 * t) / w
    return d0, 3.0 * t2 - 4.0 * t + 1.0, -d0, 3.0 * t2 - 2.0 * t


@njit(cache=True, error_model="numpy")
def cell_root(f0: float, f1: float, c0: float, c1: float, u: float) -> float:
    """Root in [0, 1] of the cubic Hermite F with F(0) = f0 <= 0 <= F(1) = f1, F'(0) = c0,
    F'(1) = c1 (derivatives per unit cell): safeguarded Halley iteration from u.

    Halley converges cubically, so a step s below 1e-5 leaves an error of order s**3
    (round-off); the step is applied and the result returned. Steps leaving the bracket
    are replaced by bisection, which stops once the bracket is below 1e-14.
    """
    # power form F = ((a u + b) u + c0) u + f0
    a = 2.0 * (f0 - f1) + c0 + c1
    b = 3.0 * (f1 - f0) - 2.0 * c0 - c1
    ul = 0.0
    uh = 1.0
    for _ in range(60):
        f = ((a * u + b) * u + c0) * u + f0
        if f > 0.0:
            uh = u
        else:
            ul = u
        fd = (3.0 * a * u + 2.0 * b) * u + c0
        fdd = 6.0 * a * u + 2.0 * b
        den = fd * fd - 0.5 * f * fdd
        if fd > 0.0 and den > 0.0:
            step = f * fd / den
            if abs(step) < 1e-5:
                return min(max(u - step, 0.0), 1.0)
            u -= step
            if ul < u < uh:
                continue
        if uh - ul < 1e-14:
            break
        u = 0.5 * (ul + uh)
    return u
