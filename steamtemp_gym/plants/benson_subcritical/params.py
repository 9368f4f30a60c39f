"""Parameters of the Neka Benson boiler: the sections, pressure-drop shares and
the dataclass of every tunable value with its validation. "The paper" is 001 (Ghaffari,
Moosavian and Chaibakhsh; see the package docstring).

Parameter sources: 18.1 MPa, 535 C, 4.35 MPa, 530 C, 28 MPa, 80 K, 5 s, eta_th ranges,
440 MW: the paper. Rated flow 375 kg/s (1350 t/h): heat balance of a 440 MW reheat unit
at these steam conditions (~1020 MW to the steam), plausible default, unverified.
Section temperatures, metal masses, volumes, conductances, gas temperatures, pressure
drops, deaerator temperature, spray fractions, controller settings and the natural-gas
calorific value: plausible defaults, unverified (sized with the IDAES 320 MW and ClaRa
figures, docs/references.md). The gas-side conductances and radiant heats are
calibrated so that the rated steady state hits the design temperatures.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

from steamtemp_gym.plants.param_ranges import ranged, validate_params
from steamtemp_gym.slots import slots

#: Sections in flow order; index k of the per-section parameter block in P.
SECTIONS = ("eco", "evap", "sh1", "sh2", "sh3", "sh4", "rh")
#: Index of each section, in the order of SECTIONS.
SEC = slots("BensonSections", "ECO", "EV", "SH1", "SH2", "SH3", "SH4", "RH")
#: Outlet pressure of each water/steam section as a share of the boiler pressure drop
#: (economizer inlet = 1, main steam = 0) at rated flow (plausible default, unverified;
#: Benson evaporators with rifled tubes carry a large share). The reheater has its own.
P_SHARE = (0.85, 0.45, 0.32, 0.20, 0.08, 0.0, 0.0)


@dataclass(frozen=True)
class BensonParams:
    """Parameters of the Neka Benson boiler (units in the names; sources in the module doc)."""

    # --- rating (Ghaffari et al. section IV unless noted)
    W_nom_kg_s: float = 375.0  # main-steam flow at 440 MW (heat balance, unverified)
    p_nom_MPa: float = ranged(18.1, 10.0, 19.5)  # main steam pressure (paper)
    T_ms_C: float = ranged(535.0, 450.0, 600.0)  # main steam temperature (paper)
    p_rh_nom_MPa: float = ranged(4.35, 1.0, 8.0)  # hot reheat pressure (paper)
    T_rh_C: float = ranged(530.0, 450.0, 600.0)  # hot reheat temperature (paper)
    p_pump_MPa: float = ranged(28.0, 20.0, 35.0)  # feed-pump discharge (paper)
    dT_hp_heaters_K: float = ranged(80.0, 0.0, 150.0)  # feedwater rise in the HP heaters (paper)
    # feed-pump suction / spray water at rated load
    T_deaerator_C: float = ranged(170.0, 100.0, 200.0)
    # deaerator temperature drop per unit load drop
    dT_deaerator_dload_K: float = ranged(20.0, 0.0, 80.0)
    dT_hp_dload_K: float = ranged(40.0, 0.0, 100.0)  # HP-heater rise drop per unit load drop
    # --- pressure (eq. 13) and sliding pressure
    p_min_MPa: float = ranged(8.0, 3.0, 19.5)  # sliding-pressure floor at slide_low_load
    slide_low_load: float = ranged(0.3, 0.1, 0.9)
    dp_boiler_MPa: float = ranged(3.0, 0.1, 4.0)  # economizer inlet minus main steam at rated flow
    dp_reheater_MPa: float = ranged(0.3, 0.01, 1.0)  # cold minus hot reheat pressure at rated flow
    storage_tau: float = 4.0  # the paper's tau in eq. (13), dimensionless (see the package doc)
    # --- design temperatures at rated load (define the calibration)
    T_eco_out_C: float = 320.0
    T_evap_out_C: float = 410.0  # 48 K superheat at the evaporator outlet
    T_sh1_out_C: float = 450.0
    T_sh2_out_C: float = 495.0
    T_sh3_out_C: float = 515.0
    spray1_design_fraction: float = ranged(0.03, 0.0, 0.15)  # of main-steam flow
    spray2_design_fraction: float = ranged(0.02, 0.0, 0.15)
    spray1_max_fraction: float = ranged(0.06, 0.005, 0.3)  # valve fully open, rated pressures
    spray2_max_fraction: float = ranged(0.04, 0.005, 0.3)
    # --- sections: segments, metal mass (t), steam/water volume (m3),
    #     steam-side conductance at rated flow (MW/K), effective gas temperature (C)
    n_eco: int = ranged(1, 1, 12)
    n_evap: int = ranged(3, 1, 12)
    n_sh1: int = ranged(2, 1, 12)
    n_sh2: int = ranged(2, 1, 12)
    n_sh3: int = ranged(2, 1, 12)
    n_sh4: int = ranged(3, 1, 12)
    n_rh: int = ranged(2, 1, 12)
    metal_eco_t: float = 350.0
    metal_evap_t: float = 600.0
    metal_sh1_t: float = 160.0
    metal_sh2_t: float = 80.0
    metal_sh3_t: float = 90.0
    metal_sh4_t: float = 100.0
    metal_rh_t: float = 220.0
    volume_eco_m3: float = 70.0
    volume_evap_m3: float = 60.0
    volume_sh1_m3: float = 35.0
    volume_sh2_m3: float = 12.0
    volume_sh3_m3: float = 14.0
    volume_sh4_m3: float = 16.0
    volume_rh_m3: float = 90.0
    kA_eco_MW_K: float = 12.0
    kA_evap_MW_K: float = 40.0
    kA_sh1_MW_K: float = 6.0
    kA_sh2_MW_K: float = 5.0
    kA_sh3_MW_K: float = 5.0
    kA_sh4_MW_K: float = 5.5
    kA_rh_MW_K: float = 5.0
    Tg_eco_C: float = 600.0  # gas entering the economizer (see the package doc)
    Tg_sh1_C: float = 750.0
    Tg_sh3_C: float = 1200.0
    Tg_sh4_C: float = 1100.0
    Tg_rh_C: float = 950.0
    c_metal_J_kgK: float = 550.0
    gas_temp_coeff: float = ranged(0.2, 0.0, 0.6)  # T_g(K) = T_g,nom (1 - coeff (1 - firing))
    gas_flow_exponent: float = ranged(0.6, 0.0, 1.5)  # convective UA_g ~ firing^0.6
    radiant_exponent: float = ranged(0.9, 0.0, 2.0)  # radiant heat ~ firing^0.9
    # --- fuel and turbine (eq. 14, 16)
    fuel_cv_MJ_kg: float = 47.0  # natural gas (unverified)
    boiler_efficiency: float = ranged(0.92, 0.5, 1.0)
    rh_flow_fraction: float = ranged(0.9, 0.5, 1.0)
    k_expansion: float = ranged(1.27, 1.01, 1.7)  # eq. (14)/(16) index of expansion
    cp_turbine_J_kgK: float = 2600.0  # eq. (16) C_p
    eta_hp: float = ranged(0.35, 0.05, 1.0)  # eq. (16), paper 0.30-0.40
    eta_iplp: float = ranged(0.70, 0.05, 1.0)  # eq. (16), paper 0.65-0.75
    p_condenser_kPa: float = ranged(7.0, 1.0, 30.0)
    # --- unit controllers and actuators
    # boiler-input-rate lead on the fuel demand (package doc)
    T_bir_s: float = ranged(135.0, 0.0, 600.0)
    # fuel/water-ratio trim on the evaporator outlet enthalpy: fuel fraction per 100 kJ/kg
    # error (P) and per 100 kJ/kg and s (I). Integral only by default: a P part makes the
    # firing an algebraic function of a fast enthalpy state, which ROS2 at 5 s integrates
    # with 0.08 K instead of 0.01 K error over the load ramp.
    fwr_kp: float = ranged(0.0, 0.0, 1.0)
    fwr_ki_per_s: float = ranged(5e-4, 0.0, 0.05)
    # --- load-change physics (package doc, "Load changes")
    tau_furnace_s: float = ranged(20.0, 0.5, 300.0)  # heat release behind the gas/oil fuel demand
    # evaporator-outlet schedule error at half load
    fwr_schedule_error_kJ_kg: float = ranged(-30.0, -80.0, 80.0)
    # share of the heat-absorption bias on the furnace walls
    bias_evap_share: float = ranged(0.5, 0.0, 1.0)
    n_line: int = ranged(3, 1, 12)  # mixing cells of the outlet header + main-steam line
    # effective header/line/valve-chest metal at steam temperature
    line_metal_t: float = ranged(50.0, 0.1, 500.0)
    # steam volume of the header and the two main-steam lines
    line_volume_m3: float = ranged(15.0, 0.1, 200.0)
    tau_valve_s: float = 2.0
    valve_rate_per_s: float = 0.1  # full stroke in 10 s
    tau_tc1_s: float = 5.0  # thermocouple ("a few seconds", Ghaffari et al. section II)
    tau_tc2_s: float = 20.0  # thermowell ("some tens of seconds", idem)
    dt_s: float = 5.0  # control interval = the paper's sampling time
    n_substeps: int = 1  # ROS2 steps per control interval

    def __post_init__(self) -> None:
        zero_ok = {
            "dT_deaerator_dload_K",
            "dT_hp_dload_K",
            "T_bir_s",
            "fwr_kp",
            "fwr_ki_per_s",
            "gas_temp_coeff",
            "fwr_schedule_error_kJ_kg",
            "bias_evap_share",
        }
        validate_params(
            self,
            positive=tuple(f.name for f in fields(self) if f.name not in zero_ok),
        )
        name = type(self).__name__
        if self.p_min_MPa >= self.p_nom_MPa:
            raise ValueError(f"{name}.p_min_MPa must be below p_nom_MPa")
        if self.p_nom_MPa + self.dp_boiler_MPa * P_SHARE[SEC.EV] * 1.44 >= 21.5:
            raise ValueError(f"{name}.dp_boiler_MPa: the evaporator must stay subcritical")
        if self.p_pump_MPa <= self.p_nom_MPa + self.dp_boiler_MPa:
            raise ValueError(f"{name}.p_pump_MPa must exceed the economizer inlet pressure")
        T_fw = self.T_deaerator_C + self.dT_hp_heaters_K
        chain = (T_fw, self.T_eco_out_C, self.T_evap_out_C, self.T_sh1_out_C, self.T_sh2_out_C)
        for a, b, f in zip(
            chain[:-1],
            chain[1:],
            ("T_eco_out_C", "T_evap_out_C", "T_sh1_out_C", "T_sh2_out_C"),
            strict=True,
        ):
            if not b > a + 5.0:
                raise ValueError(f"{name}.{f} must exceed the section inlet temperature")
        if not self.T_sh2_out_C - 30.0 <= self.T_sh3_out_C < self.T_ms_C:
            raise ValueError(f"{name}.T_sh3_out_C must lie between SH2 outlet and main steam")
        for s in (1, 2):
            design, top = (getattr(self, f"spray{s}_{w}_fraction") for w in ("design", "max"))
            if design >= top:
                raise ValueError(f"{name}.spray{s}_design_fraction must be below its max fraction")
        for f, hot in (
            ("Tg_eco_C", self.T_eco_out_C),
            ("Tg_sh1_C", self.T_sh1_out_C),
            ("Tg_sh3_C", self.T_sh3_out_C),
            ("Tg_sh4_C", self.T_ms_C),
            ("Tg_rh_C", self.T_rh_C),
        ):
            if getattr(self, f) * (1.0 - 0.6 * self.gas_temp_coeff) <= hot + 20.0:
                raise ValueError(f"{name}.{f}: gas at 40 % firing must be hotter than the steam")
