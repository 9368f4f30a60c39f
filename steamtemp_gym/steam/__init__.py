"""IAPWS-IF97 water/steam properties as compiled table lookups (numba).

Source: the IAPWS Industrial Formulation 1997 (forward equations of regions 1, 2, 3 and
the region-4 saturation line) as implemented by the ``iapws`` package, tabulated offline
by ``scripts/generate_steam_tables.py`` into ``if97_tables.npz`` (1.7 MB). No steam
library is called at run time; ``iapws`` is a generator / test dependency only.

Grid: pressure is split into three segments, 0.2 .. 16.529 MPa (psat(350 C)), 16.529 ..
22.064 MPa (the critical pressure; coordinate q = sqrt(pc - p), which makes the
sqrt-like saturation curves near the critical point smooth) and 22.064 .. 35 MPa. In each
segment the (p, h) plane is cut along the saturation curves h_l(p), h_v(p), the IF97
region boundaries (T = 623.15 K, B23 line) and the table edges h(p, 10 C), h(p, 800 C)
into 9 patches. A patch is a rectangle in (q, xi), xi = (h - lo(p)) / (hi(p) - lo(p)), so
its edges follow the saturation and boundary curves and nothing is interpolated across
a saturation kink or an IF97 region discontinuity. Both axes are piecewise uniform:
q steps from 0.02 MPa (0.2-0.5 MPa and just above pc) to 0.57 MPa; xi steps from
0.004 (superheated vapour next to saturation) to 0.005 (~5 kJ/kg, along the
pseudo-critical line) to 0.04; 25 630 nodes in all.

Method: T and rho are Hermite-bicubic in (q, xi): each node stores the value, d/dq,
d/dxi and d2/(dq dxi), with d/dxi analytic from IF97 (dT/dh = 1/cp,
drho/dh = -rho alpha_v / cp) and the q-derivatives from converged finite differences.
Boundary curves and saturation properties (Tsat, rho_l, rho_v, h_l, h_v) are cubic
Hermite in q. Inside the two-phase dome (p < pc, h_l < h < h_v) T = Tsat(p), dT/dh = 0
and rho is the homogeneous mixture density. ``h_pT`` inverts the T table exactly (binary
search over the patch column, then a safeguarded Halley solve of the cell's cubic), so
``h_pT(p, T_ph(p, h)) == h`` to round-off except within IF97's own region jumps.

Fast path: superheated steam in the rectangle 2 MPa <= p <= 35 MPa, 2850 <= h <= 3950
kJ/kg (``FAST_RECT``), which lies entirely in IF97 region 2 (max h_v = 2803 kJ/kg, B23
line h23 <= 2623 kJ/kg, h(35 MPa, 800 C) = 3996 kJ/kg), skips segment, patch and
boundary-curve evaluation: T and rho are plain Hermite bicubics on a uniform
0.5 MPa x 20 kJ/kg grid (67 x 56 nodes, 120 kB per quantity) with node derivatives from
the region-2 equation (d/dh and d/dp analytic, d2/dp dh by central differences). Where
it is used (and only there) ``h_pT`` inverts this table exactly: a start value from a
Hermite table of h(p, tau), tau = (T - T(p, 2850)) / (T(p, 3950) - T(p, 2850)), then a
Halley solve of the bracketing cell's cubic. Both paths agree on the rectangle's edges
h = 2850, h = 3950 and p = 2 MPa to 7e-5 K in T, 2e-5 relative in dT/dh, 2e-7 in rho,
1.4e-5 in drho/dh and 4e-4 kJ/kg in h_pT: the largest jump of a lookup crossing an
edge (p is clamped to 35 MPa before the test, so p = 35 MPa is no edge).

Domain: 0.2 MPa <= p <= 35 MPa, h(p, 10 C) <= h <= h(p, 800 C). Outside it every lookup
clamps to the table edge (finite values, never an out-of-bounds read; NaN inputs map to
the lower edge); ``check_domain`` raises ``ValueError`` instead (for env construction).
p within 100 Pa below pc is evaluated at pc - 100 Pa.

Measured accuracy against ``iapws.IAPWS97`` (tests/test_steam.py): T_ph max 5e-5 K over
1000 random (p, h), 7e-6 K along the pseudo-critical line (22.1-30 MPa, cp up to
3200 kJ/(kg K)), 8e-5 K just above the saturated-vapour line; h_pT max 2e-4 kJ/kg random,
1.2e-4 pseudo-critical, 1.3e-3 near saturation; rho_ph relative 5e-7 (single phase);
sat_p values relative 2e-7, their p-derivatives relative 8e-5; dT/dh vs 1/cp 2e-5. Fast
path (600 points, 200 of them within 40 kJ/kg of its lower h edge): T max 4e-5 K (2.1e-5
over 3000 uniform points; largest at 2-4 MPa next to that edge), rho relative 1.1e-7,
dT/dh vs 1/cp 2.3e-5, h_pT 1.2e-4 kJ/kg.

Cost (2.4 GHz AMD EPYC VM, batched numba loop over 1e6 random points with p 10-25 MPa,
h 3000-3400 kJ/kg, i.e. on the fast path): T_ph, T_dTdh_ph, rho_ph ~17.5 ns per call,
``T_rho_ph`` (T, dT/dh, rho and drho/dh at once) ~22 ns, h_pT ~70 ns. Elsewhere (patch
tables): T_ph ~50-60 ns, ``T_rho_ph`` ~70 ns, h_pT ~120 ns. First compile of all
functions ~6 s of CPU time (cached afterwards: ~1 s to load).

Units are SI throughout: p in Pa, h in J/kg, T in K, rho in kg/m3, cp in J/(kg K). All
public lookups are ``@njit(cache=True)`` scalar functions callable from Python and from
other jitted kernels. The tables are module-level constant arrays of < 1 MB each, which
numba freezes into the compiled code (and so can cache). ``_TABLES_SHA256`` pins the
data file; the generator updates it, which also changes this file and thereby
invalidates numba caches keyed on the sources.
"""

from __future__ import annotations

import hashlib
import math
from pathlib import Path

import llvmlite.binding as _llvm
import numpy as np
from llvmlite import ir as _ir
from numba import carray, types
from numba.extending import intrinsic

from steamtemp_gym._jit import njit

__all__ = [
    "T_ph",
    "T_dTdh_ph",
    "h_pT",
    "rho_ph",
    "rho_drhodh_ph",
    "T_rho_ph",
    "sat_p",
    "Tsat_p",
    "cp_pT",
    "h_limits_p",
    "check_domain",
    "P_MIN",
    "P_MAX",
    "P_CRIT",
    "T_CRIT",
    "T_MIN",
    "T_MAX",
    "FAST_RECT",
]

_TABLES_PATH = Path(__file__).with_name("if97_tables.npz")
_TABLES_SHA256 = "78cf6177cf9b0e35beaa9e183c0f8f46e96088a776b88ae853d325f43f1589c1"
_LAYOUT_VERSION = 2

_CURVE_NAMES = (
    ("hmin", "hl", "hv", "hmax", "Tsat", "rhol", "rhov"),
    ("hmin", "h13", "hl", "hv", "h23", "hmax", "Tsat", "rhol", "rhov"),
    ("hmin", "h13", "h23", "hmax"),
)
_BLOCK_NAMES = (
    "s0_L1", "s0_V2", "s1_L1", "s1_L3", "s1_V3", "s1_V2", "s2_L1", "s2_S3", "s2_V2",
)


def _tables_digest(data: dict[str, np.ndarray]) -> str:
    """SHA-256 over array names, dtypes, shapes and bytes (as the generator computes it)."""
    h = hashlib.sha256()
    for key in sorted(data):
        a = np.ascontiguousarray(data[key])
        h.update(f"{key}|{a.dtype.str}|{a.shape}|".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _load_tables() -> dict[str, np.ndarray]:
    """Load the npz tables and check them against this module's layout and hash."""
    with np.load(_TABLES_PATH) as z:
        data = {k: z[k] for k in z.files}
    if _tables_digest(data) != _TABLES_SHA256:
        raise ImportError(
            f"{_TABLES_PATH} does not match _TABLES_SHA256 in {__file__}; rerun "
            "scripts/generate_steam_tables.py (it updates the hash, which also invalidates "
            "numba caches)"
        )
    if int(data["layout_version"]) != _LAYOUT_VERSION:
        raise ImportError(f"{_TABLES_PATH.name}: unexpected layout version")
    for seg, names in enumerate(_CURVE_NAMES):
        if tuple(data[f"curvenames{seg}"].tolist()) != names:
            raise ImportError(f"{_TABLES_PATH.name}: unexpected curve layout in segment {seg}")
    if tuple(data["block_names"].tolist()) != _BLOCK_NAMES:
        raise ImportError(f"{_TABLES_PATH.name}: unexpected patch layout")
    return data


def _axes(zone_list: list[np.ndarray]) -> tuple[np.ndarray, ...]:
    """Pack piecewise-uniform axes given as (start, end, n_cells) zones.

    Returns per axis and zone: start coordinate (plus the axis end after the last zone),
    spacing, inverse spacing, index of the zone's first cell (plus the total cell count
    after the last zone), and the number of zones.
    """
    nmax = max(z.shape[0] for z in zone_list)
    n = len(zone_list)
    x0 = np.zeros((n, nmax + 1))
    dx = np.ones((n, nmax))
    off = np.zeros((n, nmax + 1), dtype=np.int64)
    nz = np.zeros(n, dtype=np.int64)
    for a, z in enumerate(zone_list):
        nz[a] = z.shape[0]
        for k, (start, end, ncell) in enumerate(z):
            x0[a, k] = start
            x0[a, k + 1] = end
            dx[a, k] = (end - start) / ncell
            off[a, k + 1] = off[a, k] + int(ncell)
        x0[a, nz[a] + 1:] = x0[a, nz[a]]  # padding, never selected
        off[a, nz[a] + 1:] = off[a, nz[a]]
    return x0, dx, 1.0 / dx, off, nz


_D = _load_tables()
(_PC, _TC, _P13, _T13, _TMIN, _TMAX, _PMIN, _PMAX, _SMIN) = (float(v) for v in _D["constants"])
_MARG = np.ascontiguousarray(_D["block_margins"], dtype=np.float64)  # (lo, hi) per patch
_M13, _M23 = float(_MARG[7, 0]), float(_MARG[7, 1])

# axes 0..2: segment q axes; axes 3..11: patch xi axes (in _BLOCK_NAMES order)
_AX_X0, _AX_DX, _AX_INV, _AX_OFF, _AX_NZ = _axes(
    [_D[f"qzones{s}"] for s in range(3)] + [_D[f"xizones_{b}"] for b in _BLOCK_NAMES]
)
_NXI = np.array([_D[f"T_{b}"].shape[1] for b in _BLOCK_NAMES], dtype=np.int64)
_NCURVE = np.array([len(c) for c in _CURVE_NAMES], dtype=np.int64)


def _concat(arrays: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Flatten and concatenate; return (data, start offsets)."""
    flat = [np.ascontiguousarray(a, dtype=np.float64).ravel() for a in arrays]
    off = np.cumsum([0] + [a.size for a in flat])[:-1].astype(np.int64)
    return np.concatenate(flat), off


# one flat array per quantity (numba freezes arrays <= 1 MB into the compiled code)
_CDAT, _COFF = _concat([_D[f"curves{s}"] for s in range(3)])
_TDAT, _POFF = _concat([_D[f"T_{b}"] for b in _BLOCK_NAMES])
_RDAT, _ = _concat([_D[f"rho_{b}"] for b in _BLOCK_NAMES])


def _unit_cell(tab: np.ndarray, dx: float, dy: float) -> np.ndarray:
    """Hermite node data (value, d/dx, d/dy, d2/dxdy) rescaled to unit-cell coordinates."""
    return np.ascontiguousarray(tab * np.array([1.0, dx, dy, dx * dy]), dtype=np.float64)


# fast path: uniform (p, h) rectangle in region 2; rows of fast_axes: p, h, tau axes
(_FP0, _FP1, _FNP), (_FH0, _FH1, _FNH), (_, _, _FNG) = (
    (float(a), float(b), int(n)) for a, b, n in _D["fast_axes"]
)
_FDP = (_FP1 - _FP0) / _FNP  # MPa
_FDH = (_FH1 - _FH0) / _FNH  # kJ/kg
_FPINV = 1.0 / _FDP
_FHINV = 1.0 / _FDH
_FT = _unit_cell(_D["fast_T"], _FDP, _FDH)  # (p node, h node, 4)
_FR = _unit_cell(_D["fast_rho"], _FDP, _FDH)
_FG = _unit_cell(_D["fast_h"], _FDP, 1.0 / _FNG)  # h(p, tau): start values for h_pT
del _D


# The large tables are not frozen into the compiled code (numba would copy ~2 MB of
# constants into every cached kernel that calls a lookup: 4 MB per cache file, 360 MB
# per cache). Each is registered once per process as a named external symbol and read
# through a pointer to it; the cached machine code refers to the symbol by name, and the
# JIT linker resolves it to this process's copy when the kernel is loaded. The symbol
# names carry the table hash, so code compiled against other tables cannot bind to
# these. The arrays are module globals: they live as long as the process.
def _external_table(name: str, arr: np.ndarray):
    """Register ``arr`` as a read-only external symbol; return an intrinsic giving its
    address as a float64 pointer (use with ``numba.carray`` and the array's shape)."""
    symbol = f"steamtemp_gym_if97_{_TABLES_SHA256[:16]}_{name}"
    _llvm.add_symbol(symbol, arr.ctypes.data)

    @intrinsic
    def address(typingctx):
        def codegen(context, builder, signature, args):
            module = builder.module
            try:
                g = module.get_global(symbol)
            except KeyError:
                g = _ir.GlobalVariable(module, _ir.IntType(8), symbol)
                g.linkage = "external"
                g.global_constant = True
            return builder.bitcast(g, _ir.DoubleType().as_pointer())

        return types.CPointer(types.float64)(), codegen

    return address


_CDAT_PTR = _external_table("curves", _CDAT)
_TDAT_PTR = _external_table("T", _TDAT)
_RDAT_PTR = _external_table("rho", _RDAT)
_FT_PTR = _external_table("fast_T", _FT)
_FR_PTR = _external_table("fast_rho", _FR)
_FG_PTR = _external_table("fast_h", _FG)
_NCDAT, _NTDAT, _FT_SHAPE, _FG_SHAPE = _CDAT.size, _TDAT.size, _FT.shape, _FG.shape

P_MIN = _PMIN * 1e6  # Pa, lower table edge
P_MAX = _PMAX * 1e6  # Pa, upper table edge
P_CRIT = _PC * 1e6  # Pa
T_CRIT = _TC  # K
T_MIN = _TMIN  # K, table edge (10 C)
T_MAX = _TMAX  # K, table edge (800 C)
# (p_min Pa, p_max Pa, h_min J/kg, h_max J/kg): where the uniform fast table is used
FAST_RECT = (_FP0 * 1e6, _FP1 * 1e6, _FH0 * 1e3, _FH1 * 1e3)

# patch ids, in _BLOCK_NAMES order
_S0_L1, _S0_V2, _S1_L1, _S1_L3, _S1_V3, _S1_V2, _S2_L1, _S2_S3, _S2_V2 = range(9)
# B23 boundary T(p) coefficients (IF97 eq. 6)
_B23_N3 = 0.10192970039326e-2
_B23_N4 = 0.57254459862746e3
_B23_N5 = 0.13918839778870e2


# ---------------------------------------------------------------------------------------
# Kernels (internal units: MPa, kJ/kg, K)
# ---------------------------------------------------------------------------------------

@njit(cache=True, error_model="numpy")
def _locate(ax: int, x: float) -> tuple[int, float, float]:
    """Cell index, local coordinate t in [0, 1] and cell width of x on axis ``ax``.

    x is clamped to the axis range (NaN maps to the lower edge), so the returned cell
    index is always valid.
    """
    nz = _AX_NZ[ax]
    if not x >= _AX_X0[ax, 0]:
        x = _AX_X0[ax, 0]
    elif x > _AX_X0[ax, nz]:
        x = _AX_X0[ax, nz]
    k = 0
    while k < nz - 1 and x >= _AX_X0[ax, k + 1]:
        k += 1
    r = (x - _AX_X0[ax, k]) * _AX_INV[ax, k]
    m = int(r)
    ncell = _AX_OFF[ax, k + 1] - _AX_OFF[ax, k]
    if m > ncell - 1:
        m = ncell - 1
    elif m < 0:
        m = 0
    return _AX_OFF[ax, k] + m, r - m, _AX_DX[ax, k]


@njit(cache=True, error_model="numpy", inline="always")
def _qcell(pm: float) -> tuple[int, int, float, float, float, float, float, float]:
    """Segment, q-cell, cubic Hermite basis in q (a1, a3 times the cell width), t, dq."""
    if not pm >= _PMIN:  # also NaN
        pm = _PMIN
    if pm < _P13:
        seg = 0
        q = pm
    elif pm < _PC:
        seg = 1
        q = math.sqrt(_PC - pm)
    else:
        seg = 2
        q = pm
    i, t, dq = _locate(seg, q)
    t2 = t * t
    t3 = t2 * t
    return (seg, i, 2.0 * t3 - 3.0 * t2 + 1.0, (t3 - 2.0 * t2 + t) * dq, 3.0 * t2 - 2.0 * t3,
            (t3 - t2) * dq, t, dq)


@njit(cache=True, error_model="numpy")
def _curve(seg: int, i: int, c: int, a0: float, a1: float, a2: float, a3: float) -> float:
    """Curve c of segment seg in q-cell i (cubic Hermite; a1, a3 include the width)."""
    nc = _NCURVE[seg]
    k = _COFF[seg] + (i * nc + c) * 2
    k1 = k + nc * 2
    cdat = carray(_CDAT_PTR(), _NCDAT)
    return (a0 * cdat[k] + a1 * cdat[k + 1]) + (a2 * cdat[k1] + a3 * cdat[k1 + 1])


@njit(cache=True, error_model="numpy")
def _column(dat: np.ndarray, b: int, i: int, j: int, a0: float, a1: float, a2: float,
            a3: float) -> tuple[float, float]:
    """Value and d/dxi at xi-node j of patch b, Hermite-interpolated in q within q-cell i."""
    nxi = _NXI[b]
    k0 = _POFF[b] + (i * nxi + j) * 4
    k1 = k0 + nxi * 4
    # pairwise sums (shorter dependency chains than left-to-right accumulation)
    g = (a0 * dat[k0] + a1 * dat[k0 + 1]) + (a2 * dat[k1] + a3 * dat[k1 + 1])
    gx = (a0 * dat[k0 + 2] + a1 * dat[k0 + 3]) + (a2 * dat[k1 + 2] + a3 * dat[k1 + 3])
    return g, gx


@njit(cache=True, error_model="numpy", inline="always")
def _where(pm: float, hk: float) -> tuple[int, int, float, float, float, float, int, float,
                                          float]:
    """Locate (p, h): segment, q-cell, q basis, patch and its h bounds (lo, hi).

    Patch -1 is the two-phase dome (then lo = h_l, hi = h_v). Region boundaries as
    IAPWS97(P, h): region 1 for h <= h13(p), region 2 for h >= h23(p), region 3 between,
    two-phase for h_l(p) < h < h_v(p).
    """
    seg, i, a0, a1, a2, a3, _, _ = _qcell(pm)
    b = -1  # two-phase unless a single-phase patch is found below
    if seg == 0:
        lo = _curve(0, i, 1, a0, a1, a2, a3)  # hl
        hi = _curve(0, i, 2, a0, a1, a2, a3)  # hv
        if hk <= lo:
            b, hi, lo = _S0_L1, lo, _curve(0, i, 0, a0, a1, a2, a3)
        elif hk >= hi:
            b, lo, hi = _S0_V2, hi, _curve(0, i, 3, a0, a1, a2, a3)
    elif seg == 1:
        h13 = _curve(1, i, 1, a0, a1, a2, a3)
        h23 = _curve(1, i, 4, a0, a1, a2, a3)
        lo = _curve(1, i, 2, a0, a1, a2, a3)  # hl
        hi = _curve(1, i, 3, a0, a1, a2, a3)  # hv
        if hk >= h23:
            b, lo, hi = _S1_V2, h23, _curve(1, i, 5, a0, a1, a2, a3)
        elif hk <= h13:
            b, lo, hi = _S1_L1, _curve(1, i, 0, a0, a1, a2, a3), h13
        elif hk <= lo:
            b, hi, lo = _S1_L3, lo, h13 - _M13
        elif hk >= hi:
            b, lo, hi = _S1_V3, hi, h23 + _M23
    else:
        h13 = _curve(2, i, 1, a0, a1, a2, a3)
        h23 = _curve(2, i, 2, a0, a1, a2, a3)
        if hk <= h13:
            b, lo, hi = _S2_L1, _curve(2, i, 0, a0, a1, a2, a3), h13
        elif hk < h23:
            b, lo, hi = _S2_S3, h13 - _M13, h23 + _M23
        else:
            b, lo, hi = _S2_V2, h23, _curve(2, i, 3, a0, a1, a2, a3)
    return seg, i, a0, a1, a2, a3, b, lo, hi


# ---------------------------------------------------------------------------------------
# Fast path: uniform (p, h) rectangle in region 2
# ---------------------------------------------------------------------------------------


@njit(cache=True, error_model="numpy")
def _ucell(x: float, n: int) -> tuple[int, float]:
    """Cell index in [0, n - 1] and local coordinate of x (in cell units) on a uniform axis.

    x is clamped to [0, n] (NaN to 0).
    """
    if not x > 0.0:
        x = 0.0
    elif x > n:
        x = float(n)
    i = int(x)
    if i > n - 1:
        i = n - 1
    return i, x - i


@njit(cache=True, error_model="numpy")
def _hermite(t: float) -> tuple[float, float, float, float]:
    """Cubic Hermite basis on a unit cell: weights of f(0), f'(0), f(1), f'(1)."""
    t2 = t * t
    t3 = t2 * t
    return 2.0 * t3 - 3.0 * t2 + 1.0, t3 - 2.0 * t2 + t, 3.0 * t2 - 2.0 * t3, t3 - t2


@njit(cache=True, error_model="numpy")
def _fcol(tab: np.ndarray, i: int, j: int, a0: float, a1: float, a2: float,
          a3: float) -> tuple[float, float]:
    """Value and d/(cell coordinate) at node j of a fast table, Hermite in p in p-cell i."""
    g = (a0 * tab[i, j, 0] + a1 * tab[i, j, 1]) + (a2 * tab[i + 1, j, 0] + a3 * tab[i + 1, j, 1])
    gu = (a0 * tab[i, j, 2] + a1 * tab[i, j, 3]) + (a2 * tab[i + 1, j, 2] + a3 * tab[i + 1, j, 3])
    return g, gu


@njit(cache=True, error_model="numpy")
def _fast(pm: float, hk: float, want: int) -> tuple[float, float, float, float]:
    """``_lookup`` on the fast rectangle: plain Hermite bicubic on the uniform (p, h) grid.

    The caller ensures _FP0 <= pm <= _FP1 and _FH0 <= hk <= _FH1.
    """
    ft = carray(_FT_PTR(), _FT_SHAPE)
    fr = carray(_FR_PTR(), _FT_SHAPE)
    i, t = _ucell((pm - _FP0) * _FPINV, _FNP)
    j, u = _ucell((hk - _FH0) * _FHINV, _FNH)
    a0, a1, a2, a3 = _hermite(t)
    b0, b1, b2, b3 = _hermite(u)
    u2 = u * u
    e0 = (6.0 * u2 - 6.0 * u) * _FHINV  # d/dh of the basis (e2 = -e0)
    e1 = (3.0 * u2 - 4.0 * u + 1.0) * _FHINV
    e3 = (3.0 * u2 - 2.0 * u) * _FHINV
    T = 0.0
    dT = 0.0
    rho = 0.0
    drho = 0.0
    if want != 1:
        g0, gu0 = _fcol(ft, i, j, a0, a1, a2, a3)
        g1, gu1 = _fcol(ft, i, j + 1, a0, a1, a2, a3)
        T = (b0 * g0 + b1 * gu0) + (b2 * g1 + b3 * gu1)
        dT = e0 * (g0 - g1) + (e1 * gu0 + e3 * gu1)
    if want != 0:
        g0, gu0 = _fcol(fr, i, j, a0, a1, a2, a3)
        g1, gu1 = _fcol(fr, i, j + 1, a0, a1, a2, a3)
        rho = (b0 * g0 + b1 * gu0) + (b2 * g1 + b3 * gu1)
        drho = e0 * (g0 - g1) + (e1 * gu0 + e3 * gu1)
    return T, dT, rho, drho


@njit(cache=True, error_model="numpy")
def _cell_root(f0: float, f1: float, c0: float, c1: float, u: float) -> float:
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


@njit(cache=True, error_model="numpy")
def _fast_h_of_T(pm: float, T: float) -> float:
    """h (kJ/kg) inverting the fast T table at (MPa, K), NaN if T lies outside its range.

    Start value from the h(p, tau) table, tau = (T - T_lo(p)) / (T_hi(p) - T_lo(p)) with
    T_lo, T_hi the T table at the rectangle's h edges; then a walk to the h-cell whose
    node temperatures bracket T and a safeguarded Halley solve of its cubic. The caller
    ensures _FP0 <= pm <= _FP1.
    """
    ft = carray(_FT_PTR(), _FT_SHAPE)
    fg = carray(_FG_PTR(), _FG_SHAPE)
    i, t = _ucell((pm - _FP0) * _FPINV, _FNP)
    a0, a1, a2, a3 = _hermite(t)
    t_lo = _fcol(ft, i, 0, a0, a1, a2, a3)[0]
    t_hi = _fcol(ft, i, _FNH, a0, a1, a2, a3)[0]
    if not t_lo <= T <= t_hi:
        return math.nan
    k, w = _ucell((T - t_lo) / (t_hi - t_lo) * _FNG, _FNG)
    g0, gw0 = _fcol(fg, i, k, a0, a1, a2, a3)
    g1, gw1 = _fcol(fg, i, k + 1, a0, a1, a2, a3)
    c0, c1, c2, c3 = _hermite(w)
    j, u = _ucell(((c0 * g0 + c1 * gw0) + (c2 * g1 + c3 * gw1) - _FH0) * _FHINV, _FNH)
    g0, gu0 = _fcol(ft, i, j, a0, a1, a2, a3)
    g1, gu1 = _fcol(ft, i, j + 1, a0, a1, a2, a3)
    while T < g0 and j > 0:  # rarely taken: the start value is within ~0.01 kJ/kg
        j -= 1
        u = 1.0
        g1, gu1 = g0, gu0
        g0, gu0 = _fcol(ft, i, j, a0, a1, a2, a3)
    while T > g1 and j < _FNH - 1:
        j += 1
        u = 0.0
        g0, gu0 = g1, gu1
        g1, gu1 = _fcol(ft, i, j + 1, a0, a1, a2, a3)
    return _FH0 + (j + _cell_root(g0 - T, g1 - T, gu0, gu1, u)) * _FDH


@njit(cache=True, error_model="numpy")
def _patch_lookup(pm: float, hk: float, want: int) -> tuple[float, float, float, float]:
    """``_lookup`` on the patch tables (any (p, h); clamped to the table domain)."""
    tdat = carray(_TDAT_PTR(), _NTDAT)
    rdat = carray(_RDAT_PTR(), _NTDAT)
    if hk != hk:  # NaN enthalpy: lower table edge
        hk = -math.inf
    seg, i, a0, a1, a2, a3, b, lo, hi = _where(pm, hk)
    T = 0.0
    dT = 0.0
    rho = 0.0
    drho = 0.0
    if b < 0:  # two-phase dome: lo = hl, hi = hv
        c = 4 if seg == 0 else 6
        if want != 1:
            T = _curve(seg, i, c, a0, a1, a2, a3)
        if want != 0:
            vl = 1.0 / _curve(seg, i, c + 1, a0, a1, a2, a3)
            vv = 1.0 / _curve(seg, i, c + 2, a0, a1, a2, a3)
            dvdh = (vv - vl) / (hi - lo)
            rho = 1.0 / (vl + (hk - lo) * dvdh)
            drho = -rho * rho * dvdh
        return T, dT, rho, drho
    iw = 1.0 / (hi - lo)
    j, u, dxi = _locate(3 + b, (hk - lo) * iw)
    u2 = u * u
    u3 = u2 * u
    b0 = 2.0 * u3 - 3.0 * u2 + 1.0
    b1 = (u3 - 2.0 * u2 + u) * dxi
    b2 = 3.0 * u2 - 2.0 * u3
    b3 = (u3 - u2) * dxi
    e0 = (6.0 * u2 - 6.0 * u) / dxi * iw
    e1 = (3.0 * u2 - 4.0 * u + 1.0) * iw
    e3 = (3.0 * u2 - 2.0 * u) * iw
    if want != 1:
        g0, gx0 = _column(tdat, b, i, j, a0, a1, a2, a3)
        g1, gx1 = _column(tdat, b, i, j + 1, a0, a1, a2, a3)
        T = (b0 * g0 + b1 * gx0) + (b2 * g1 + b3 * gx1)
        dT = e0 * (g0 - g1) + (e1 * gx0 + e3 * gx1)
    if want != 0:
        g0, gx0 = _column(rdat, b, i, j, a0, a1, a2, a3)
        g1, gx1 = _column(rdat, b, i, j + 1, a0, a1, a2, a3)
        rho = (b0 * g0 + b1 * gx0) + (b2 * g1 + b3 * gx1)
        drho = e0 * (g0 - g1) + (e1 * gx0 + e3 * gx1)
    return T, dT, rho, drho


@njit(cache=True, error_model="numpy")
def _lookup(pm: float, hk: float, want: int) -> tuple[float, float, float, float]:
    """(T K, dT/dh K per kJ/kg, rho kg/m3, drho/dh) at (MPa, kJ/kg).

    ``want``: 0 computes T only, 1 rho only, 2 both (the others are returned as 0).
    The fast table inside its rectangle, the patch tables elsewhere.
    """
    if pm > _PMAX:  # clamp first, so that the fast path also serves p > P_MAX
        pm = _PMAX
    if _FP0 <= pm <= _FP1 and _FH0 <= hk <= _FH1:  # False for NaN
        return _fast(pm, hk, want)
    return _patch_lookup(pm, hk, want)


@njit(cache=True, error_model="numpy", inline="always")
def _select_T(pm: float, T: float) -> tuple[int, int, float, float, float, float, int, float,
                                            float]:
    """Locate (p, T): like ``_where`` but with the (p, T) region logic of IAPWS97(P, T).

    Liquid for T < Tsat(p), vapour for T >= Tsat(p) (subcritical); region 1 for
    T <= 623.15 K, region 2 for T >= T_B23(p), region 3 between (p > 16.529 MPa).
    """
    seg, i, a0, a1, a2, a3, _, _ = _qcell(pm)
    t_b23 = _B23_N4 + math.sqrt(max(pm - _B23_N5, 0.0) / _B23_N3)
    if seg == 0:
        if T < _curve(0, i, 4, a0, a1, a2, a3):
            b, c_lo, c_hi = _S0_L1, 0, 1
        else:
            b, c_lo, c_hi = _S0_V2, 2, 3
    elif T <= _T13:
        b, c_lo, c_hi = (_S1_L1 if seg == 1 else _S2_L1), 0, 1
    elif seg == 1:
        if T < _curve(1, i, 6, a0, a1, a2, a3):
            b, c_lo, c_hi = _S1_L3, 1, 2
        elif T < t_b23:
            b, c_lo, c_hi = _S1_V3, 3, 4
        else:
            b, c_lo, c_hi = _S1_V2, 4, 5
    elif T < t_b23:
        b, c_lo, c_hi = _S2_S3, 1, 2
    else:
        b, c_lo, c_hi = _S2_V2, 2, 3
    m_lo, m_hi = _MARG[b, 0], _MARG[b, 1]
    lo = _curve(seg, i, c_lo, a0, a1, a2, a3) - m_lo
    hi = _curve(seg, i, c_hi, a0, a1, a2, a3) + m_hi
    return seg, i, a0, a1, a2, a3, b, lo, hi


@njit(cache=True, error_model="numpy")
def _patch_h_of_T(pm: float, T: float) -> float:
    """h (kJ/kg) at (MPa, K): exact inverse of the T table on the patch holding (p, T).

    Binary search for the xi-cell over the q-interpolated node temperatures (monotone in
    xi), then a safeguarded Halley solve of that cell's Hermite cubic. T outside the
    patch range is clamped to its edge.
    """
    tdat = carray(_TDAT_PTR(), _NTDAT)
    _, i, a0, a1, a2, a3, b, lo, hi = _select_T(pm, T)
    nxi = _NXI[b]
    g_lo, gx_lo = _column(tdat, b, i, 0, a0, a1, a2, a3)
    if not T > g_lo:
        return lo
    g_hi, gx_hi = _column(tdat, b, i, nxi - 1, a0, a1, a2, a3)
    if T >= g_hi:
        return hi
    jl = 0
    jh = nxi - 1
    while jh - jl > 1:
        jm = (jl + jh) >> 1
        g, gx = _column(tdat, b, i, jm, a0, a1, a2, a3)
        if g <= T:
            jl, g_lo, gx_lo = jm, g, gx
        else:
            jh, g_hi, gx_hi = jm, g, gx
    # node coordinate and width of xi-cell jl
    ax = 3 + b
    k = 0
    while k < _AX_NZ[ax] - 1 and jl >= _AX_OFF[ax, k + 1]:
        k += 1
    dxi = _AX_DX[ax, k]
    x0 = _AX_X0[ax, k] + (jl - _AX_OFF[ax, k]) * dxi
    # cubic F(u) - T on the cell, started from the secant root
    f0 = g_lo - T
    f1 = g_hi - T
    u = _cell_root(f0, f1, dxi * gx_lo, dxi * gx_hi, f0 / (f0 - f1))
    return lo + (x0 + u * dxi) * (hi - lo)


@njit(cache=True, error_model="numpy")
def _h_of_T(pm: float, T: float) -> float:
    """h (kJ/kg) at (MPa, K): exact inverse of the T table that ``_lookup`` uses there.

    The fast table if T lies within its range at p (then h lies in the fast rectangle),
    the patch tables otherwise.
    """
    if pm > _PMAX:
        pm = _PMAX
    if _FP0 <= pm <= _FP1:
        h = _fast_h_of_T(pm, T)
        if h == h:
            return h
    return _patch_h_of_T(pm, T)


@njit(cache=True, error_model="numpy")
def _sat(pm: float) -> tuple[float, float, float, float, float, float, float, float, float,
                             float]:
    """Tsat, rho_l, rho_v, h_l, h_v and their d/dp (MPa, kJ/kg units), pm in [PMIN, pc)."""
    if not pm >= _PMIN:
        pm = _PMIN
    if pm < _P13:
        seg, q, dpdq = 0, pm, 1.0
        cs = (4, 5, 6, 1, 2)  # Tsat, rhol, rhov, hl, hv
    else:
        seg, q = 1, math.sqrt(max(_PC - pm, 0.0))
        dpdq = -2.0 * max(q, _SMIN)  # dp/dq at the (clamped) point
        cs = (6, 7, 8, 2, 3)
    i, t, dq = _locate(seg, q)
    t2 = t * t
    t3 = t2 * t
    a0 = 2.0 * t3 - 3.0 * t2 + 1.0
    a1 = (t3 - 2.0 * t2 + t) * dq
    a2 = 3.0 * t2 - 2.0 * t3
    a3 = (t3 - t2) * dq
    d0 = (6.0 * t2 - 6.0 * t) / dq
    d1 = 3.0 * t2 - 4.0 * t + 1.0
    d2 = -d0
    d3 = 3.0 * t2 - 2.0 * t
    v0 = _curve(seg, i, cs[0], a0, a1, a2, a3)
    v1 = _curve(seg, i, cs[1], a0, a1, a2, a3)
    v2 = _curve(seg, i, cs[2], a0, a1, a2, a3)
    v3 = _curve(seg, i, cs[3], a0, a1, a2, a3)
    v4 = _curve(seg, i, cs[4], a0, a1, a2, a3)
    e0 = _curve(seg, i, cs[0], d0, d1, d2, d3) / dpdq
    e1 = _curve(seg, i, cs[1], d0, d1, d2, d3) / dpdq
    e2 = _curve(seg, i, cs[2], d0, d1, d2, d3) / dpdq
    e3 = _curve(seg, i, cs[3], d0, d1, d2, d3) / dpdq
    e4 = _curve(seg, i, cs[4], d0, d1, d2, d3) / dpdq
    return v0, v1, v2, v3, v4, e0, e1, e2, e3, e4


# ---------------------------------------------------------------------------------------
# Public API (SI units)
# ---------------------------------------------------------------------------------------


@njit(cache=True, error_model="numpy")
def T_ph(p: float, h: float) -> float:
    """Temperature T(p, h).

    Args:
        p: Pressure (Pa).
        h: Specific enthalpy (J/kg).

    Returns:
        Temperature (K); Tsat(p) inside the two-phase dome. Inputs outside the table
        domain are clamped to its edge.
    """
    return _lookup(p * 1e-6, h * 1e-3, 0)[0]


@njit(cache=True, error_model="numpy")
def T_dTdh_ph(p: float, h: float) -> tuple[float, float]:
    """Temperature and its derivative at constant pressure (for Jacobians).

    Args:
        p: Pressure (Pa).
        h: Specific enthalpy (J/kg).

    Returns:
        (T in K, dT/dh at constant p in K per J/kg). dT/dh is 0 inside the dome; outside
        the table domain, value and derivative at the clamped point.
    """
    T, d, _, _ = _lookup(p * 1e-6, h * 1e-3, 0)
    return T, d * 1e-3


@njit(cache=True, error_model="numpy")
def rho_ph(p: float, h: float) -> float:
    """Density rho(p, h) (kg/m3); homogeneous mixture density inside the dome.

    Args:
        p: Pressure (Pa).
        h: Specific enthalpy (J/kg).
    """
    return _lookup(p * 1e-6, h * 1e-3, 1)[2]


@njit(cache=True, error_model="numpy")
def rho_drhodh_ph(p: float, h: float) -> tuple[float, float]:
    """Density and its derivative at constant pressure (for Jacobians).

    Args:
        p: Pressure (Pa).
        h: Specific enthalpy (J/kg).

    Returns:
        (rho in kg/m3, drho/dh at constant p in kg/m3 per J/kg).
    """
    _, _, r, d = _lookup(p * 1e-6, h * 1e-3, 1)
    return r, d * 1e-3


@njit(cache=True, error_model="numpy")
def T_rho_ph(p: float, h: float) -> tuple[float, float, float, float]:
    """T, dT/dh, rho and drho/dh at (p, h) with a single table location (cheaper than
    ``T_dTdh_ph`` plus ``rho_drhodh_ph``; for superheater segment updates).

    Args:
        p: Pressure (Pa).
        h: Specific enthalpy (J/kg).

    Returns:
        (T K, dT/dh K per J/kg, rho kg/m3, drho/dh kg/m3 per J/kg).
    """
    T, dT, r, dr = _lookup(p * 1e-6, h * 1e-3, 2)
    return T, dT * 1e-3, r, dr * 1e-3


@njit(cache=True, error_model="numpy")
def h_pT(p: float, T: float) -> float:
    """Specific enthalpy h(p, T) (J/kg) of single-phase water or steam.

    Compressed liquid for T < Tsat(p), superheated vapour for T >= Tsat(p) (at exactly
    Tsat the saturated-vapour value); supercritical above 22.064 MPa. Exact inverse of
    the ``T_ph`` table. Inputs outside the table domain are clamped.

    Args:
        p: Pressure (Pa).
        T: Temperature (K).
    """
    return _h_of_T(p * 1e-6, T) * 1e3


@njit(cache=True, error_model="numpy")
def cp_pT(p: float, T: float) -> float:
    """Isobaric heat capacity cp(p, T) = 1 / (dT/dh)_p of the T table (J/(kg K)).

    Args:
        p: Pressure (Pa).
        T: Temperature (K).
    """
    pm = p * 1e-6
    d = _lookup(pm, _h_of_T(pm, T), 0)[1]
    return 1e3 / max(d, 1e-12)


@njit(cache=True, error_model="numpy")
def sat_p(p: float) -> tuple[float, float, float, float, float, float, float, float, float,
                             float]:
    """Saturation properties and their pressure derivatives (drum-boiler models).

    Valid (and tested) for 0.5 MPa <= p <= 21.5 MPa; p is clamped to [0.2 MPa, pc). IF97
    itself jumps slightly (h, rho) at p = 16.529 MPa, where the saturated states switch
    from regions 1 / 2 to region 3; the derivatives are one-sided there.

    Args:
        p: Pressure (Pa).

    Returns:
        (Tsat K, rho_l kg/m3, rho_v kg/m3, h_l J/kg, h_v J/kg, dTsat/dp K/Pa,
        drho_l/dp, drho_v/dp in kg/m3/Pa, dh_l/dp, dh_v/dp in J/kg/Pa).
    """
    Ts, rl, rv, hl, hv, dTs, drl, drv, dhl, dhv = _sat(p * 1e-6)
    return (Ts, rl, rv, hl * 1e3, hv * 1e3, dTs * 1e-6, drl * 1e-6, drv * 1e-6, dhl * 1e-3,
            dhv * 1e-3)


@njit(cache=True, error_model="numpy")
def Tsat_p(p: float) -> float:
    """Saturation temperature (K) at p (Pa); Tc at and above pc, clamped below 0.2 MPa.

    Args:
        p: Pressure (Pa).
    """
    pm = p * 1e-6
    if pm >= _PC:
        return _TC
    return _sat(pm)[0]


@njit(cache=True, error_model="numpy")
def h_limits_p(p: float) -> tuple[float, float]:
    """Table enthalpy range (J/kg) at p (Pa), p clamped: (h(p, 10 C), h(p, 800 C)).

    Args:
        p: Pressure (Pa).
    """
    seg, i, a0, a1, a2, a3, _, _ = _qcell(p * 1e-6)
    ctop = 5 if seg == 1 else 3
    return _curve(seg, i, 0, a0, a1, a2, a3) * 1e3, _curve(seg, i, ctop, a0, a1, a2, a3) * 1e3


def check_domain(p: float | np.ndarray, h: float | np.ndarray | None = None) -> None:
    """Raise ValueError unless every (p, h) lies inside the table domain.

    Args:
        p: Pressure(s) in Pa; must lie in [P_MIN, P_MAX] = [0.2, 35] MPa.
        h: Specific enthalpy(ies) in J/kg (broadcast against p); must lie between
            h(p, 10 C) and h(p, 800 C). Omit to check the pressure only.

    Raises:
        ValueError: naming the first offending value and the admissible range.
    """
    pa = np.asarray(p, dtype=np.float64)
    if h is None:
        bad = ~((pa >= P_MIN) & (pa <= P_MAX))
        if bad.any():
            v = pa[bad].ravel()[0]
            raise ValueError(
                f"steam tables: p = {v:.6g} Pa outside [{P_MIN:.6g}, {P_MAX:.6g}] Pa"
            )
        return
    pa, ha = np.broadcast_arrays(pa, np.asarray(h, dtype=np.float64))
    for pv, hv in zip(pa.ravel(), ha.ravel(), strict=True):
        if not (P_MIN <= pv <= P_MAX):
            raise ValueError(
                f"steam tables: p = {pv:.6g} Pa outside [{P_MIN:.6g}, {P_MAX:.6g}] Pa"
            )
        lo, hi = h_limits_p(float(pv))
        if not (lo <= hv <= hi):
            raise ValueError(
                f"steam tables: h = {hv:.6g} J/kg at p = {pv:.6g} Pa outside "
                f"[{lo:.6g}, {hi:.6g}] J/kg (10 C .. 800 C)"
            )
