"""Parameters of the boiler-turbine unit: the dataclass of every tunable value with its
validation. "The paper" is 002 (Toyoda and Wada; see the package docstring).

Rated point (stated, typical of 24.1 MPa / 538 / 566 C units; plausible defaults,
unverified): 2270 t/h main steam, 25.0 MPa / 538 C at the superheater outlet; cold reheat
4.3 MPa / 330 C, hot reheat 566 C at 88 % of main steam flow. Design temperatures are
evaporator outlet 410 C, SP1 outlet 440 C and SP2 outlet 498 C, with design sprays of
4 % (SP1) and 3 % (SP2). Feedwater 290 C. The gas-side conductances and the platen's
radiant heat are calibrated so that this rated balance holds. The evaporator-outlet
schedule h_up(L) is computed so that the design sprays hold 538 C at every load when RGD
holds 566 C (``_calibrate``).
"""

from __future__ import annotations

from dataclasses import dataclass

from steamtemp_gym.plants.param_ranges import ranged, validate_params


@dataclass(frozen=True)
class BoilerTurbineParams:
    """Parameters of the boiler-turbine unit (units in the names; sources in the module doc).

    The platen (secondary SH) values are effective lumped values fitted to Table 1 of
    Toyoda and Wada 1999; every other value is a plausible default, unverified.
    """

    # unit and operating program
    W_nom_kg_s: float = 2270e3 / 3600.0  # rated main-steam flow, 2270 t/h (Table 1)
    # superheater outlet at rated load (24.1 MPa throttle)
    p_nom_MPa: float = ranged(25.0, 15.0, 31.0)
    p_min_MPa: float = ranged(14.0, 1.0, 31.0)  # at slide_min_load and below
    slide_knee_load: float = ranged(0.9, 0.3, 1.2)  # constant pressure above this load
    slide_min_load: float = ranged(0.25, 0.1, 0.9)
    T_ms_C: float = ranged(538.0, 450.0, 650.0)  # main-steam (STE) setpoint
    T_rh_C: float = ranged(566.0, 450.0, 650.0)  # reheat (RTE) setpoint
    # reheater pressure at rated flow (~ proportional to flow)
    p_rh_nom_MPa: float = ranged(4.3, 1.0, 10.0)
    p_rh_min_MPa: float = ranged(0.6, 0.3, 5.0)
    # HP-turbine exhaust (cold reheat) at rated load
    T_crh_nom_C: float = ranged(330.0, 200.0, 450.0)
    # reheat / main-steam flow (HP-heater extraction)
    reheat_flow_fraction: float = ranged(0.88, 0.5, 1.0)
    # rated design temperatures and sprays
    T_up_design_C: float = 410.0  # evaporator/separator outlet = primary SH inlet
    T_sp1_out_design_C: float = 440.0  # platen inlet
    T_sp2_out_design_C: float = 498.0  # final SH inlet
    sp1_design_fraction: float = ranged(0.04, 0.0, 0.15)  # of main-steam flow
    sp2_design_fraction: float = ranged(0.03, 0.0, 0.15)
    # spray valves are sized to pass the design at this
    valve_design_opening: float = ranged(0.5, 0.1, 0.9)
    dp_boiler_nom_MPa: float = 4.0  # feed-pump discharge minus SH outlet, rated flow
    T_fw_nom_C: float = ranged(290.0, 100.0, 350.0)  # feedwater after the HP heaters, rated load
    # feedwater temperature drop per unit load reduction
    dT_fw_dload_K: float = ranged(70.0, 0.0, 200.0)
    # tube metal (all convective stages) and steam-side film, eq. (4)-(5)
    rho_metal_kg_m3: float = 7800.0
    c_metal_J_kgK: float = 600.0  # alloy steel near 500 C
    k_wall_W_mK: float = 25.0
    alpha_sh_W_m2K: float = 6000.0  # supercritical steam film at rated flow (Dittus-Boelter)
    alpha_rh_W_m2K: float = 1500.0  # reheat steam film at rated flow
    # primary SH (convective, rear pass)
    n_seg_primary: int = ranged(3, 1, 20)
    primary_n_tubes: int = 500
    primary_length_m: float = 70.0
    primary_id_m: float = 0.038
    primary_od_m: float = 0.048
    # secondary SH = platen: the eq. (1)-(6) section of Table 1 (effective lumped values)
    n_seg_platen: int = ranged(1, 1, 20)
    platen_volume_m3: float = 85.0
    platen_metal_MJ_K: float = 121.0  # M_m c_m
    platen_kA_film_MW_K: float = 4.4  # film UA at rated flow (scales as w^0.8)
    platen_kA_wall_MW_K: float = 2.75  # wall term of eq. (4), flow independent
    # final SH (convective, furnace exit)
    n_seg_final: int = ranged(3, 1, 20)
    final_n_tubes: int = 300
    final_length_m: float = 60.0
    final_id_m: float = 0.038
    final_od_m: float = 0.0508
    # reheater (convective, rear pass)
    n_seg_reheat: int = ranged(4, 1, 20)
    reheat_n_tubes: int = 450
    reheat_length_m: float = 80.0
    reheat_id_m: float = 0.050
    reheat_od_m: float = 0.057
    # gas side
    Tg_primary_C: float = 750.0  # gas at the primary SH, rated firing
    Tg_final_C: float = 1100.0  # furnace exit gas at the final SH
    Tg_reheat_C: float = 950.0  # gas at the reheater
    # SH gas temperature drop per unit firing reduction
    dTg_dload_K: float = ranged(250.0, 0.0, 600.0)
    dTg_reheat_dload_K: float = ranged(200.0, 0.0, 600.0)  # the same at the reheater (rear pass)
    gas_flow_exponent: float = 0.6  # convective UA_g ~ gas flow^0.6
    radiant_exponent: float = 0.85  # platen radiant heat ~ firing^0.85
    # recirculated / combustion gas with RGD fully open
    recirc_max_fraction: float = ranged(0.5, 0.0, 1.0)
    rgd_design_opening: float = ranged(0.25, 0.05, 0.95)  # RGD opening of the rated design balance
    # relative platen heat loss per unit recirculation
    platen_recirc_sensitivity: float = ranged(0.3, 0.0, 2.0)
    # existing controllers and lags
    # coal mills: grinding, pulverised-coal inventory, transport
    tau_mill_s: float = ranged(100.0, 1.0, 900.0)
    tau_firing_s: float = 15.0  # furnace heat release behind the mills
    T_bir_s: float = ranged(30.0, 0.0, 600.0)  # boiler-input-rate lead
    tau_steam_s: float = 20.0  # steam flow following MWD
    tau_upstream_s: float = 120.0  # evaporator outlet enthalpy lag
    fwr_coupling: float = ranged(0.3, 0.0, 1.0)  # share of a firing/flow ratio error reaching h_up
    # evaporator-outlet schedule error at half load
    fwr_schedule_error_kJ_kg: float = ranged(-30.0, -80.0, 80.0)
    # share of the heat-absorption bias on the evaporator
    bias_upstream_share: float = ranged(0.5, 0.0, 1.0)
    n_line: int = ranged(3, 1, 12)  # mixing cells of the SH outlet header + main-steam line
    # effective header/line/valve-chest metal (package doc)
    line_metal_t: float = ranged(100.0, 0.1, 500.0)
    line_volume_m3: float = ranged(20.0, 0.1, 300.0)  # steam volume of header and main-steam lines
    n_rh_line: int = ranged(2, 1, 12)  # mixing cells of the hot-reheat line
    rh_line_metal_t: float = ranged(30.0, 0.1, 500.0)  # effective hot-reheat header/line metal
    rh_line_volume_m3: float = ranged(60.0, 0.1, 500.0)  # steam volume of the hot-reheat lines
    tau_hp_s: float = 15.0  # HP turbine and cold-reheat line
    fuel_bias_action: bool = False  # FF bias as a fourth action
    fuel_bias_max: float = ranged(0.1, 0.0, 0.5)  # FF bias range, fraction of rated firing
    tau_fuel_bias_s: float = 1.0
    tau_valve_s: float = 2.0
    valve_rate_per_s: float = 0.1  # full stroke in 10 s
    tau_damper_s: float = 5.0
    damper_rate_per_s: float = 0.05  # full stroke in 20 s
    tau_tc1_s: float = 5.0  # thermocouple
    tau_tc2_s: float = 20.0  # thermowell
    dt_s: float = 2.0  # control interval
    n_substeps: int = 1  # ROS2 steps per control interval

    def __post_init__(self) -> None:
        signed = (
            "dT_fw_dload_K",
            "dTg_dload_K",
            "dTg_reheat_dload_K",
            "T_bir_s",
            "fwr_coupling",
            "platen_recirc_sensitivity",
            "fwr_schedule_error_kJ_kg",
            "bias_upstream_share",
        )
        validate_params(
            self,
            positive=tuple(
                n for n in self.__dataclass_fields__ if n not in signed and n != "fuel_bias_action"
            ),
        )
        name = type(self).__name__
        for stage in ("primary", "final", "reheat"):
            if getattr(self, f"{stage}_od_m") <= getattr(self, f"{stage}_id_m"):
                raise ValueError(f"{name}.{stage}_od_m must exceed {stage}_id_m")
        if self.p_min_MPa > self.p_nom_MPa:
            raise ValueError(f"{name}.p_min_MPa must not exceed p_nom_MPa")
        if not self.slide_min_load < self.slide_knee_load:
            raise ValueError(f"{name}.slide_min_load must be below slide_knee_load")
        if not (
            self.T_up_design_C < self.T_sp1_out_design_C < self.T_sp2_out_design_C < self.T_ms_C
        ):
            raise ValueError(
                f"{name}.T_up_design_C < T_sp1_out_design_C < T_sp2_out_design_C < T_ms_C "
                "must hold (the steam heats up along the path)"
            )
        if self.T_crh_nom_C >= self.T_rh_C:
            raise ValueError(f"{name}.T_crh_nom_C must be below T_rh_C")
        for g, dtg in (
            ("Tg_primary_C", self.dTg_dload_K),
            ("Tg_final_C", self.dTg_dload_K),
            ("Tg_reheat_C", self.dTg_reheat_dload_K),
        ):
            if getattr(self, g) - 0.8 * dtg <= self.T_ms_C - 100.0:
                raise ValueError(f"{name}.{g}: gas at 20 % firing must stay above the steam")
