"""Linearly implicit integrator for the stiff superheater equations.

Steam storage in a superheater segment is small next to the tube metal (an
IDAES 320 MW platen holds ~0.9 t of steam, 3.5 s residence, against 85.7 t of
metal, in the IDAES subcritical power plant model; docs/references.md), so the
enthalpy states are fast and the system is stiff at the control interval. We use the
two-stage, second-order, L-stable Rosenbrock W-method ROS2 of Verwer, Spee, Blom and
Hundsdorfer (SIAM J. Sci. Comput. 20, 1999), gamma = 1 + 1/sqrt(2)::

    (I - gamma h A) k1 = F(x_n)
    (I - gamma h A) k2 = F(x_n + h k1) - 2 k1
    x_{n+1} = x_n + 3/2 h k1 + 1/2 h k2

ROS2 keeps order two for *any* matrix A (checked on a scalar problem in
tests/test_integrator.py), so A need only carry the stiff part of the
Jacobian: its diagonal ``jd``, a sparse strictly-lower pattern ``(jrow, jcol,
jl)`` and optional entries ``ju[j] = A[j, j+1]`` just above the diagonal, which
make (j, j+1) a 2x2 diagonal block solved exactly (a superheater segment's
metal and fluid). The linear solves are one block forward substitution,
O(n_states) per stage. In practice A must hold every *stiff* coupling, including
those from slow states into the fast fluid (valve, upstream enthalpy, steam
flow): with them missing the error constant explodes and ROS2 behaves as a
first-order method (measured: 1.2 K instead of 0.02 K over the load ramp).
Accuracy against a Radau reference (rtol 1e-8) over the 100 -> 50 % ramp is
checked in tests/test_integrator.py.

A plant supplies two compiled functions:

- ``rhs(x, u, d, p, f, jd, ju, jl, want_jac)``: writes dx/dt into ``f``; when
  ``want_jac`` also the diagonal ``jd``, the super-diagonal block entries ``ju``
  (zero where unused; a row with ``ju[j] != 0`` must have ``ju[j+1] == 0``)
  and the values ``jl`` of the lower pattern (whose (row, col) pairs, sorted by
  row, are passed as ``jrow, jcol``).
- ``outputs(x, u, d, p, z)``: writes the plant's physical outputs into ``z``.

:func:`make_batched_step` returns the batched kernel
``step(X, U, D, P, jrow, jcol, dt, n_sub, Z)`` that advances every row of X
by ``dt`` in ``n_sub`` ROS2 steps with the inputs held (zero-order hold) and
fills Z (unless built without outputs). It is a copy of one template per plant,
compiled and cached on disk like any kernel (plants/specialize.py).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from steamtemp_gym._jit import njit
from steamtemp_gym.plants.specialize import specialize
from steamtemp_gym.plants.valve import valve_travel

GAMMA = 1.0 + 1.0 / np.sqrt(2.0)


@njit(cache=True, error_model="numpy")
def block_solve(gh, jd, ju, jl, jrow, jcol, r, z):
    """Solve (I - gh*A) z = r by block forward substitution.

    A = diag(jd) + strictly-lower pattern (jrow, jcol, jl) + ju just above the
    diagonal (2x2 blocks). Positive diagonal entries are treated as zero (W-methods
    admit any A; this keeps the solve well conditioned).
    """
    c = 0
    nc = jrow.shape[0]
    n = r.shape[0]
    j = 0
    while j < n:
        acc = r[j]
        while c < nc and jrow[c] == j:
            acc += gh * jl[c] * z[jcol[c]]
            c += 1
        m11 = 1.0 - gh * min(jd[j], 0.0)
        if ju[j] == 0.0:
            z[j] = acc / m11
            j += 1
            continue
        acc2 = r[j + 1]
        low = 0.0
        while c < nc and jrow[c] == j + 1:
            if jcol[c] == j:
                low = jl[c]
            else:
                acc2 += gh * jl[c] * z[jcol[c]]
            c += 1
        m12 = -gh * ju[j]
        m21 = -gh * low
        m22 = 1.0 - gh * min(jd[j + 1], 0.0)
        det = m11 * m22 - m12 * m21
        z[j] = (acc * m22 - m12 * acc2) / det
        z[j + 1] = (m11 * acc2 - m21 * acc) / det
        j += 2


def pattern_arrays(pattern: list[tuple[int, int]]) -> tuple[np.ndarray, np.ndarray]:
    """(jrow, jcol) int arrays of a strictly-lower Jacobian pattern, checked sorted by row."""
    jrow = np.array([r for r, _ in pattern], dtype=np.int64)
    jcol = np.array([c for _, c in pattern], dtype=np.int64)
    if np.any(np.diff(jrow) < 0) or np.any(jcol >= jrow):
        raise ValueError("Jacobian pattern must be strictly lower and sorted by row")
    return jrow, jcol


# Bound per plant by make_batched_step (plants/specialize.py); never compiled as they are.
rhs = outputs = project = None
ACTUATORS = np.zeros((0, 3), dtype=np.int64)


def _batched_step(X, U, D, P, jrow, jcol, dt, n_sub, Z):  # noqa: N803
    """Template of ``step``: see :func:`make_batched_step`."""
    n = X.shape[1]
    nc = jrow.shape[0]
    f = np.empty(n)
    jd = np.empty(n)
    ju = np.zeros(n)
    jl = np.empty(max(nc, 1))
    k1 = np.empty(n)
    k2 = np.empty(n)
    x2 = np.empty(n)
    h = dt / n_sub
    gh = GAMMA * h
    uc = np.empty(U.shape[1])
    # runtime flags, not literals: with literal True/False numba compiles rhs (and all it
    # calls) twice, once per value
    jac = n >= 0
    no_jac = n < 0
    for b in range(X.shape[0]):
        x = X[b]
        u = U[b]
        d = D[b]
        for _ in range(n_sub):
            for j in range(U.shape[1]):
                uc[j] = u[j]
            for j in range(ACTUATORS.shape[0]):
                iv = ACTUATORS[j, 0]
                v_end = valve_travel(x[iv], u[j], P[ACTUATORS[j, 1]], P[ACTUATORS[j, 2]], h)[0]
                uc[j] = (v_end - x[iv]) / h if h > 0.0 else 0.0
            rhs(x, uc, d, P, f, jd, ju, jl, jac)
            block_solve(gh, jd, ju, jl, jrow, jcol, f, k1)
            for i in range(n):
                x2[i] = x[i] + h * k1[i]
            rhs(x2, uc, d, P, f, jd, ju, jl, no_jac)
            for i in range(n):
                f[i] -= 2.0 * k1[i]
            block_solve(gh, jd, ju, jl, jrow, jcol, f, k2)
            for i in range(n):
                x[i] += 1.5 * h * k1[i] + 0.5 * h * k2[i]
            project(x, P)
        outputs(x, u, d, P, Z[b])


@njit(cache=True, error_model="numpy")
def _no_outputs(x, u, d, p, z):
    """Bound in place of ``outputs`` when the caller computes them itself."""


def make_batched_step(
    name: str,
    rhs: Callable,
    outputs: Callable | None,
    project: Callable,
    actuators: np.ndarray | None = None,
) -> Callable:
    """Build the compiled batched ROS2 step of a plant (cached on disk).

    Args:
        name: The plant's name, unique per set of functions (it names the cache entry).
        rhs: Compiled right-hand side (see module docstring).
        outputs: Compiled output map, or None for a step that leaves Z alone: for plants
            whose own step finishes the state after ROS2 (exact lags) and then computes the
            outputs once.
        project: Compiled ``project(x, p)`` that clips states to their physical
            ranges after each step (valve opening in [0, 1], ...).
        actuators: int array (k, 3): for each of the first k actions, the state index of
            its valve and the P indices of its time constant and rate limit
            (plants/valve.py). Their motion over each substep is computed exactly
            (valve_travel) and ``rhs`` receives, in place of those commands, the chord
            velocity (v_end - v_start)/h, which must be the valve's derivative with a
            zero Jacobian entry: ROS2 then moves the valve exactly along that chord and
            the rest of the plant sees it to second order. (Measured on the FSH under
            random valve steps: 0.24 K outlet error with ROS2 on the valve, see
            tests/test_integrator.py.)

    Returns:
        ``step(X, U, D, P, jrow, jcol, dt, n_sub, Z)``, in place on X and Z.
    """
    act = np.zeros((0, 3), dtype=np.int64) if actuators is None else np.asarray(actuators, np.int64)
    outputs = _no_outputs if outputs is None else outputs
    return specialize(
        _batched_step, name, rhs=rhs, outputs=outputs, project=project, ACTUATORS=act.reshape(-1, 3)
    )
