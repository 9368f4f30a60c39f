"""The IF97 tables (``if97_tables.npz``) loaded and checked, as the constant arrays and
external symbols the compiled lookups read, and the table constants.

``_TABLES_SHA256`` pins the data file; ``scripts/generate_steam_tables.py`` updates it,
which changes the package code and thereby the folder of cached kernels
(steamtemp_gym/_cache.py).
"""

from __future__ import annotations

from pathlib import Path

import llvmlite.binding as _llvm
import numpy as np
from llvmlite import ir as _ir
from numba import types
from numba.extending import intrinsic

from steamtemp_gym.steam.digest import tables_digest

_TABLES_PATH = Path(__file__).with_name("if97_tables.npz")
_TABLES_SHA256 = "78cf6177cf9b0e35beaa9e183c0f8f46e96088a776b88ae853d325f43f1589c1"
_LAYOUT_VERSION = 2

_CURVE_NAMES = (
    ("hmin", "hl", "hv", "hmax", "Tsat", "rhol", "rhov"),
    ("hmin", "h13", "hl", "hv", "h23", "hmax", "Tsat", "rhol", "rhov"),
    ("hmin", "h13", "h23", "hmax"),
)
_BLOCK_NAMES = (
    "s0_L1",
    "s0_V2",
    "s1_L1",
    "s1_L3",
    "s1_V3",
    "s1_V2",
    "s2_L1",
    "s2_S3",
    "s2_V2",
)


def _load_tables() -> dict[str, np.ndarray]:
    """Load the npz tables and check them against this module's layout and hash."""
    with np.load(_TABLES_PATH) as z:
        data = {k: z[k] for k in z.files}
    if tables_digest(data) != _TABLES_SHA256:
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
        x0[a, nz[a] + 1 :] = x0[a, nz[a]]  # padding, never selected
        off[a, nz[a] + 1 :] = off[a, nz[a]]
    return x0, dx, 1.0 / dx, off, nz


_D = _load_tables()
(PC, TC, P13, T13, _TMIN, _TMAX, PMIN, PMAX, SMIN) = (float(v) for v in _D["constants"])
MARG = np.ascontiguousarray(_D["block_margins"], dtype=np.float64)  # (lo, hi) per patch
M13, M23 = float(MARG[7, 0]), float(MARG[7, 1])

# axes 0..2: segment q axes; axes 3..11: patch xi axes (in _BLOCK_NAMES order)
AX_X0, AX_DX, AX_INV, AX_OFF, AX_NZ = _axes(
    [_D[f"qzones{s}"] for s in range(3)] + [_D[f"xizones_{b}"] for b in _BLOCK_NAMES]
)
NXI = np.array([_D[f"T_{b}"].shape[1] for b in _BLOCK_NAMES], dtype=np.int64)
NCURVE = np.array([len(c) for c in _CURVE_NAMES], dtype=np.int64)


def _concat(arrays: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Flatten and concatenate; return (data, start offsets)."""
    flat = [np.ascontiguousarray(a, dtype=np.float64).ravel() for a in arrays]
    off = np.cumsum([0] + [a.size for a in flat])[:-1].astype(np.int64)
    return np.concatenate(flat), off


# one flat array per quantity (numba freezes arrays <= 1 MB into the compiled code)
_CDAT, COFF = _concat([_D[f"curves{s}"] for s in range(3)])
_TDAT, POFF = _concat([_D[f"T_{b}"] for b in _BLOCK_NAMES])
_RDAT, _ = _concat([_D[f"rho_{b}"] for b in _BLOCK_NAMES])


def _unit_cell(tab: np.ndarray, dx: float, dy: float) -> np.ndarray:
    """Hermite node data (value, d/dx, d/dy, d2/dxdy) rescaled to unit-cell coordinates."""
    return np.ascontiguousarray(tab * np.array([1.0, dx, dy, dx * dy]), dtype=np.float64)


# fast path: uniform (p, h) rectangle in region 2; rows of fast_axes: p, h, tau axes
(FP0, FP1, FNP), (FH0, FH1, FNH), (_, _, FNG) = (
    (float(a), float(b), int(n)) for a, b, n in _D["fast_axes"]
)
_FDP = (FP1 - FP0) / FNP  # MPa
FDH = (FH1 - FH0) / FNH  # kJ/kg
FPINV = 1.0 / _FDP
FHINV = 1.0 / FDH
_FT = _unit_cell(_D["fast_T"], _FDP, FDH)  # (p node, h node, 4)
_FR = _unit_cell(_D["fast_rho"], _FDP, FDH)
_FG = _unit_cell(_D["fast_h"], _FDP, 1.0 / FNG)  # h(p, tau): start values for h_pT
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


CDAT_PTR = _external_table("curves", _CDAT)
TDAT_PTR = _external_table("T", _TDAT)
RDAT_PTR = _external_table("rho", _RDAT)
FT_PTR = _external_table("fast_T", _FT)
FR_PTR = _external_table("fast_rho", _FR)
FG_PTR = _external_table("fast_h", _FG)
NCDAT, NTDAT, FT_SHAPE, FG_SHAPE = _CDAT.size, _TDAT.size, _FT.shape, _FG.shape

P_MIN = PMIN * 1e6  # Pa, lower table edge
P_MAX = PMAX * 1e6  # Pa, upper table edge
P_CRIT = PC * 1e6  # Pa
T_CRIT = TC  # K
T_MIN = _TMIN  # K, table edge (10 C)
T_MAX = _TMAX  # K, table edge (800 C)
# (p_min Pa, p_max Pa, h_min J/kg, h_max J/kg): where the uniform fast table is used
FAST_RECT = (FP0 * 1e6, FP1 * 1e6, FH0 * 1e3, FH1 * 1e3)

# patch ids, in _BLOCK_NAMES order
S0_L1, S0_V2, S1_L1, S1_L3, S1_V3, S1_V2, S2_L1, S2_S3, S2_V2 = range(9)
# B23 boundary T(p) coefficients (IF97 eq. 6)
B23_N3 = 0.10192970039326e-2
B23_N4 = 0.57254459862746e3
B23_N5 = 0.13918839778870e2
