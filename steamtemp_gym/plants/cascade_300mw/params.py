"""Parameters of the 300 MW cascade plant, with their sources (Zhang et al. 2012; see the
package docstring)."""

from __future__ import annotations

from dataclasses import dataclass

from steamtemp_gym.plants.param_ranges import ranged, validate_params

PLANT_ID = "steamtemp/Cascade300MW-v0"
LOAD_MIN, LOAD_MAX = 0.2, 1.2  # the load range of the section models (fraction)


@dataclass(frozen=True)
class CascadeParams:
    """Parameters of the 300 MW cascade plant (units in the names; sources in the module doc)."""

    lead_gain_K_s_kg: float = 2.01  # |K2| at 100 % load, K per kg/s (sign: spray cools)
    lead_time_s: float = 16.0  # T2 at 100 % load
    lead_order: int = ranged(2, 1, 6)
    inertia_gain: float = 2.09  # K1 at 100 % load, K per K
    inertia_time_s: float = 22.3  # T1 at 100 % load
    inertia_order: int = ranged(4, 1, 6)
    load_dependent: bool = True  # gains and time constants vary with load (table in module doc)
    load_gain_exponent_lead: float = ranged(1.0, 0.0, 3.0)  # K2 ~ L^-a (attemperator balance ~ 1/W)
    load_gain_exponent_inertia: float = ranged(0.0, 0.0, 3.0)  # K1 ~ L^-a
    # T1, T2 ~ L^-a (~1/load, IDAES 320 MW geometry; unverified)
    load_time_exponent: float = ranged(1.0, 0.0, 3.0)
    # outlet operating point and setpoint (paper, Section 5)
    T_out_C: float = ranged(535.0, 450.0, 650.0)
    # outlet minus intermediate temperature at rated load (unverified)
    ht_rise_K: float = ranged(65.0, 1.0, 200.0)
    spray_max_kg_s: float = 9.0  # spray flow with the valve fully open (unverified)
    spray_rated_kg_s: float = 4.5  # spray holding T_out at 100 % load (unverified)
    # spray holding T_out at 50 % load (unverified)
    spray_half_load_kg_s: float = ranged(2.0, 0.0, 1000.0)
    # secondary attemperator, 300 MW drum unit (unverified)
    attemp_pressure_MPa: float = ranged(17.5, 5.0, 22.0)
    # feed-pump discharge (units: 170-290 C; unverified)
    spray_water_temp_C: float = ranged(175.0, 100.0, 300.0)
    omega_halfwidth_K: float = ranged(3.0, 0.0, 50.0)  # outer disturbance omega, marginal U(-a, a)
    omega_corr_time_s: float = ranged(150.0, 0.0, 3600.0)  # correlation time of omega (0: white)
    omega2_scale_kg_s: float = ranged(0.8, 0.0, 10.0)  # inner disturbance omega_2 ~ b (Exp(1) - 1)
    dt_s: float = ranged(1.0, 0.01, 60.0)  # sampling period T_s (paper, Section 5)
    n_substeps: int = ranged(1, 1, 1)  # the discretization is exact: one step per interval

    def __post_init__(self) -> None:
        validate_params(
            self,
            positive=(
                "lead_gain_K_s_kg",
                "lead_time_s",
                "inertia_gain",
                "inertia_time_s",
                "ht_rise_K",
                "spray_max_kg_s",
                "spray_rated_kg_s",
                "attemp_pressure_MPa",
                "spray_water_temp_C",
                "dt_s",
            ),
        )
        for name in ("spray_rated_kg_s", "spray_half_load_kg_s"):
            if not getattr(self, name) < self.spray_max_kg_s:
                raise ValueError(f"CascadeParams.{name} must be below spray_max_kg_s")
        if self.T_out_C - self.ht_rise_K <= self.spray_water_temp_C:
            raise ValueError(
                "CascadeParams.ht_rise_K puts the intermediate steam below the spray water"
            )

    def section_model(self, load: float) -> tuple[float, float, float, float]:
        """(K2 in K s/kg (negative), T2 s, K1, T1 s) at a load fraction (module-doc table)."""
        L = min(max(float(load), LOAD_MIN), LOAD_MAX) if self.load_dependent else 1.0
        return (
            -self.lead_gain_K_s_kg * L**-self.load_gain_exponent_lead,
            self.lead_time_s * L**-self.load_time_exponent,
            self.inertia_gain * L**-self.load_gain_exponent_inertia,
            self.inertia_time_s * L**-self.load_time_exponent,
        )
