"""Can the steam lookups run across environments in the vector units? A measurement.

    python benchmarks/simd_lookup.py [--batch 4096] [--repeats 30]

The physics plants spend 40-55 % of their right-hand sides in IAPWS-IF97 table lookups
(docs/performance_profile.md). A batch-innermost (structure-of-arrays) restructure of the plants
would pay only if those lookups vectorize across rows. This script times, on one thread,
ns per lookup of T, dT/dh and rho on the fast table for ``--batch`` random superheated
states (10-25 MPa, 3000-3400 kJ/kg):

- ``scalar``: the plants' way, one ``steam.T_rho_ph`` call per row;
- ``batch``: one loop over the rows that locates each row's cell branch-free and
  evaluates it with the steam package's own Hermite bicubic (``hermite``, ``fast_basis_h``
  and ``fast_value``, as ``steam.T_rho_ph`` does), as numba compiles it;
- ``batch, noalias``: the same loop compiled with numba's internal ``noalias`` flag (the
  arrays declared not to overlap), which is what lets LLVM vectorize its table reads into
  gathers. The flag is not a public numba option; the script sets it for this one compile.

It prints the three timings (best of ``--repeats``, interleaved), whether the batch loops
give bit-identical results to the scalar calls, and the packed (``...pd``), gather and scalar
(``...sd``) instructions in each loop's machine code.
"""

from __future__ import annotations

import argparse
import re
import time
from contextlib import contextmanager

import numba.core.cpu as _cpu
import numpy as np
from numba import carray, float64, njit

from steamtemp_gym.steam import T_rho_ph
from steamtemp_gym.steam import tables as tb
from steamtemp_gym.steam.cubic import hermite
from steamtemp_gym.steam.fast import fast_basis_h, fast_value

SIG = (float64[::1],) * 5


def _batch(P, H, T, dT, R):  # noqa: N803
    """T, dT/dh and rho of every row (P Pa, H J/kg) on the fast table, cells located
    branch-free."""
    ft = carray(tb.FT_PTR(), tb.FT_SHAPE)
    fr = carray(tb.FR_PTR(), tb.FT_SHAPE)
    for k in range(P.shape[0]):
        x = min(max((min(P[k] * 1e-6, 35.0) - tb.FP0) * tb.FPINV, 0.0), float(tb.FNP))
        i = min(int(x), tb.FNP - 1)
        y = min(max((H[k] * 1e-3 - tb.FH0) * tb.FHINV, 0.0), float(tb.FNH))
        j = min(int(y), tb.FNH - 1)
        a = hermite(x - i)
        b, e = fast_basis_h(y - j)
        T[k], dT_kJ = fast_value(ft, i, j, a, b, e)
        dT[k] = dT_kJ * 1e-3
        R[k] = fast_value(fr, i, j, a, b, e)[0]


@njit(error_model="numpy")
def _scalar(P, H, T, dT, R):  # noqa: N803
    for k in range(P.shape[0]):
        T[k], dT[k], R[k], _ = T_rho_ph(P[k], H[k])


@contextmanager
def _noalias():
    """Compile with numba's internal ``noalias`` flag set (restored afterwards)."""
    orig = _cpu.CPUTargetOptions.finalize

    def finalize(self, flags, options):
        orig(self, flags, options)
        flags.noalias = True

    _cpu.CPUTargetOptions.finalize = finalize
    try:
        yield
    finally:
        _cpu.CPUTargetOptions.finalize = orig


def _counts(kernel) -> str:
    asm = next(iter(kernel.inspect_asm().values()))
    packed = len(re.findall(r"\tv\w+pd\s", asm))
    scalar = len(re.findall(r"\tv\w+sd\s", asm))
    return f"packed {packed:4d}  gathers {asm.count('gather'):3d}  scalar {scalar:4d}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--batch", type=int, default=4096)
    ap.add_argument("--repeats", type=int, default=30)
    args = ap.parse_args()
    plain = njit(error_model="numpy")(_batch)
    plain.compile(SIG)
    noalias = njit(error_model="numpy")(_batch)
    with _noalias():
        noalias.compile(SIG)
    kernels = {"scalar": _scalar, "batch": plain, "batch, noalias": noalias}
    rng = np.random.default_rng(0)
    P = rng.uniform(10e6, 25e6, args.batch)  # noqa: N806
    H = rng.uniform(3.0e6, 3.4e6, args.batch)  # noqa: N806
    out = {name: [np.zeros(args.batch) for _ in range(3)] for name in kernels}
    best = dict.fromkeys(kernels, np.inf)
    for _ in range(args.repeats):
        for name, k in kernels.items():
            t0 = time.perf_counter()
            k(P, H, *out[name])
            best[name] = min(best[name], time.perf_counter() - t0)
    same = {
        name: all(np.array_equal(a, b) for a, b in zip(out["scalar"], out[name], strict=True))
        for name in kernels
    }
    print(f"{args.batch} rows, ns per lookup (best of {args.repeats}):")
    for name, k in kernels.items():
        asm = _counts(k) if k is not _scalar else ""
        ns, ratio = best[name] / args.batch * 1e9, best["scalar"] / best[name]
        print(f"  {name:15s} {ns:6.2f}  x{ratio:4.2f}  bit-identical {same[name]}  {asm}")


if __name__ == "__main__":
    main()
