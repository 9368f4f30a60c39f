"""Generate ``steamtemp_gym/steam/if97_tables.npz`` from IAPWS-IF97 (``iapws`` package).

Offline generator for the compiled steam-property lookups of :mod:`steamtemp_gym.steam`.
Rerunnable: ``python scripts/generate_steam_tables.py [--workers N] [--out PATH]``
(about 30 s on two cores). Requires ``iapws`` (the ``tables`` extra); the run-time
package never imports it.
The forward IF97 states are in ``scripts/steam_tables/if97.py``, the fast-path tables in
``scripts/steam_tables/fast.py``; this script lays out and builds the patch tables and
writes the file.

Source and method
-----------------
All values come from the *forward* IAPWS-IF97 equations as implemented by the ``iapws``
package (``iapws.iapws97._Region1``, ``_Region2`` (Gibbs, in p and T), ``_Region3``
(Helmholtz, in rho and T), ``_TSat_P`` (region 4) and ``_t_P`` (B23 boundary)), i.e. exactly
the equations ``iapws.IAPWS97`` evaluates. The private functions are called directly, with
our own tightly converged Newton iterations (relative tolerance 1e-12), because
``IAPWS97(P=, h=)`` takes ~1.6 ms per call and stops its region-3 ``fsolve`` at ~1e-8, too
loose for finite-difference derivatives. Region boundaries follow ``IAPWS97`` exactly:

* region 1 / 3 at T = 623.15 K (h13(p) = h1(p, 623.15 K)),
* region 2 / 3 at the B23 line T_B23(p) (h23(p) = h2(p, T_B23(p))),
* saturation: region 1 / 2 at Tsat(p) for p <= psat(623.15 K) = 16.529 MPa, region 3 at
  (p, Tsat(p)) on the liquid or vapour density root above it (as ``IAPWS97(P=, x=0/1)``).

IF97 is slightly discontinuous across these boundaries (up to 0.12 kJ/kg in h), so no
table patch interpolates across any of them.

Layout
------
Pressure is split into three segments, each with its own pressure-like coordinate q and a
piecewise-uniform q grid shared by all its curves and patches:

===  ========================  ==========================  =================================
seg  p range (MPa)             q                           patches (h ranges between curves)
===  ========================  ==========================  =================================
0    0.2 .. 16.529 (P13)       q = p                       L1 [hmin, hl] | dome | V2 [hv, hmax]
1    P13 .. pc - 1e-4          q = sqrt(pc - p)            L1 [hmin, h13] | L3 [h13-m, hl] |
                                                           dome | V3 [hv, h23+m] | V2 [h23, hmax]
2    pc .. 35                  q = p                       L1 [hmin, h13] | S3 [h13-m, h23+m] |
                                                           V2 [h23, hmax]
===  ========================  ==========================  =================================

(hmin = h(p, 10 C), hmax = h(p, 800 C), pc = 22.064 MPa, m = 1 kJ/kg: region-3 patches
overlap their neighbours so that h(p, T) can be inverted exactly on either side of the
IF97 region discontinuities.) q = sqrt(pc - p) makes the saturation curves, which behave
like sqrt(pc - p) near the critical point, smooth.

Each patch is a rectangle in (q, xi) with xi = (h - lo(q)) / (hi(q) - lo(q)) in [0, 1], so
patch edges follow the saturation and region-boundary curves exactly. At every node the
table stores, for T and for rho, the value and the derivatives d/dq, d/dxi, d2/dq dxi
(Hermite-bicubic data). d/dxi is analytic (dT/dh = 1/cp, drho/dh = -rho alpha_v / cp, times
hi - lo); d/dq and the cross derivative are finite differences in q (step 1e-4 in q,
central, one-sided at segment ends) of the converged solutions. The boundary curves
(and the saturation properties Tsat, rho_l, rho_v) are stored on the same q grid as
cubic-Hermite data (value, d/dq). Grids are piecewise uniform (a few zones per axis,
refined near the saturation line at low pressure, near the critical point and along the
pseudo-critical line); see ``SEGMENTS`` and ``BLOCKS`` below: 25 630 nodes, 0.82 MB per
quantity (each concatenated table must stay below numba's 1 MB constant-freezing limit,
which the script checks). Measured accuracy: see :mod:`steamtemp_gym.steam`.

Fast path
---------
Superheated steam in the rectangle ``FAST_P`` x ``FAST_H`` (2-35 MPa x 2850-3950 kJ/kg,
entirely in region 2; ``check_fast_rectangle`` verifies that against h_v(p), h23(p) and
h(p, 800 C)) gets its own uniform Hermite-bicubic tables ``fast_T`` and ``fast_rho``
(0.5 MPa x 20 kJ/kg, 67 x 56 nodes, 120 kB each) so that the run-time lookup needs no
patch or curve evaluation there. Node values come from the region-2 Newton solve
``state_ph``; d/dh is analytic (1/cp, -rho alpha_v / cp), so is d/dp at constant h
((dT/dp)_h = v (T alpha_v - 1) / cp, (drho/dp)_h = rho (kappa_T - alpha_v (dT/dp)_h)),
checked against central differences of the values; d2/dp dh is the central difference
(step ``FD_STEP``) of the analytic d/dh. ``fast_h`` holds h(p, tau) with
tau = (T - T(p, 2850)) / (T(p, 3950) - T(p, 2850)) on 67 x 33 nodes, the start value of the
run-time h(p, T) inversion. The spacing was chosen from the measured interpolation error
(max |dT| 3e-5 K at 0.5 MPa x 20 kJ/kg, dominated by the p spacing at 2-4 MPa; 1.5e-6 K at
0.25 MPa x 10 kJ/kg for four times the size), i.e. as accurate as the patch tables.

Units in the file: p in MPa, h in kJ/kg, T in K, rho in kg/m3 (the run-time module
converts to SI).
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import re
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from iapws import iapws97 as if97
from steam_tables.fast import build_fast
from steam_tables.if97 import (
    FD_STEP,
    P13,
    PC,
    PMAX,
    PMIN,
    T13,
    TC,
    TMAX,
    TMIN,
    State,
    curve_state,
    region3_pT,
    region12_pT,
    sat_state,
    state_ph,
)

LAYOUT_VERSION = 2

S_MIN = 0.01  # segment 1 ends at p = pc - S_MIN**2 (100 Pa below the critical point)
MARGIN = 1.0  # kJ/kg overlap of region-3 patches beyond the 1/3 and 2/3 boundaries

# Curve indices per segment (the run-time module checks these names).
CURVES = {
    0: ("hmin", "hl", "hv", "hmax", "Tsat", "rhol", "rhov"),
    1: ("hmin", "h13", "hl", "hv", "h23", "hmax", "Tsat", "rhol", "rhov"),
    2: ("hmin", "h13", "h23", "hmax"),
}

# Segments: q range and q zones given as (q_start, q_end, n_cells), contiguous.
SEGMENTS: dict[int, dict] = {
    0: {
        "coord": "p",
        "zones": [
            (0.2, 0.5, 15),
            (0.5, 1.0, 10),
            (1.0, 2.0, 10),
            (2.0, 4.0, 10),
            (4.0, 8.0, 10),
            (8.0, P13, 15),
        ],
    },
    1: {
        "coord": "s",  # q = sqrt(pc - p), decreasing in p; zones in increasing q
        "zones": [(S_MIN, 0.2, 10), (0.2, 1.0, 20), (1.0, math.sqrt(PC - P13), 20)],
    },
    2: {
        "coord": "p",
        "zones": [
            (PC, 22.3, 12),
            (22.3, 23.0, 18),
            (23.0, 25.0, 20),
            (25.0, 28.0, 15),
            (28.0, PMAX, 14),
        ],
    },
}


@dataclass(frozen=True)
class Block:
    """One (q, xi) patch: which segment, IF97 region, bounding curves and xi zones."""

    name: str
    seg: int
    region: int  # 1, 2 or 3
    lo: str  # lower bounding curve
    hi: str  # upper bounding curve
    lo_margin: float  # lo = curve(lo) - lo_margin
    hi_margin: float  # hi = curve(hi) + hi_margin
    phase: str  # "liquid", "vapour" or "super" (branch of region-3 solutions)
    zones: tuple  # xi zones (xi_start, xi_end, n_cells)


BLOCKS: tuple[Block, ...] = (
    Block("s0_L1", 0, 1, "hmin", "hl", 0.0, 0.0, "liquid", ((0.0, 0.8, 20), (0.8, 1.0, 10))),
    Block(
        "s0_V2",
        0,
        2,
        "hv",
        "hmax",
        0.0,
        0.0,
        "vapour",
        ((0.0, 0.02, 5), (0.02, 0.1, 8), (0.1, 0.3, 10), (0.3, 1.0, 18)),
    ),
    Block("s1_L1", 1, 1, "hmin", "h13", 0.0, 0.0, "liquid", ((0.0, 0.8, 20), (0.8, 1.0, 10))),
    Block("s1_L3", 1, 3, "h13", "hl", MARGIN, 0.0, "liquid", ((0.0, 0.8, 10), (0.8, 1.0, 10))),
    Block("s1_V3", 1, 3, "hv", "h23", 0.0, MARGIN, "vapour", ((0.0, 0.2, 10), (0.2, 1.0, 15))),
    Block(
        "s1_V2",
        1,
        2,
        "h23",
        "hmax",
        0.0,
        0.0,
        "vapour",
        ((0.0, 0.1, 10), (0.1, 0.3, 10), (0.3, 1.0, 18)),
    ),
    Block("s2_L1", 2, 1, "hmin", "h13", 0.0, 0.0, "liquid", ((0.0, 0.8, 20), (0.8, 1.0, 10))),
    Block(
        "s2_S3",
        2,
        3,
        "h13",
        "h23",
        MARGIN,
        MARGIN,
        "super",
        ((0.0, 0.3, 15), (0.3, 0.7, 80), (0.7, 1.0, 15)),
    ),
    Block(
        "s2_V2",
        2,
        2,
        "h23",
        "hmax",
        0.0,
        0.0,
        "vapour",
        ((0.0, 0.1, 10), (0.1, 0.3, 10), (0.3, 1.0, 18)),
    ),
)


def curve_values(seg: int, p: float) -> dict[str, float]:
    """All curve values of a segment at p."""
    out: dict[str, float] = {}
    cache: dict[str, State] = {}
    for name in CURVES[seg]:
        if name in ("Tsat", "rhol", "rhov"):
            continue
        cache[name] = curve_state(name, p, seg)
        out[name] = cache[name].h
    if "Tsat" in CURVES[seg]:
        out["Tsat"] = cache["hl"].T
        out["rhol"] = cache["hl"].rho
        out["rhov"] = cache["hv"].rho
    return out


# ---------------------------------------------------------------------------------------
# Grids
# ---------------------------------------------------------------------------------------


def axis_nodes(zones: Sequence[tuple[float, float, int]]) -> np.ndarray:
    """Node coordinates of a piecewise-uniform axis given as (start, end, n_cells) zones."""
    pts = [zones[0][0]]
    for a, b, n in zones:
        pts.extend(np.linspace(a, b, n + 1)[1:])
    return np.asarray(pts, dtype=np.float64)


def q_to_p(seg: int, q: float) -> float:
    """Pressure (MPa) from the segment coordinate q."""
    return PC - q * q if SEGMENTS[seg]["coord"] == "s" else q


def column(args: tuple[int, float]) -> dict:
    """Curves and patch columns (all xi nodes of every patch) of a segment at one q."""
    seg, q = args
    p = q_to_p(seg, q)
    curves = curve_values(seg, p)
    cols = {}
    for blk in BLOCKS:
        if blk.seg != seg:
            continue
        lo = curves[blk.lo] - blk.lo_margin
        hi = curves[blk.hi] + blk.hi_margin
        width = hi - lo
        xi = axis_nodes(blk.zones)
        n = xi.size
        out = np.empty((n, 4))
        # march from the edge whose state is known, using the previous node as guess
        if blk.phase == "liquid" and blk.region == 3:
            order = range(n - 1, -1, -1)
            guess = sat_state(p, 0, True)
        elif blk.phase == "vapour" and blk.region == 3:
            order = range(n)
            guess = sat_state(p, 1, True)
        elif blk.region == 3:  # supercritical region 3, start near 623 K liquid-like
            order = range(n)
            guess = region3_pT(p, T13, 1.0 / float(if97._Backward3_v_PT(p, T13 + 1e-3)))
        elif blk.region == 1:
            order = range(n)
            guess = region12_pT(1, p, TMIN)
        else:
            order = range(n)
            guess = curve_state(blk.lo, p, seg)
        for j in order:
            st = state_ph(blk.region, p, lo + xi[j] * width, guess)
            guess = st
            out[j, 0] = st.T
            out[j, 1] = width / st.cp  # dT/dxi
            out[j, 2] = st.rho
            out[j, 3] = -st.rho * st.alpha / st.cp * width  # drho/dxi
        cols[blk.name] = out
    return {"curves": curves, "cols": cols}


def fd_weights(q: float, qmin: float, qmax: float) -> tuple[np.ndarray, np.ndarray]:
    """Offsets and weights of a second-order first-derivative stencil kept inside [qmin, qmax]."""
    d = FD_STEP
    if q - d < qmin - 1e-12:
        return np.array([0.0, d, 2 * d]), np.array([-1.5, 2.0, -0.5]) / d
    if q + d > qmax + 1e-12:
        return np.array([0.0, -d, -2 * d]), np.array([1.5, -2.0, 0.5]) / d
    return np.array([-d, d]), np.array([-0.5, 0.5]) / d


def build_segment(seg: int, pool: ProcessPoolExecutor) -> dict[str, np.ndarray]:
    """Tables (curves and patches) of one segment."""
    qn = axis_nodes(SEGMENTS[seg]["zones"])
    qmin, qmax = qn[0], qn[-1]
    jobs: list[tuple[int, float]] = []
    stencils = []
    for q in qn:
        offs, w = fd_weights(q, qmin, qmax)
        idx = []
        for o in offs:
            idx.append(len(jobs))
            jobs.append((seg, q + o))
        centre = len(jobs)
        jobs.append((seg, q))
        stencils.append((idx, w, centre))
    res = list(pool.map(column, jobs, chunksize=4))
    names = CURVES[seg]
    nq = qn.size
    curves = np.empty((nq, len(names), 2))
    out: dict[str, np.ndarray] = {}
    blocks = [b for b in BLOCKS if b.seg == seg]
    tabs = {b.name: np.empty((nq, axis_nodes(b.zones).size, 2, 4)) for b in blocks}
    for i, (idx, w, centre) in enumerate(stencils):
        c0 = res[centre]
        for k, nm in enumerate(names):
            curves[i, k, 0] = c0["curves"][nm]
            curves[i, k, 1] = sum(wk * res[j]["curves"][nm] for j, wk in zip(idx, w, strict=True))
        for b in blocks:
            col = c0["cols"][b.name]
            dq = sum(wk * res[j]["cols"][b.name] for j, wk in zip(idx, w, strict=True))
            t = tabs[b.name]
            for m in range(2):  # 0: T, 1: rho
                t[i, :, m, 0] = col[:, 2 * m]
                t[i, :, m, 1] = dq[:, 2 * m]
                t[i, :, m, 2] = col[:, 2 * m + 1]
                t[i, :, m, 3] = dq[:, 2 * m + 1]
    out[f"curves{seg}"] = curves
    for b in blocks:
        out[f"T_{b.name}"] = np.ascontiguousarray(tabs[b.name][:, :, 0, :])
        out[f"rho_{b.name}"] = np.ascontiguousarray(tabs[b.name][:, :, 1, :])
    return out


def zones_array(zones: Sequence[tuple[float, float, int]]) -> np.ndarray:
    """(n_zones, 3) array of (start, end, n_cells)."""
    return np.asarray(zones, dtype=np.float64)


def _tables_digest() -> Callable[[dict[str, np.ndarray]], str]:
    """``tables_digest`` of steamtemp_gym/steam/digest.py, the one the run-time module checks
    (loaded from its file: the package does not import while the tables and their hash
    disagree, as they do between writing the file and updating the hash)."""
    path = Path(__file__).resolve().parents[1] / "steamtemp_gym" / "steam" / "digest.py"
    spec = importlib.util.spec_from_file_location("_steam_tables_digest", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.tables_digest


def update_module_hash(module: Path, digest: str) -> None:
    """Write the new table digest into ``_TABLES_SHA256`` of the run-time module.

    Editing the module changes the package code, and with it the folder of cached kernels.
    """
    src = module.read_text()
    new, n = re.subn(
        r"^_TABLES_SHA256 = \"[0-9A-Za-z]*\"$",
        f'_TABLES_SHA256 = "{digest}"',
        src,
        flags=re.MULTILINE,
    )
    if n != 1:
        raise RuntimeError(f"could not find the _TABLES_SHA256 line in {module}")
    if new != src:
        module.write_text(new)


def main(argv: list[str] | None = None) -> None:
    """Generate the tables, write the npz file and update the module's table hash."""
    pkg = Path(__file__).resolve().parents[1] / "steamtemp_gym" / "steam"
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=pkg / "if97_tables.npz")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument(
        "--no-hash-update",
        action="store_true",
        help="do not write the table digest into steamtemp_gym/steam/tables.py",
    )
    args = ap.parse_args(argv)
    t0 = time.time()
    data: dict[str, np.ndarray] = {}
    with ProcessPoolExecutor(max_workers=args.workers) as pool:
        for seg in SEGMENTS:
            data.update(build_segment(seg, pool))
            print(f"segment {seg} done ({time.time() - t0:.0f} s)", flush=True)
        data.update(build_fast(pool))
        print(f"fast tables done ({time.time() - t0:.0f} s)", flush=True)
    for seg, spec in SEGMENTS.items():
        data[f"qzones{seg}"] = zones_array(spec["zones"])
        data[f"curvenames{seg}"] = np.array(CURVES[seg])
    data["block_names"] = np.array([b.name for b in BLOCKS])
    data["block_seg"] = np.array([b.seg for b in BLOCKS], dtype=np.int64)
    data["block_margins"] = np.array([[b.lo_margin, b.hi_margin] for b in BLOCKS])
    for b in BLOCKS:
        data[f"xizones_{b.name}"] = zones_array(b.zones)
    data["constants"] = np.array([PC, TC, P13, T13, TMIN, TMAX, PMIN, PMAX, S_MIN])
    data["layout_version"] = np.array(LAYOUT_VERSION)
    # run-time arrays (patch tables concatenated per quantity); numba freezes <= 1 MB
    sizes = {
        f"{qty}_*": sum(v.nbytes for k, v in data.items() if k.startswith(f"{qty}_"))
        for qty in ("T", "rho")
    }
    sizes.update({k: data[k].nbytes for k in ("fast_T", "fast_rho", "fast_h")})
    for name, nbytes in sizes.items():
        if nbytes > 10**6:
            raise RuntimeError(f"{name} tables take {nbytes} bytes > 1 MB; coarsen the grids")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(args.out, **data)
    digest = _tables_digest()(data)
    if not args.no_hash_update and args.out.resolve() == (pkg / "if97_tables.npz").resolve():
        update_module_hash(pkg / "tables.py", digest)
    n_nodes = sum(v.size // 4 for k, v in data.items() if k.startswith("T_"))
    print(
        f"wrote {args.out} ({args.out.stat().st_size / 1e6:.2f} MB, {n_nodes} patch nodes, "
        f"sha256 {digest[:16]}..., {time.time() - t0:.0f} s)"
    )


if __name__ == "__main__":
    main()
