"""The plant class of ``steamtemp/Cascade300MW-v0``."""

from __future__ import annotations

import numpy as np

from steamtemp_gym.plants.base import (
    MAIN,
    Plant,
    Signal,
)
from steamtemp_gym.plants.cascade_300mw.discretization import pack_params
from steamtemp_gym.plants.cascade_300mw.kernel import SEED_SALT, steady, step
from steamtemp_gym.plants.cascade_300mw.layout import IX, OUTPUTS
from steamtemp_gym.plants.cascade_300mw.params import (
    PLANT_ID,
    CascadeParams,
)
from steamtemp_gym.plants.cascade_300mw.scenarios import SCENARIOS
from steamtemp_gym.rng import splitmix64


class Cascade300MW(Plant):
    """Plant of ``steamtemp/Cascade300MW-v0`` (Zhang et al. 2012)."""

    id = PLANT_ID
    source = "Zhang et al., ISA Transactions 51, 2012"
    Params = CascadeParams
    actions = (
        Signal("spray_valve_cmd", "1", 0.5, 0.5, description="secondary spray valve command"),
    )
    outputs = OUTPUTS
    setpoint_C = 535.0
    control_loops = (("intermediate_temp_C", MAIN),)
    design_spray = "design_spray_kg_s"
    perturbation_groups = {
        "section_gains": ("lead_gain_K_s_kg", "inertia_gain"),
        "section_time_constants": ("lead_time_s", "inertia_time_s"),
    }
    #: The corners of the two groups' ranges.
    mismatch_variants = {
        "high_gain_slow": {"section_gains": 1.3, "section_time_constants": 1.3},
        "high_gain_fast": {"section_gains": 1.3, "section_time_constants": 0.7},
        "low_gain_slow": {"section_gains": 0.7, "section_time_constants": 1.3},
        "low_gain_fast": {"section_gains": 0.7, "section_time_constants": 0.7},
    }
    commissioning = {
        "mpc_linear": {"move_weight": 0.001},
        # LQI's valve travel 3.7x cascade_pi_ff's at its default e_max_K = 1 K, within 3x at 2
        "lqi": {"e_max_K": 2.0},
        # the paper's omega and omega_2, and its secondary P controller G_C2 = 8 %/K
        "neuro_pid": {"disturbance_signals": ("omega_K", "omega2_kg_s"), "inner_p_pct_per_K": 8.0},
    }
    extra_info = ("intermediate_temp_C", "omega_K", "omega2_kg_s", "outer_disturbance_K")
    default_duration_s = 3600.0
    scenarios = SCENARIOS

    pack = staticmethod(pack_params)
    setpoint_param = "T_out_C"

    def kernel(self):
        return step

    def steady_state(self, D: np.ndarray, setpoint_C: np.ndarray, X: np.ndarray) -> None:
        """Equilibrium holding the setpoint with the rows' step-0 omega values (the omega
        generators seeded by :meth:`seed_rows` before; seed 0 if never seeded)."""
        sp = np.asarray(setpoint_C, dtype=np.float64)
        steady(D, sp.copy(), self.P, X)

    def seed_rows(self, X: np.ndarray, keys: np.ndarray) -> None:
        """Seed the omega generators of rows X from the episodes' keys (uint64).

        The seed (kept in the float64 state, hence 52 bits) is the key mixed with a
        plant-specific salt, so omega is independent of the env's sensor noise. Called
        before :meth:`steady_state`, which draws the step-0 values.
        """
        for b in range(X.shape[0]):
            X[b, IX.SEED] = float(int(splitmix64(np.uint64(keys[b]) ^ SEED_SALT)) >> 12)
            X[b, IX.CNT] = 0.0
