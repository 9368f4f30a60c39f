"""Fuzzy P²ID: a fuzzy PI and a fuzzy PD in parallel, gains scheduled on load by a TSK system.

Source: A. Ghaffari, S. A. A. Moosavian and A. Chaibakhsh, "Experimental fuzzy modeling
and control of a once-through boiler" (K. N. Toosi University of Technology; the
Neka 440 MW unit 2), section VI and Fig. 4-7; the controller itself is from their
"Fuzzy control of a supercritical once-through boiler", Proc. ISME Int. Conf. on
Mechanical Engineering, Isfahan, 2005 (the paper's ref. [16]). Its claim: "more accurate
and less fluctuation" of the superheater temperatures than the classic controller, and
less fuel. The claim check is in tests/test_fuzzy_p2id.py on BensonSubcritical-v0.

What the paper states and what is chosen here (the text extraction lost Fig. 4, the
block diagram, and Fig. 5, the membership functions and rule base):

- Two fuzzy controllers share one rule base and one set of membership functions (Fig. 5):
  the fuzzy PI (FPI) has inputs K_i e_p and K_p e_v, the fuzzy PD (FPD) K_d e_p and
  K_p e_i. The paper does not define e_p, e_v, e_i; read here as the error, its rate
  and its integral (e, de/dt, int e dt), the only reading under which the gain letters
  fit: the FPI's output is integrated (u_I = int f(K_i e, K_p de/dt) dt ~ K_i int e +
  K_p e, the incremental fuzzy PI) and the FPD's differentiated (u_D = d/dt f(K_d e,
  K_p int e) ~ K_d de/dt + K_p e). The sum is a nonlinear P + P + I + D, hence "P²ID".
  In discrete form at the plant's interval dt (the FPI summed, the FPD differenced):

      u_k = U0 [ sum_{i<=k} (dt / T0) f(x_PI,i) + (T0 / dt) (f(x_PD,k) - f(x_PD,k-1)) ]  (P2ID)

  with x_PI = (K_i e / E0, K_p T0 de/dt / E0), x_PD = (K_d e / E0, K_p int e dt / (E0 T0))
  and f the rule base's crisp output recentred to [-1, 1]. Small-signal it is the PID
  Kc [2 K_p e + (K_i / T0) int e + K_d T0 de/dt] with Kc = U0 s0 / E0 (s0 the surface's
  slope at the origin), so K_p = 0.5, K_i = 1, K_d = 0 is the SIMC PI the conventional
  loop has (the start of the gain search).
- Normalization (section VI): every input is mapped to (0, 1) by x -> (1 + sat(x)) / 2
  (0.5 = zero error) and the output lives in (0, 20) (10 = no action). E0 = 10 K
  (``E0_K``: the error at which a unit-gain input saturates; the +-10 K field tolerance
  of once-through units in load changes; operating practice, unverified); T0 and Kc are the
  SIMC integral time and gain of the loop the P²ID replaces (baselines/cascade_pi.py's
  step-test tuning), U0 = Kc E0 / s0. The integral input is held inside its saturation
  (int e clipped to |K_p int e / (E0 T0)| <= 1) so that it does not wind up.
- Rule base (Fig. 5 lost; chosen): 7 triangular sets NB, NM, NS, ZE, PS, PM, PB evenly
  spaced on each input's (0, 1) and on the output's (0, 20) (peaks every 1/6 and 20/6,
  half-width one spacing), the Mac Vicar-Whelan diagonal table (output set index
  i + j - 3, saturated), Mamdani inference: AND = min, implication = min (clip),
  aggregation = max, centroid defuzzification; scikit-fuzzy's ControlSystem defaults,
  against which tests/test_fuzzy_p2id.py checks :func:`infer` on a grid. Per step the
  controller interpolates a precomputed surface (``SURFACE_N`` x ``SURFACE_N`` grid,
  bilinear, vectorized over rows); scikit-fuzzy is needed only by the tests.
- Gain scheduling (section VI: "a TSK fuzzy system is used to change the gains"): a
  zero-order TSK system on the measured load demand L, rules "IF L is about L_r THEN
  (K_p, K_i, K_d) = G_r" at L_r = 0.5, 0.75, 1.0 (``RULE_LOADS``, the paper's 50-100 %
  range), Gaussian memberships exp(-((L - L_r) / beta)^2) (eq. 22), beta = 0.15
  (``BETA``, about 0.6 of the rule spacing; chosen), normalized firing (eq. 24) and the
  weighted sum of the consequents (eq. 25-26).
- Gain sets: the paper's were tuned "by several trials" and are not given. Here they are
  the benchmark's common tuning (agents/baseline_tuning.py, the same search, budget,
  objective and valve-travel budget as every tunable baseline): the knobs ``kp_L``,
  ``ki_L``, ``kd_L`` are the main-steam P²IDs' (K_p, K_i, K_d) of the rule at load L
  (K_p, K_i on a log scale in 1/8-8, K_d linear in 0-1), started from the SIMC-equivalent
  set; the first stages keep that set. The result per plant is stored in
  baselines/tuned/fuzzy_p2id.json and is the default; a plant without a stored tuning
  uses the start set.

Claim check (tests/test_fuzzy_p2id.py; BensonSubcritical-v0, 5 seeds, against cascade_pi,
with the common tuning's gains): IAE ratio 1.03 / 0.80 / 0.88 and outlet-error std ratio
0.86 / 0.84 / 0.90 on load_ramp_100_50 / load_ramp_50_100 / load_following: "less
fluctuation" reproduces, "more accurate" on two of the three (a strict xfail on the 100 ->
50 % ramp). The fuel claim does not (a strict xfail): fuel equal within 0.01 % (this
unit's fuel follows the load demand through its fuel/water schedule).

Mapping onto the plants (``Plant.control_loops``; the paper uses the P²ID "for superheaters
temperature control", one per spray stage, replacing the classic loop that holds that
stage's temperature; the rest is cascade_pi's):

- cascade (inner, MAIN or another outer signal): the P²ID replaces the outer PI (the
  slow main-steam loop with "a significant delay between the water injection and its
  effect", the paper's motivation) and sets the inner setpoint; the fast inner PI on the
  attemperator outlet stays conventional (the paper describes no inner loop);
- scheduled (inner, SCHEDULED) and inner-only (inner, None) stages: the P²ID replaces
  the PI holding the stage's attemperator outlet at its load schedule (resp. start value);
- loops without an inner spray temperature (None, outer), e.g. the reheat gas
  recirculation damper of BoilerTurbineMIMO-v0: not a spray stage, cascade_pi's PI kept.

Same measurement filter (5 s), bumpless start and observation as cascade_pi. Anti-windup:
on a valve the integrated FPI part is kept inside the valve range (less the FPD part); in
a cascade the FPI increment is dropped while the inner valve is saturated in the direction
it pushes.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from baselines import tuning
from baselines.cascade_pi import CascadePI
from baselines.commissioned import commissioned
from baselines.loops import input_filter, observation_layout, pi_position, restart_rows
from baselines.tuning import Knob
from steamtemp_gym.plants.base import MAIN, SCHEDULED

#: Fuzzy set labels of the inputs and of the output (Fig. 5 lost: 7 sets chosen).
LABELS = ("NB", "NM", "NS", "ZE", "PS", "PM", "PB")
#: Universes (section VI): inputs normalized to (0, 1), output to (0, 20).
IN_RANGE = (0.0, 1.0)
OUT_RANGE = (0.0, 20.0)
#: Points of the sampled universes (the set peaks fall on them: multiples of 1/6).
UNIVERSE_N = 61
#: Grid of the precomputed control surface per input axis.
SURFACE_N = 241
#: Error (K) at which an input with unit gain saturates (module docstring).
E0_K = 10.0
#: TSK gain-scheduling rule centres (load fraction) and Gaussian width (eq. 22).
RULE_LOADS = (0.5, 0.75, 1.0)
BETA = 0.15
#: (K_p, K_i, K_d) equivalent to the SIMC PI (module docstring): the search's start.
GAINS_PI = (0.5, 1.0, 0.0)


# ----------------------------------------------------------------------------- rule base
def set_peaks(lo: float, hi: float) -> np.ndarray:
    """Peaks of the 7 evenly spaced triangular sets on [lo, hi]; half-width one spacing."""
    return np.linspace(lo, hi, len(LABELS))


def rule_table() -> np.ndarray:
    """Output set index of rule (i, j): the Mac Vicar-Whelan diagonal table, saturated."""
    i, j = np.meshgrid(range(len(LABELS)), range(len(LABELS)), indexing="ij")
    return np.clip(i + j - 3, 0, len(LABELS) - 1)


def _tri(x: np.ndarray, peaks: np.ndarray) -> np.ndarray:
    """Memberships (..., 7) of x in the triangular sets centred on ``peaks``."""
    w = peaks[1] - peaks[0]
    return np.clip(1.0 - np.abs(np.asarray(x)[..., None] - peaks) / w, 0.0, 1.0)


def infer(x1: np.ndarray, x2: np.ndarray) -> np.ndarray:
    """Crisp output in (0, 20) of the Mamdani rule base for inputs in (0, 1) (any shape).

    min AND, min implication (clip), max aggregation, centroid. The aggregated output set
    is piecewise linear; between two neighbouring output peaks it is
    max(min(c_k, 1 - t), min(c_k+1, t)) in the local coordinate t, linear between the
    breakpoints {0, 1 - c_k, c_k, c_k+1, 1 - c_k+1, 1/2, 1}, so its area and moment are
    summed exactly (scikit-fuzzy's centroid is exact for piecewise-linear sets too).
    """
    x1, x2 = np.broadcast_arrays(np.clip(x1, *IN_RANGE), np.clip(x2, *IN_RANGE))
    shape = x1.shape
    m1 = _tri(x1.ravel(), set_peaks(*IN_RANGE))
    m2 = _tri(x2.ravel(), set_peaks(*IN_RANGE))
    fire = np.minimum(m1[:, :, None], m2[:, None, :]).reshape(len(m1), -1)  # (n, 49)
    table = rule_table().ravel()
    clip = np.stack([fire[:, table == o].max(axis=1) for o in range(len(LABELS))], axis=1)
    ca, cb = clip[:, :-1, None], clip[:, 1:, None]  # (n, 6, 1): left and right set levels
    t = np.sort(
        np.clip(
            np.concatenate(np.broadcast_arrays(0.0, 1.0 - ca, ca, cb, 1.0 - cb, 0.5, 1.0), axis=2),
            0.0,
            1.0,
        ),
        axis=2,
    )
    m = np.maximum(np.minimum(ca, 1.0 - t), np.minimum(cb, t))
    peaks = set_peaks(*OUT_RANGE)
    h = peaks[1] - peaks[0]
    x = peaks[:-1, None] + h * t  # (n, 6, 7) abscissae of the breakpoints
    x0, x1_, y0, y1 = x[..., :-1], x[..., 1:], m[..., :-1], m[..., 1:]
    area = (0.5 * (x1_ - x0) * (y0 + y1)).sum(axis=(1, 2))
    moment = ((x1_ - x0) * (x0 * (2 * y0 + y1) + x1_ * (y0 + 2 * y1)) / 6.0).sum(axis=(1, 2))
    return (moment / area).reshape(shape)


def control_system() -> Any:
    """The same rule base as a scikit-fuzzy ``ControlSystem`` (the reference of the tests)."""
    import skfuzzy as fuzz
    from skfuzzy import control as ctrl

    uin = np.linspace(*IN_RANGE, UNIVERSE_N)
    uout = np.linspace(*OUT_RANGE, UNIVERSE_N)
    a = ctrl.Antecedent(uin, "x1")
    b = ctrl.Antecedent(uin, "x2")
    c = ctrl.Consequent(uout, "u")  # centroid, max aggregation by default
    for var, peaks in (
        (a, set_peaks(*IN_RANGE)),
        (b, set_peaks(*IN_RANGE)),
        (c, set_peaks(*OUT_RANGE)),
    ):
        w = peaks[1] - peaks[0]
        for lab, p in zip(LABELS, peaks, strict=True):
            var[lab] = fuzz.trimf(var.universe, [p - w, p, p + w])
    table = rule_table()
    rules = [
        ctrl.Rule(a[LABELS[i]] & b[LABELS[j]], c[LABELS[table[i, j]]])
        for i in range(len(LABELS))
        for j in range(len(LABELS))
    ]
    return ctrl.ControlSystem(rules)


@commissioned(maxsize=1)
def surface() -> tuple[np.ndarray, float]:
    """(F on the SURFACE_N^2 grid recentred to [-1, 1], slope s0 of f per unit input at 0).

    f(x) = (F(u) - 10) / 10 with u = (1 + x) / 2, x in [-1, 1] the saturated scaled input.
    """
    g = np.linspace(*IN_RANGE, SURFACE_N)
    F = infer(g[:, None], g[None, :])
    f = (F - 0.5 * sum(OUT_RANGE)) / (0.5 * (OUT_RANGE[1] - OUT_RANGE[0]))
    h = 1e-4  # slope df/dx1 at the origin (x = 2 u - 1, f = (F - 10) / 10)
    s0 = float((infer(0.5 + h / 2, 0.5) - infer(0.5 - h / 2, 0.5)) / (2.0 * h) / 10.0)
    return f, s0


def evaluate_surface(f: np.ndarray, x1: np.ndarray, x2: np.ndarray) -> np.ndarray:
    """Bilinear interpolation of the recentred surface at scaled inputs x1, x2 (any shape)."""
    n = f.shape[0] - 1
    p = (np.clip(x1, -1.0, 1.0) + 1.0) * 0.5 * n
    q = (np.clip(x2, -1.0, 1.0) + 1.0) * 0.5 * n
    i = np.minimum(p.astype(np.int64), n - 1)
    j = np.minimum(q.astype(np.int64), n - 1)
    a, b = p - i, q - j
    return (
        (1 - a) * (1 - b) * f[i, j]
        + a * (1 - b) * f[i + 1, j]
        + (1 - a) * b * f[i, j + 1]
        + a * b * f[i + 1, j + 1]
    )


def tsk_weights(load: np.ndarray) -> np.ndarray:
    """Normalized firing (eq. 22-24) of the gain-scheduling rules, shape (n, len(RULE_LOADS))."""
    mu = np.exp(-(((np.asarray(load)[:, None] - np.array(RULE_LOADS)) / BETA) ** 2))
    return mu / mu.sum(axis=1, keepdims=True)


# ------------------------------------------------------------------------------ controller
def fuzzy_loops(control_loops: Any) -> list[int]:
    """Indices of the actions that get a P²ID: the spray stages (loops with an inner signal)."""
    return [j for j, (inner, _) in enumerate(control_loops) if inner]


class FuzzyP2ID:
    """Fuzzy P²ID per spray stage plus cascade_pi's loops elsewhere (see module docstring).

    Args:
        env: The env (or native vector env) the policy acts on.
        gains: Optional gain sets, shape (n_actions, len(RULE_LOADS), 3) of (K_p, K_i, K_d)
            per action and TSK rule (rows of non-fuzzy actions ignored).
        **knobs: ``kp_<L>``, ``ki_<L>``, ``kd_<L>`` for the rule loads L = 50, 75, 100 (the
            ``KNOBS``): the gain sets of the main-steam P²IDs per rule (the other stages keep
            the SIMC-equivalent set). Knobs not given take the benchmark's stored tuning
            (baselines/tuned/fuzzy_p2id.json) where the plant has one, else the SIMC-equivalent
            :data:`GAINS_PI`.
    """

    KNOBS = tuple(
        Knob(f"{g}_{round(100 * L)}", *box)
        for L in RULE_LOADS
        for g, box in (("kp", (0.125, 8.0)), ("ki", (0.125, 8.0)), ("kd", (0.0, 1.0, False)))
    )

    @staticmethod
    def knob_defaults(env_id: str) -> dict[str, float]:
        """The search's start: the SIMC-equivalent set at every rule."""
        return {k.name: GAINS_PI["pid".index(k.name[1])] for k in FuzzyP2ID.KNOBS}

    def __init__(self, env: Any, gains: Any = None, **knobs: float | None) -> None:
        u = env.unwrapped
        plant = u.plant
        names, self._scale, self._center = observation_layout(env)
        self.i_err = names.index("error_K")
        self.i_load = names.index("load_demand")
        self.i_valve = [names.index(n) for n in plant.valves]
        self.pi = CascadePI(env)  # the loops without a spray stage, and the loop structure
        self.loops, self.schedules = self.pi.loops, self.pi.schedules
        self.fuzzy = fuzzy_loops(plant.control_loops)
        self.conventional = [j for j in range(len(self.loops)) if j not in self.fuzzy]
        self.dt = plant.dt_s
        self.a_filter = self.pi.a_filter
        self.f, s0 = surface()
        # per action: Kc, T0 of the loop the P²ID replaces (outer of a cascade, else inner)
        self.kc = np.zeros(len(self.loops))
        self.t0 = np.ones(len(self.loops))
        for j in self.fuzzy:
            kc_o, ti_o, kc_i, ti_i = self.pi.gains[j]
            cascade = self.loops[j][1] not in (None, SCHEDULED)
            self.kc[j], self.t0[j] = (kc_o, ti_o) if cascade else (kc_i, ti_i)
        self.u0 = self.kc * E0_K / s0
        self.gains = np.array(
            gains if gains is not None else self._knob_gains(plant, knobs), dtype=float
        )  # (n_act, n_rules, 3)
        self._st: dict[str, np.ndarray] | None = None
        self.inner_setpoint = np.zeros((1, len(self.loops)))

    def _knob_gains(self, plant: Any, knobs: dict[str, float | None]) -> np.ndarray:
        """(n_act, n_rules, 3) gain sets from the knobs (docstring of the class)."""
        names = {k.name for k in self.KNOBS}
        unknown = sorted(set(knobs) - names)
        if unknown:
            raise ValueError(f"unknown FuzzyP2ID knobs {unknown}; valid: {sorted(names)}")
        base = tuning.stored_or("fuzzy_p2id", plant.id, self.knob_defaults(plant.id))
        values = {**base, **{k: v for k, v in knobs.items() if v is not None}}
        g = np.tile(np.array(GAINS_PI), (len(self.loops), len(RULE_LOADS), 1))
        for r, L in enumerate(RULE_LOADS):
            row = [float(values[f"{x}_{round(100 * L)}"]) for x in ("kp", "ki", "kd")]
            if not (np.all(np.isfinite(row)) and row[0] > 0 and row[1] > 0 and row[2] >= 0):
                raise ValueError(
                    f"fuzzy P2ID gains at {L:.0%} load must be finite with "
                    f"K_p, K_i > 0 and K_d >= 0, got {row}"
                )
            for j in self.fuzzy:
                if self.loops[j][1] == MAIN:
                    g[j, r] = row
        return g

    def reset(self) -> None:
        self._st = None
        self.pi.reset()

    def _restart(self, st: dict[str, np.ndarray], rows: np.ndarray, y: np.ndarray) -> None:
        st["y0"][rows], st["v0"][rows], st["yf"][rows] = y[rows], y[rows][:, self.i_valve], y[rows]
        st["ii"][rows], st["ie"][rows], st["fpd"][rows] = 0.0, 0.0, 0.0
        st["e1"][rows] = np.nan  # no rate on the first step
        for j in self.fuzzy:
            inner, outer = self.loops[j]
            # integrated FPI part of the P²ID output: inner setpoint (cascade) or valve
            st["u"][rows, j] = (
                y[rows, inner] if outer not in (None, SCHEDULED) else y[rows, self.i_valve[j]]
            )

    def _errors(self, st: dict[str, np.ndarray], yf: np.ndarray, load: np.ndarray, n: int):
        """Error per fuzzy loop that the P²ID acts on, (n, n_act) (0 for the others)."""
        e = np.zeros((n, len(self.loops)))
        for j in self.fuzzy:
            inner, outer = self.loops[j]
            if outer == MAIN:
                e[:, j] = yf[:, self.i_err]
            elif outer == SCHEDULED:
                e[:, j] = np.interp(load, *self.schedules[j]) - yf[:, inner]
            elif outer is None:
                e[:, j] = st["y0"][:, inner] - yf[:, inner]
            else:
                e[:, j] = st["y0"][:, outer] - yf[:, outer]
        return e

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        obs = np.atleast_2d(np.asarray(observation, dtype=np.float64))
        y = obs * self._scale + self._center
        n, m = obs.shape[0], len(self.loops)
        st = self._st
        fresh = st is None or st["y0"].shape != y.shape
        if fresh:
            z = np.zeros((n, m))
            st = self._st = {
                "y0": y.copy(),
                "v0": y[:, self.i_valve].copy(),
                "yf": y.copy(),
                "ii": z,
                "ie": z.copy(),
                "fpd": z.copy(),
                "e1": z.copy(),
                "u": z.copy(),
            }
        restart = restart_rows(fresh, n, episode_start)
        if restart.any():
            self._restart(st, restart, y)
        yf = st["yf"]
        input_filter(yf, y, self.a_filter, restart)
        load = y[:, self.i_load]
        e = self._errors(st, yf, load, n)
        w = tsk_weights(load)  # (n, n_rules)
        v = st["v0"].copy()
        if self.conventional:  # e.g. a reheat damper: cascade_pi's loop
            a_pi, _ = self.pi.predict(obs, episode_start=restart)
            v[:, self.conventional] = 0.5 * (a_pi[:, self.conventional].astype(float) + 1.0)
        self.inner_setpoint = np.full((n, m), np.nan)
        dt = self.dt
        for j in self.fuzzy:
            inner, outer = self.loops[j]
            _, _, kc_i, ti_i = self.pi.gains[j]
            kp, ki, kd = (w @ self.gains[j]).T  # TSK-scheduled gains per row
            t0, ej = self.t0[j], e[:, j]
            e1 = np.where(np.isnan(st["e1"][:, j]), ej, st["e1"][:, j])
            rate = (ej - e1) / dt
            lim = E0_K * t0 / np.maximum(kp, 1e-9)  # integral input held at saturation
            st["ie"][:, j] = np.clip(st["ie"][:, j] + ej * dt, -lim, lim)
            f_pi = evaluate_surface(self.f, ki * ej / E0_K, kp * t0 * rate / E0_K)
            f_pd = evaluate_surface(self.f, kd * ej / E0_K, kp * st["ie"][:, j] / (E0_K * t0))
            d_pd = np.where(restart, 0.0, f_pd - st["fpd"][:, j])
            st["fpd"][:, j], st["e1"][:, j] = f_pd, ej
            du_i = self.u0[j] * dt / t0 * f_pi  # FPI output, integrated (increment)
            u_d = self.u0[j] * t0 / dt * d_pd  # FPD output, differentiated (position)
            if outer not in (None, SCHEDULED):  # P²ID sets the inner setpoint; inner PI
                r = st["u"][:, j] + du_i + u_d
                self.inner_setpoint[:, j] = r
                e_i = r - yf[:, inner]
                v[:, j], sat = pi_position(st["v0"][:, j], kc_i, e_i, st["ii"][:, j], dt, ti_i)
                # anti-windup: drop the FPI increment that pushes further into saturation
                windup = sat & (np.sign(kc_i * du_i) == np.sign(kc_i * e_i))
                st["u"][:, j] += np.where(windup, 0.0, du_i)
            else:  # P²ID moves the valve; the integrated FPI part is kept inside [0, 1]
                st["u"][:, j] = np.clip(st["u"][:, j] + du_i, -u_d, 1.0 - u_d)
                v[:, j] = st["u"][:, j] + u_d
        action = (2.0 * np.clip(v, 0.0, 1.0) - 1.0).astype(np.float32)
        return (action[0] if np.ndim(observation) == 1 else action), None
