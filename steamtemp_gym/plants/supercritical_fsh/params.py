"""Parameters of the supercritical final superheater, with their sources (Sagara et al.
1998; see the package docstring)."""

from __future__ import annotations

from dataclasses import dataclass

from steamtemp_gym.plants.param_ranges import ranged, validate_params

P_CRIT_PA = 22.064e6  # critical pressure of water (IAPWS-IF97)


@dataclass(frozen=True)
class FSHParams:
    """Parameters of the supercritical FSH (units in the names; sources in the module doc)."""

    # divisions along the tube (Sagara et al. 1998 uses n = 3 in its observer)
    n_segments: int = ranged(8, 1, 40)
    W_nom_kg_s: float = 2270e3 / 3600.0  # rated main-steam flow, 2270 t/h
    p_nom_MPa: float = ranged(24.8, 15.0, 31.0)  # FSH outlet pressure at rated load
    p_min_MPa: float = ranged(8.0, 1.0, 31.0)  # sliding-pressure floor
    slide_high_load: float = 0.9  # constant pressure above this load
    slide_low_load: float = 0.3  # p_min at and below this load
    T_out_C: float = ranged(593.0, 450.0, 650.0)  # outlet temperature setpoint
    dh_fsh_nom_kJ_kg: float = 217.8  # h_a0 - h_e0 at rated load (Sagara et al. 1998)
    n_tubes: int = 480
    tube_length_m: float = 50.0
    tube_id_m: float = 0.036
    tube_od_m: float = 0.0508
    rho_metal_kg_m3: float = 7800.0  # steel (IDAES)
    c_metal_J_kgK: float = 550.0  # alloy steel near 550 C
    alpha_nom_W_m2K: float = 3500.0  # effective steam-side coefficient incl. half the wall
    Tg_nom_C: float = 1000.0  # flue gas at the FSH, rated firing
    dTg_dload_K: float = ranged(300.0, 0.0, 800.0)  # gas temperature drop per unit firing reduction
    gas_flow_exponent: float = 0.6  # convective UA_g ~ gas flow^0.6
    # steady spray / main-steam flow the FWR schedule aims at
    spray_design_fraction: float = ranged(0.04, 0.0, 0.2)
    # spray / main-steam flow with the valve fully open
    spray_max_fraction: float = ranged(0.12, 0.01, 0.3)
    dp_boiler_nom_MPa: float = 4.0  # feed-pump discharge minus FSH pressure at rated flow
    T_fw_nom_C: float = ranged(290.0, 100.0, 350.0)  # feedwater after the HP heaters at rated load
    # feedwater temperature drop per unit load reduction
    dT_fw_dload_K: float = ranged(70.0, 0.0, 200.0)
    # coal mill: grinding and pulverized-coal inventory lag
    tau_mill_s: float = ranged(60.0, 1.0, 600.0)
    # furnace and waterwall heat release behind the mills
    tau_firing_s: float = ranged(90.0, 1.0, 900.0)
    # boiler-input-rate feed-forward lead (imperfect: < the lags)
    T_bir_s: float = ranged(30.0, 0.0, 600.0)
    tau_steam_s: float = 20.0  # steam-flow response to load demand
    tau_upstream_s: float = 120.0  # upstream superheaters' thermal lag
    # share of a firing/flow ratio error reaching the FSH inlet
    fwr_coupling: float = ranged(0.3, 0.0, 1.0)
    # FWR schedule error: relative enthalpy-rise error at 50 % load
    fwr_mismatch: float = ranged(0.008, -0.05, 0.05)
    # share of a heat-absorption bias reaching h_up
    bias_upstream_share: float = ranged(0.3, 0.0, 1.0)
    n_line: int = ranged(3, 1, 8)  # mixing cells of the outlet header and main-steam line
    line_volume_m3: float = ranged(20.0, 0.1, 200.0)  # their steam volume
    line_metal_t: float = ranged(55.0, 0.1, 500.0)  # their effective metal at steam temperature
    # protection: attemperator outlet >= Tsat + margin
    attemp_margin_K: float = ranged(12.0, 1.0, 50.0)
    tau_valve_s: float = 2.0
    valve_rate_per_s: float = 0.1  # full stroke in 10 s
    tau_tc1_s: float = 5.0  # thermocouple
    tau_tc2_s: float = 20.0  # thermowell
    dt_s: float = 2.0  # control interval
    n_substeps: int = 2  # ROS2 steps per control interval (1 step: 0.074 K error on the ramp)

    def __post_init__(self) -> None:
        validate_params(
            self,
            positive=tuple(
                n
                for n in self.__dataclass_fields__
                if n
                not in (
                    "dTg_dload_K",
                    "dT_fw_dload_K",
                    "T_bir_s",
                    "fwr_coupling",
                    "fwr_mismatch",
                    "bias_upstream_share",
                )
            ),
        )
        if self.tube_od_m <= self.tube_id_m:
            raise ValueError("FSHParams.tube_od_m must exceed tube_id_m")
        if self.p_min_MPa > self.p_nom_MPa:
            raise ValueError("FSHParams.p_min_MPa must not exceed p_nom_MPa")
        if not self.slide_low_load < self.slide_high_load:
            raise ValueError("FSHParams.slide_low_load must be below slide_high_load")
        if self.spray_design_fraction >= self.spray_max_fraction:
            raise ValueError("FSHParams.spray_design_fraction must be below spray_max_fraction")
        if self.Tg_nom_C - self.dTg_dload_K * 0.8 <= self.T_out_C:
            raise ValueError(
                "FSHParams: gas temperature at 20 % firing must exceed the steam outlet"
            )
