"""What every plant provides to the generic env (the plant side of docs/architecture.md).

A plant is pure physics: a frozen parameter dataclass, a packed parameter
vector ``P`` for the kernels, and a compiled batched step
``step(X, U, D, dt)`` over arrays shaped (batch, n_states) that also fills the
plant's physical outputs Z (batch, n_outputs). The disturbance vector D holds
the common scenario vocabulary (:data:`DIST`); each plant maps it onto its own
inputs. U holds actuator commands in [0, 1] (the env maps actions in [-1, 1]).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from steamtemp_gym._jit import read_only
from steamtemp_gym.checks import key_list
from steamtemp_gym.plants.integrator import make_batched_step
from steamtemp_gym.plants.threads import run_rows
from steamtemp_gym.plants.valve import valve_rhs

#: Disturbance vector entries handed to every plant kernel, in order.
DIST: tuple[str, ...] = (
    "load",  # load demand, fraction of rated
    "load_rate_per_s",  # slope of the load demand schedule (1/s)
    "heat_absorption_bias",  # relative heat-absorption error
    "fouling",  # gas-side heat-transfer multiplier
    "spray_water_temp_offset_C",  # K
)
N_DIST = len(DIST)
#: Index of each disturbance channel in a kernel's ``d`` (and column of the env's ``D``).
D_LOAD, D_LOAD_RATE, D_HEAT_BIAS, D_FOULING, D_SPRAY_T = range(N_DIST)
#: ``outer`` entry of Plant.control_loops meaning the main-steam temperature against its setpoint.
MAIN = "main"
#: ``outer`` entry of Plant.control_loops meaning: hold the inner temperature at a setpoint
#: scheduled on load (a function generator set at commissioning from the plant's steady
#: states, as first-stage sprays are run), not at the main-steam error.
SCHEDULED = "scheduled"
#: Default trip band (below, above) the setpoint, K. Above: rated + 28 K is the excursion
#: a steam turbine may never exceed (IEC 60045-1, "Steam turbines - Part 1: Specifications",
#: main-steam temperature limits: +8 K continuous, +14 K for 400 h/yr, +28 K for 80 h/yr in
#: swings of at most 15 min); below: -50 K, the low-main-steam-temperature protection of
#: turbines against loss of superheat (plausible default, unverified).
TRIP_BAND_K = (50.0, 28.0)
#: Positions of X, U, D and Z (a row per batch entry) among :meth:`Plant.step_args`.
STEP_ROWS = (0, 1, 2, 8)
#: 0 C in kelvin.
K0 = 273.15


@dataclass(frozen=True)
class Signal:
    """A named physical signal with its unit and the scaling used for observations.

    ``(value - center) / scale`` is about [-1, 1] in normal operation.
    """

    name: str
    unit: str
    center: float
    scale: float
    observed: bool = True
    noisy: bool = False
    description: str = ""


def design_spray_signal(center: float, scale: float, description: str) -> Signal:
    """The hidden output ``design_spray_kg_s`` of a plant with a design spray
    (``Plant.design_spray``): the spray its design schedule passes at this load."""
    return Signal(
        "design_spray_kg_s", "kg/s", center, scale, observed=False, description=description
    )


#: The hidden coal-mill output of a plant with a mill lag (fraction of rated fuel).
MILL_OUTPUT = Signal("mill_output", "1", 0.75, 0.3, observed=False, description="coal to burners")


def nominal_disturbances(load: float) -> np.ndarray:
    """(1, N_DIST) disturbances of the undisturbed plant at ``load``: no load rate, no
    heat-absorption bias, clean (fouling 1), spray water at its design temperature."""
    d = np.zeros((1, N_DIST))
    d[0, D_LOAD], d[0, D_FOULING] = load, 1.0
    return d


class Plant:
    """Base class of the plants; subclasses fill the class attributes and the kernels.

    Attributes:
        id: Gymnasium id, e.g. ``steamtemp/SupercriticalFSH-v0``.
        source: The reference document the plant implements.
        Params: Frozen dataclass of physical parameters (with units and sources).
        actions: The actuator command signals (valves, dampers), in order.
        outputs: The physical outputs Z, in order; observed ones form the observation.
        setpoint_C: Nominal main-steam temperature setpoint.
        outlet: Name of the true main-steam temperature output.
        outlet_measured: Name of the measured main-steam temperature output.
        valves: Names of the valve-opening outputs. sprays: names of the spray-flow outputs.
        control_loops: Per action, the conventional loop that moves it, as (inner, outer)
            measured signals: inner is the fast temperature the actuator acts on (e.g. the
            attemperator outlet) or None, outer is MAIN (the main-steam error against the
            setpoint), another signal held at its value at the episode start, or None (the
            inner signal is held at its start value). Used by baselines/cascade_pi.py.
        secondary: Other controlled temperatures scored by the reward, as (true output name,
            setpoint in C), e.g. the reheat steam temperature.
        design_spray: Name of the output (kg/s) giving the total spray flow the plant's
            schedules are designed for at the current operating point (what the undisturbed
            plant needs in steady state at that load). The reward charges spray above it.
        trip_band_K: (below, above) setpoint at which the unit trips (episode terminates);
            :data:`TRIP_BAND_K` by default.
    """

    id: ClassVar[str]
    source: ClassVar[str]
    Params: ClassVar[type]
    actions: ClassVar[tuple[Signal, ...]]
    outputs: ClassVar[tuple[Signal, ...]]
    setpoint_C: ClassVar[float]
    outlet: ClassVar[str] = "outlet_temp_C"
    outlet_measured: ClassVar[str] = "outlet_temp_meas_C"
    valves: ClassVar[tuple[str, ...]] = ("spray_valve",)
    sprays: ClassVar[tuple[str, ...]] = ("spray_flow_kg_s",)
    control_loops: ClassVar[tuple[tuple[str | None, str | None], ...]] = (
        ("attemp_out_temp_meas_C", MAIN),
    )
    secondary: ClassVar[tuple[tuple[str, float], ...]] = ()
    #: The plant's own named scenarios, name -> Scenario (``steamtemp_gym.scenarios.declare``).
    scenarios: ClassVar[Mapping[str, Any]] = {}
    extra_info: ClassVar[tuple[str, ...]] = ()
    design_spray: ClassVar[str | None] = None
    #: Parameter groups of ``plant_randomization`` and the mismatch set: group (a name of
    #: ``perturb.RANGES``) -> the ``Params`` fields its factor scales (plants/perturb.py).
    perturbation_groups: ClassVar[Mapping[str, tuple[str, ...]]] = {}
    #: The named model-mismatch variants: variant -> {group: factor} (plants/perturb.py).
    mismatch_variants: ClassVar[Mapping[str, Mapping[str, float]]] = {}
    #: The boiler's circulation, "once_through" or "drum" (None: a model without the
    #: steam-water circuit, e.g. transfer functions); agents/difficulty.py sets its
    #: cascade-PI ramp targets by it.
    circulation: ClassVar[str | None] = None
    #: What the baselines' commissioning rules take from this plant: rule -> values, each
    #: documented by the rule (``mpc_linear``: ``move_weight``; ``lqi``: knob values;
    #: ``neuro_pid``: ``disturbance_signals``, ``inner_p_pct_per_K``; ``fao``: ``observer``,
    #: "divisions" where the FAO paper's own observer model applies). A rule without an
    #: entry commissions the plant by its own defaults.
    commissioning: ClassVar[Mapping[str, Mapping[str, Any]]] = {}
    trip_band_K: ClassVar[tuple[float, float]] = TRIP_BAND_K
    default_duration_s: ClassVar[float] = 3600.0
    #: Params field holding the main-steam setpoint (C); overrides ``setpoint_C``.
    setpoint_param: ClassVar[str | None] = None
    #: Compiled (rhs, outputs, project) for the shared ROS2 kernel (plants/integrator.py);
    #: a plant with its own kernel overrides :meth:`kernel` instead.
    kernels: ClassVar[tuple[Callable, Callable, Callable] | None] = None
    #: (valve state index, P index of its time constant, P index of its rate limit) for
    #: the first actions; integrated exactly by the shared kernel (plants/integrator.py).
    actuators: ClassVar[tuple[tuple[int, int, int], ...]] = ()
    #: Compiled steady-state solver ``steady(D, setpoint_K, P, X)`` (setpoints in kelvin)
    #: that :meth:`steady_state` calls; a plant whose solver takes other arguments
    #: overrides :meth:`steady_state` instead.
    steady: ClassVar[Callable | None] = None
    _compiled: ClassVar[dict[type, Callable]] = {}

    def __init__(self, **overrides: Any) -> None:
        valid = {f.name for f in dataclasses.fields(self.Params)}
        unknown = key_list(set(overrides) - valid)
        if unknown:
            raise ValueError(
                f"unknown parameter(s) {unknown} for {self.id}; valid parameters: {sorted(valid)}"
            )
        self.params = self.Params(**overrides)
        self.P, self.jrow, self.jcol, self.n_x = self.pack(self.params)
        self.dt_s = float(self.params.dt_s)
        self.n_sub = int(self.params.n_substeps)
        self.n_u = len(self.actions)
        self.n_z = len(self.outputs)
        self.index = {s.name: i for i, s in enumerate(self.outputs)}
        if self.setpoint_param:
            self.setpoint_C = float(getattr(self.params, self.setpoint_param))

    @property
    def rate_limits(self) -> tuple[float, ...]:
        """Each action's valve rate limit (fraction of full stroke per second), ``inf`` for
        an action without valve dynamics in the plant (:attr:`actuators`)."""
        rates = [float(self.P[ir]) for _, _, ir in self.actuators[: self.n_u]]
        return tuple(rates + [float("inf")] * (self.n_u - len(rates)))

    @classmethod
    def skeleton(cls) -> Plant:
        """An instance with the default parameters whose kernel arrays (P, jrow, jcol) are
        placeholders of the right types: nothing is calibrated or compiled.

        For reading a plant's layout without its numbers (steamtemp_gym/docs.py); its
        kernels must never run on its arrays.
        """
        plant = cls.__new__(cls)
        empty = np.zeros(0, dtype=np.int64)
        plant.pack = lambda params: (read_only(np.zeros(1)), empty, empty, 1)
        plant.__init__()
        return plant

    # -- to be provided by subclasses ---------------------------------------------
    @staticmethod
    def pack(params: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
        """(P, jrow, jcol, n_states) for the kernels."""
        raise NotImplementedError

    def kernel(self) -> Callable:
        """The compiled batched step ``step(X, U, D, P, jrow, jcol, dt, n_sub, Z)``.

        Built from :attr:`kernels` by the shared ROS2 integrator (one cached kernel per
        class, plants/specialize.py).
        """
        cls = type(self)
        step = Plant._compiled.get(cls)
        if step is None:
            step = Plant._compiled[cls] = make_batched_step(
                cls.__name__, *cls.kernels, cls.actuators or None
            )
        return step

    def steady_state(self, D: np.ndarray, setpoint_C: np.ndarray, X: np.ndarray) -> None:
        """Write into X the steady state at the disturbances D holding ``setpoint_C``."""
        if self.steady is None:
            raise NotImplementedError
        self.steady(D, setpoint_C + K0, self.P, X)

    def seed_rows(self, X: np.ndarray, keys: np.ndarray) -> None:
        """Seed the plant's own random disturbances of rows X from the episodes' keys (uint64).

        Called by the env right before :meth:`steady_state` (so that the steady state can
        include the disturbances' initial values); a no-op for plants without internal
        random inputs (use steamtemp_gym.rng in the kernel).
        """

    # -- generic ---------------------------------------------------------------------
    def continuous_rhs(self, x: np.ndarray, u: np.ndarray, d: np.ndarray) -> np.ndarray:
        """dx/dt of the continuous model at commands u (openings in [0, 1]).

        The kernels' ``rhs`` receives the actuators' chord velocities instead of their
        commands (plants/integrator.py); this maps commands through the valve ODE of
        plants/valve.py first. For tests, linearization and reference solutions.
        """
        P = self.P
        uc = np.array(u, dtype=np.float64)
        for j, (iv, it, ir) in enumerate(self.actuators):
            uc[j] = valve_rhs(x[iv], u[j], P[it], P[ir])[0]
        n = self.n_x
        f, jd, ju, jl = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(max(len(self.jrow), 1))
        self.kernels[0](x, uc, d, P, f, jd, ju, jl, False)
        return f

    def step(
        self, X: np.ndarray, U: np.ndarray, D: np.ndarray, Z: np.ndarray, dt: float | None = None
    ) -> None:
        """Advance X by ``dt`` (default: one control interval) with commands U; fill Z.

        ``dt = 0`` only evaluates the outputs of the current state.
        """
        run_rows(self.kernel(), self.step_args(X, U, D, Z, dt), per_row=STEP_ROWS)

    def step_args(
        self, X: np.ndarray, U: np.ndarray, D: np.ndarray, Z: np.ndarray, dt: float | None = None
    ) -> tuple:
        """The arguments of :meth:`kernel` for :meth:`step` (callers that step the same
        arrays again and again may build them once)."""
        dt = self.dt_s if dt is None else dt
        return (X, U, D, self.P, self.jrow, self.jcol, dt, self.n_sub, Z)

    def steady_outputs(
        self, d: np.ndarray, setpoint_C: float | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """(x, z): the steady state at disturbances ``d`` (:data:`DIST` order) holding
        ``setpoint_C`` (default: the plant's setpoint), with the plant's own random inputs
        seeded by key 0, and its outputs (a zero-length step)."""
        D = np.asarray(d, dtype=np.float64).reshape(1, N_DIST)
        sp = np.array([self.setpoint_C if setpoint_C is None else setpoint_C], dtype=np.float64)
        X, Z = np.zeros((1, self.n_x)), np.zeros((1, self.n_z))
        self.seed_rows(X, np.zeros(1, dtype=np.uint64))
        self.steady_state(D, sp, X)
        self.step(X.copy(), np.zeros((1, self.n_u)), D, Z, dt=0.0)
        return X[0], Z[0]

    def linearize(
        self,
        load: float,
        *,
        setpoint_C: float | None = None,
        rel_step: float = 1e-6,
        du: float = 1e-4,
        outputs: Sequence[str] | None = None,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Discrete-time linear model (A, B, C, D) at the control interval around the
        steady state at ``load``.

        The operating point is the plant's own steady state (:meth:`seed_rows` with key 0,
        then :meth:`steady_state`) at the nominal disturbances (``load``, no load rate,
        heat-absorption bias 0, fouling 1, spray-water offset 0) holding ``setpoint_C``
        (default: the plant's setpoint); the commands u0 are the steady valve openings (the
        outputs :attr:`valves`, as the env sets them at a reset). In deviations from it::

            x_{k+1} = A x_k + B u_k,    y_k = C x_k + D u_k

        x: the plant's full state vector (its own units: SI enthalpies, pressures, ...);
        u: the actions as valve openings in [0, 1] (action a gives opening (a + 1) / 2);
        y: the OBSERVED outputs (``Signal.observed``, in :attr:`outputs` order), or the
        outputs named in ``outputs``, in their physical units (C, kg/s, MPa, ...). A and B
        are central finite differences of one control interval of the compiled step
        (:meth:`step`, the kernel the env runs), C and D of its output evaluation
        (``dt = 0``): x_i is perturbed by ``rel_step`` max(|x_i|, 1), u_j by ``du``
        (one-sided, inward, at a closed valve or a fully open one). The env's observation
        after a step is the outputs of the new state with the command just held, so
        y_{k+1} = C x_{k+1} + D u_k there (D is zero for plants whose outputs read the valve
        states only). Plant-internal random disturbances (seeded by key 0) are the same in
        every evaluation and cancel in the differences; their generator states appear as
        uncontrollable modes. The disturbances' columns are :meth:`linearize_disturbances`.

        Generic: no per-plant code. Checked against the env's finite-difference step
        responses for every id in tests/test_linearize.py.
        """
        x0, u0, d, run = self._linear_point(load, setpoint_C, outputs)
        n, m, p = self.n_x, self.n_u, len(run(x0, u0, d, 0.0)[1])
        A, B = np.zeros((n, n)), np.zeros((n, m))
        C, D = np.zeros((p, n)), np.zeros((p, m))
        for i in range(n):
            h = rel_step * max(abs(float(x0[0, i])), 1.0)
            A[:, i], C[:, i] = _central_difference(run, (x0, u0, d), 0, i, h)
        for j in range(m):
            lo, hi = max(u0[0, j] - du, 0.0), min(u0[0, j] + du, 1.0)
            up, um = u0.copy(), u0.copy()
            up[0, j], um[0, j] = hi, lo
            B[:, j] = (run(x0, up, d, None)[0] - run(x0, um, d, None)[0]) / (hi - lo)
            D[:, j] = (run(x0, up, d, 0.0)[1] - run(x0, um, d, 0.0)[1]) / (hi - lo)
        return A, B, C, D

    def linearize_disturbances(
        self,
        load: float,
        channels: Sequence[str] = DIST,
        *,
        setpoint_C: float | None = None,
        rel_step: float = 1e-6,
        outputs: Sequence[str] | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """The disturbance columns (Bd, Dd) of :meth:`linearize`'s model at ``load``::

            x_{k+1} = A x_k + B u_k + Bd w_k,    y_k = C x_k + D u_k + Dd w_k

        w: the deviations of the disturbance ``channels`` (names of :data:`DIST`, in the
        given order; e.g. ``heat_absorption_bias``, ``load``) from their nominal values at
        the same operating point, held over the control interval as the env holds them.
        Central finite differences of the same compiled step, channel i perturbed by
        ``rel_step`` max(|w_i|, 1); ``outputs`` as for :meth:`linearize`.

        Raises:
            ValueError: On a channel name not in :data:`DIST`.
        """
        unknown = [c for c in channels if c not in DIST]
        if unknown:
            raise ValueError(f"unknown disturbance channel(s) {unknown}; valid: {list(DIST)}")
        x0, u0, d0, run = self._linear_point(load, setpoint_C, outputs)
        p = len(run(x0, u0, d0, 0.0)[1])
        Bd, Dd = np.zeros((self.n_x, len(channels))), np.zeros((p, len(channels)))
        for j, name in enumerate(channels):
            c = DIST.index(name)
            h = rel_step * max(abs(float(d0[0, c])), 1.0)
            Bd[:, j], Dd[:, j] = _central_difference(run, (x0, u0, d0), 2, c, h)
        return Bd, Dd

    def _linear_point(
        self, load: float, setpoint_C: float | None, outputs: Sequence[str] | None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, Callable]:
        """(x0, u0, d0, run) of the linearizations: the operating point (rows of one) and
        ``run(x, u, d, dt) -> (x after dt, the selected outputs)``."""
        if outputs is None:
            rows = np.array([i for i, s in enumerate(self.outputs) if s.observed])
        else:
            unknown = [o for o in outputs if o not in self.index]
            if unknown:
                raise ValueError(
                    f"unknown output(s) {unknown} of {self.id}; valid: {list(self.index)}"
                )
            rows = np.array([self.index[o] for o in outputs], dtype=np.int64)
        d0 = nominal_disturbances(load)
        x, z = self.steady_outputs(d0[0], setpoint_C)
        u0 = z[[self.index[v] for v in self.valves]].reshape(1, self.n_u)

        def run(
            x: np.ndarray, u: np.ndarray, d: np.ndarray, dt: float | None
        ) -> tuple[np.ndarray, np.ndarray]:
            X, Z = x.copy(), np.zeros((1, self.n_z))
            self.step(X, u, d, Z, dt=dt)
            return X[0], Z[0, rows]

        return x[None, :], u0, d0, run


def _central_difference(
    run: Callable, point: tuple[np.ndarray, ...], which: int, i: int, h: float
) -> tuple[np.ndarray, np.ndarray]:
    """Derivatives of the next state and of the outputs of ``run`` (a one-row step, as
    :meth:`Plant._linear_point` makes it) in entry i of point[which] (x, u or d), by central
    differences of step h."""
    hi, lo = [a.copy() for a in point], [a.copy() for a in point]
    hi[which][0, i] += h
    lo[which][0, i] -= h
    return (
        (run(*hi, None)[0] - run(*lo, None)[0]) / (2.0 * h),
        (run(*hi, 0.0)[1] - run(*lo, 0.0)[1]) / (2.0 * h),
    )
