"""Where an env step's time goes: ns per env-step for each component, per plant.

    python benchmarks/step_profile.py [--envs ID,...] [--batch 4096] [--seconds 0.5]

For each plant, on one thread, at B = 1 and B = ``--batch`` rows of the native vector env
(scenario ``load_following``, after 50 steps so the states are realistic):

- **env step**: the whole ``VectorEnv.step``, per env-step;
- **commands**: action checks and scaling (``to_commands``);
- **plant step**: the plant's compiled step (for ROS2 plants split into the next five);
  - **RHS**: the right-hand-side evaluations of the step (``2 n_sub``, one with the
    Jacobian), timed on the rows' states, *including* the steam lookups they make;
  - **steam lookups**: the IF97 table lookups of those evaluations: calls counted per
    step (below), each function timed on the arguments it was called with;
  - **W solve**: the ``2 n_sub`` block forward substitutions of ROS2;
  - **outputs**: the output map, steam lookups included;
  - **integrator rest**: plant step minus the above (stage vector updates, exact valve
    travel, projection);
- **schedules**: scenario schedules (load, bias, setpoint) of every row;
- **observation + reward**: the rest of ``advance`` (noise, normalization, trips, reward);
- **Python**: env step minus commands, plant step and ``advance``: what the interpreter
  spends around the kernels (argument passing, info, autoreset bookkeeping).

``--asm`` also compiles each plant afresh in a subprocess (an empty cache folder: numba
cannot disassemble code loaded from its cache) and counts, in the machine code of the
plant step and of ``advance``, the double-precision arithmetic instructions that work on
packed vectors (``...pd``) against scalar ones (``...sd``), and the instructions touching
256-bit registers: whether LLVM put the vector units to work.

Steam calls are counted in a subprocess that runs the plant's step as plain Python
(numba's ``njit`` replaced by the identity for plant code, the steam kernels compiled and
wrapped in counters), so the counts are those of the compiled step's code paths. The parts
of the plant step and the schedules are timed in compiled loops over the rows (compute per
row); env step, commands, plant step and ``advance`` are timed as called from Python, so at
B = 1 they include the call overhead. Every component is timed in ``--repeats``
interleaved repetitions and the fastest kept; the derived columns (integrator rest,
observation + reward, Python) are differences of such timings and carry their noise.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable

import gymnasium as gym
import numpy as np

import steamtemp_gym
from steamtemp_gym._jit import njit
from steamtemp_gym.envs.kernels import advance, schedules, to_commands
from steamtemp_gym.envs.state import ROW_FIELDS
from steamtemp_gym.plants import threads
from steamtemp_gym.plants.integrator import block_solve
from steamtemp_gym.plants.specialize import specialize

# ---------------------------------------------------------------- counting (subprocess)

COUNT = r"""
import collections, json, sys, types
import numpy as np
import steamtemp_gym.steam as S          # compiled as usual
import steamtemp_gym._jit as J
J.njit = lambda *a, **k: a[0] if (a and callable(a[0]) and not k) else (lambda f: f)

phase = ["other"]
counts = collections.Counter()
samples = collections.defaultdict(list)
proxy = types.ModuleType(S.__name__)
proxy.__dict__.update(S.__dict__)
for name in S.__all__:
    f = getattr(S, name)
    if hasattr(f, "py_func"):
        def counted(*a, _f=f, _n=name):
            counts[phase[0] + ":" + _n] += 1
            if phase[0] != "other" and len(samples[_n]) < 4000:
                samples[_n].append([float(v) for v in a])
            return _f(*a)
        setattr(proxy, name, counted)
sys.modules[S.__name__] = proxy

import steamtemp_gym.plants.specialize as SP

rhs_u = []  # the inputs the first RHS evaluation of the step receives

def phased(key, fn):
    def run(*a):
        if key == "rhs" and phase[0] != "other" and not rhs_u:
            rhs_u.extend(float(v) for v in a[1])
        outer, phase[0] = phase[0], key
        try:
            return fn(*a)
        finally:
            phase[0] = outer
    return run

template = SP.specialize
def specialize(t, name, **bound):
    for key in ("rhs", "outputs"):
        if key in bound:
            bound[key] = phased(key, bound[key])
    return template(t, name, **bound)
SP.specialize = specialize

import steamtemp_gym.plants as plants
plant = plants.make(sys.argv[1])
mod = sys.modules[plant.kernel().__module__]
for key in ("rhs", "outputs"):
    if callable(getattr(mod, key, None)):
        setattr(mod, key, phased(key, getattr(mod, key)))
d = np.array([0.85, 0.0, 0.0, 1.0, 0.0])
x, z = plant.steady_outputs(d)
X, D, Z = x[None].copy(), d[None].copy(), z[None].copy()
U = np.full((1, plant.n_u), 0.5)
counts.clear()
samples.clear()
phase[0] = "step"
plant.step(X, U, D, Z)
phase[0] = "other"
print(json.dumps({"counts": counts, "samples": samples, "rhs_u": rhs_u}))
"""


def steam_calls(env_id: str) -> tuple[dict[str, int], dict[str, np.ndarray], np.ndarray]:
    """Steam calls of one step of one row, as {"phase:function": n}, their arguments, and
    the inputs the RHS receives (plants with exact lags pass interval means, not U)."""
    out = subprocess.run(
        [sys.executable, "-c", COUNT, env_id], capture_output=True, text=True, check=True
    ).stdout
    data = json.loads(out.strip().splitlines()[-1])
    samples = {k: np.array(v) for k, v in data["samples"].items()}
    return data["counts"], samples, np.array(data["rhs_u"])


ASM = r"""
import json, re, sys
import gymnasium as gym
import steamtemp_gym
from steamtemp_gym.envs.kernels import advance
env = gym.make(sys.argv[1])
env.reset(seed=0)
env.step(env.action_space.sample())
arith = re.compile(r"^\s+v?(?:add|sub|mul|div|sqrt|max|min|fn?m(?:add|sub)\d*)(pd|sd)\b", re.M)
out = {}
for name, f in (("plant step", env.unwrapped.core.plant.kernel()), ("advance", advance)):
    asm = "\n".join(f.inspect_asm(sig) for sig in f.signatures)
    kinds = arith.findall(asm)
    out[name] = {"packed": kinds.count("pd"), "scalar": kinds.count("sd"),
                 "ymm": len(re.findall(r"%ymm", asm)), "lines": asm.count("\n")}
print(json.dumps(out))
"""


def vector_units(env_id: str) -> dict[str, dict[str, int]]:
    """Packed and scalar double arithmetic in the plant step's and advance's machine code."""
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, STEAMTEMP_GYM_CACHE_DIR=cache)
        out = subprocess.run(
            [sys.executable, "-c", ASM, env_id], capture_output=True, text=True, check=True, env=env
        ).stdout
    return json.loads(out.strip().splitlines()[-1])


# ---------------------------------------------------------------- compiled timing loops

rhs = outputs = steam_fn = None  # bound per plant by specialize


def _rhs_loop(X, U, D, P, nc, reps, with_jac):
    n = X.shape[1]
    f, jd, ju, jl = np.empty(n), np.empty(n), np.zeros(n), np.empty(max(nc, 1))
    acc = 0.0
    for _ in range(reps):
        for b in range(X.shape[0]):
            rhs(X[b], U[b], D[b], P, f, jd, ju, jl, with_jac)
            acc += f[0]
    return acc


def _outputs_loop(X, U, D, P, Z, reps):
    for _ in range(reps):
        for b in range(X.shape[0]):
            outputs(X[b], U[b], D[b], P, Z[b])
    return Z[0, 0]


def _steam_loop(A, reps):
    acc = 0.0
    for _ in range(reps):
        for i in range(A.shape[0]):
            acc += steam_fn(A[i, 0], A[i, 1])
    return acc


def _steam_loop_tuple(A, reps):
    acc = 0.0
    for _ in range(reps):
        for i in range(A.shape[0]):
            acc += steam_fn(A[i, 0], A[i, 1])[0]
    return acc


def _steam_loop1(A, reps):
    acc = 0.0
    for _ in range(reps):
        for i in range(A.shape[0]):
            acc += steam_fn(A[i, 0])
    return acc


def _steam_loop1_tuple(A, reps):
    acc = 0.0
    for _ in range(reps):
        for i in range(A.shape[0]):
            acc += steam_fn(A[i, 0])[0]
    return acc


#: timing loop of a steam function by (number of arguments, returns a tuple)
STEAM_LOOPS = {
    (2, False): _steam_loop,
    (2, True): _steam_loop_tuple,
    (1, False): _steam_loop1,
    (1, True): _steam_loop1_tuple,
}


@njit(cache=True, error_model="numpy")
def _solve_loop(gh, X, jd, ju, jl, jrow, jcol, reps):
    n = X.shape[1]
    z = np.empty(n)
    acc = 0.0
    for _ in range(reps):
        for b in range(X.shape[0]):
            block_solve(gh, jd, ju, jl, jrow, jcol, X[b], z)
            acc += z[0]
    return acc


@njit(cache=True, error_model="numpy")
def _schedules_loop(slot, ep, bp_t, bp_v, bp_n, sp_nom, ou, D, sp, reps):
    for _ in range(reps):
        for b in range(D.shape[0]):
            schedules(b, slot[b], ep[b, 0], bp_t, bp_v, bp_n, sp_nom, ou, D, sp)
    return sp[0]


def per_row_ns(fn: Callable[[int], object], rows: int, seconds: float) -> tuple[int, float]:
    """(reps, ns per row) of ``fn(reps)``, with reps grown until one call takes ``seconds``."""
    fn(1)
    reps = 1
    while True:
        t0 = time.perf_counter()
        fn(reps)
        dt = time.perf_counter() - t0
        if dt > seconds or reps > 1 << 24:
            return reps, dt / (reps * rows) * 1e9
        reps *= 4


def measure(
    timers: dict[str, tuple[Callable[[int], object], int]], seconds: float, rounds: int
) -> dict[str, float]:
    """Best ns per row of each timer over ``rounds`` interleaved rounds (a slow spell of the
    host then hits every component, not one)."""
    reps = {}
    best = {}
    for name, (fn, rows) in timers.items():
        reps[name], best[name] = per_row_ns(fn, rows, seconds)
    for _ in range(rounds - 1):
        for name, (fn, rows) in timers.items():
            t0 = time.perf_counter()
            fn(reps[name])
            best[name] = min(best[name], (time.perf_counter() - t0) / (reps[name] * rows) * 1e9)
    return best


def profile(
    env_id: str, batch: int, seconds: float, rounds: int, counts, samples, rhs_u
) -> dict[str, float]:
    venv = gym.make_vec(
        env_id, num_envs=batch, vectorization_mode="vector_entry_point", scenario="load_following"
    )
    venv.reset(seed=0)
    a = np.zeros(venv.action_space.shape, dtype=np.float32)
    for _ in range(50):
        venv.step(a)
    core = venv.unwrapped.core
    plant = core.plant
    X0 = core.X.copy()
    X, Z = core.X.copy(), core.Z.copy()

    def env_step(reps: int) -> None:
        for _ in range(reps):
            venv.step(a)

    def plant_step(reps: int) -> None:  # forward from the rows' states (as the env does)
        for _ in range(reps):
            plant.step(X, core.U, core.D, Z)

    sched_args = (
        core.slot,
        core.ep,
        core.bp_t,
        core.bp_v,
        core.bp_n,
        plant.setpoint_C,
        core.ou.copy(),
        core.D.copy(),
        core.sp.copy(),
    )
    # advance on copies of the rows' arrays (X and Z as the plant step found them)
    adv = core.state._replace(**{f: getattr(core, f).copy() for f in ROW_FIELDS})
    adv = adv._replace(X=X0.copy(), Z=Z.copy())
    timers = {
        "env step": (env_step, batch),
        "commands": (lambda r: [to_commands(a, core.U) for _ in range(r)], batch),
        "plant step": (plant_step, batch),
        "schedules": (lambda r: _schedules_loop(*sched_args, r), batch),
        "advance": (lambda r: [advance(adv) for _ in range(r)], batch),
    }
    mod = sys.modules[plant.kernel().__module__]
    fns = getattr(type(plant), "kernels", None) or (
        getattr(mod, "rhs", None),
        getattr(mod, "outputs", None),
        None,
    )
    steam: list[tuple[str, int, str]] = []  # (phase, calls per step, timer)
    if fns[0] is not None:
        name = f"{type(plant).__name__}.profile"
        rl = specialize(_rhs_loop, name, rhs=fns[0])
        ol = specialize(_outputs_loop, name, outputs=fns[1])
        Uc = np.tile(rhs_u, (batch, 1))  # what the RHS saw in the counted step
        P, nc = plant.P, plant.jrow.shape[0]
        n = X0.shape[1]
        jd, ju, jl = np.empty(n), np.zeros(n), np.empty(max(nc, 1))
        Xw = X0.copy()
        fns[0](Xw[0], Uc[0], core.D[0], P, np.empty(n), jd, ju, jl, True)
        gh = (1.0 + 1.0 / np.sqrt(2.0)) * plant.dt_s / plant.n_sub
        Zc = Z.copy()
        timers.update(
            {
                "rhs+jac": (lambda r: rl(X0, Uc, core.D, P, nc, r, r >= 0), batch),
                "rhs": (lambda r: rl(X0, Uc, core.D, P, nc, r, r < 0), batch),
                "solve": (
                    lambda r: _solve_loop(gh, Xw, jd, ju, jl, plant.jrow, plant.jcol, r),
                    batch,
                ),
                "outputs": (lambda r: ol(X0, core.U, core.D, P, Zc, r), batch),
            }
        )
        for key, n_calls in counts.items():
            phase, fname = key.split(":")
            if phase not in ("rhs", "outputs") or n_calls == 0:
                continue
            f = getattr(steamtemp_gym.steam, fname)
            A = samples[fname]
            template = STEAM_LOOPS[A.shape[1], isinstance(f(*A[0]), tuple)]
            loop = specialize(template, f"profile.{fname}", steam_fn=f)
            timers["steam " + fname] = (lambda r, loop=loop, A=A: loop(A, r), A.shape[0])
            steam.append((phase, n_calls, "steam " + fname))
    t = measure(timers, seconds, rounds)
    row = {k: t[k] for k in ("env step", "commands", "plant step", "schedules")}
    if fns[0] is not None:
        row["RHS"] = plant.n_sub * (t["rhs+jac"] + t["rhs"])
        row["W solve"] = 2 * plant.n_sub * t["solve"]
        row["outputs"] = t["outputs"]
        row["steam lookups"] = sum(n_calls * t[timer] for _, n_calls, timer in steam)
        row["integrator rest"] = row["plant step"] - row["RHS"] - row["W solve"] - row["outputs"]
    row["observation + reward"] = t["advance"] - row["schedules"]
    row["Python"] = row["env step"] - row["commands"] - row["plant step"] - t["advance"]
    venv.close()
    return row


COLUMNS = (
    "env step",
    "commands",
    "plant step",
    "RHS",
    "steam lookups",
    "W solve",
    "outputs",
    "integrator rest",
    "schedules",
    "observation + reward",
    "Python",
)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--envs", default=",".join(steamtemp_gym.ENV_IDS))
    ap.add_argument("--batch", type=int, default=4096)
    ap.add_argument(
        "--seconds", type=float, default=0.25, help="length of one timed call of each component"
    )
    ap.add_argument(
        "--repeats",
        type=int,
        default=5,
        help="interleaved repetitions of each timing (the fastest kept)",
    )
    ap.add_argument("--rounds", type=int, dest="repeats", help=argparse.SUPPRESS)  # old name
    ap.add_argument(
        "--asm",
        action="store_true",
        help="count packed vs scalar arithmetic in the machine code (compiles afresh)",
    )
    args = ap.parse_args(argv)
    ids = args.envs.split(",")
    unknown = sorted(set(ids) - set(steamtemp_gym.ENV_IDS))
    if unknown:
        ap.error(f"unknown env ids {unknown}; valid: {', '.join(steamtemp_gym.ENV_IDS)}")
    threads.set_threads(1)
    print("ns per env-step, one thread (RHS includes its steam lookups; outputs too)\n")
    print("| id | B | " + " | ".join(COLUMNS) + " | steam calls/step |")
    print("|---|---|" + "---|" * (len(COLUMNS) + 1))
    for env_id in ids:
        counts, samples, rhs_u = steam_calls(env_id)
        n_steam = sum(v for k, v in counts.items() if not k.startswith("other:"))
        for batch in (1, args.batch):
            row = profile(env_id, batch, args.seconds, args.repeats, counts, samples, rhs_u)
            cells = [f"{row[c]:,.0f}" if c in row else "-" for c in COLUMNS]
            print(f"| {env_id.split('/')[1]} | {batch} | " + " | ".join(cells) + f" | {n_steam} |")
    if args.asm:
        print(
            "\ndouble arithmetic in the machine code: packed (SIMD) / scalar instructions, "
            "and instructions on 256-bit registers\n"
        )
        print("| id | kernel | packed | scalar | packed share | ymm |")
        print("|---|---|---|---|---|---|")
        for env_id in ids:
            for name, c in vector_units(env_id).items():
                share = c["packed"] / max(c["packed"] + c["scalar"], 1)
                print(
                    f"| {env_id.split('/')[1]} | {name} | {c['packed']} | {c['scalar']} | "
                    f"{share:.1%} | {c['ymm']} |"
                )


if __name__ == "__main__":
    main()
