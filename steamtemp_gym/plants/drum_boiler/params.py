"""Parameters of the drum boiler plant: the dataclass of every tunable value with its
validation. The sources (003: Kim's thesis; Astrom-Bell 2000) are named in the package
docstring.

Parameters and their sources:

- drum: Astrom and Bell 2000 (docs/references.md); V_wt,nom = 57.2 m3 at 8.5 MPa /
  50 kg/s defines the normal water level (level 0). Drum metal m_d 40 t: plausible
  default, unverified (drum.py).
- operating point: drum pressure 8.5 MPa, drum steam flow 50 kg/s and feedwater
  242 C at rated load (Astrom-Bell); feedwater 40 K colder per unit load reduction
  (HP heaters; plausible default, unverified). Constant drum pressure over the load
  range (usual for drum units; the thesis's operating points instead let pressure rise
  with load).
- superheaters: plausible defaults, unverified, for a unit of this size. Rated main
  steam 52.6 kg/s (189 t/h: 50 kg/s from the drum plus 5 % spray), 8.1 MPa / 505 C at
  the SH outlet (the usual 500-510 C of ~9 MPa non-reheat units; 0.4 MPa drum-to-outlet
  pressure drop at rated flow). Heat to the steam at rated load: 85 MW in the risers
  plus 41 MW in the superheaters (~126 MW, a ~40-45 MWe non-reheat unit, the nearest
  round class being ~60 MW). Primary SH 96 tubes 34/42 mm x 70 m
  designed to deliver 440 C; final SH 72 tubes 32/42 mm x 60 m; steel 7800 kg/m3,
  550 J/(kg K); steam-side coefficient 3500 W/(m2 K) at rated flow, exponent 0.8
  (IDAES 320 MW figures, docs/references.md); 5 segments each. The gas-side
  conductances UA_g1, UA_g2 are calibrated so that the rated design holds: 440 C after
  the primary SH, 5 % spray
  (valve 0.50 of its 10 % capacity, 1.5 MPa across it; attemperator capacities of
  8-10 % of rated steam flow are usual), 400 C after the attemperator, 505 C out. Gas
  temperatures 750 C / 1050 C at the two SH at rated firing, falling 200 / 300 K per
  unit of firing: the spray need falls with load (valve 0.50, 0.37, 0.26 at 100, 75,
  50 %) and stays inside the valve range for fouling 0.85-1.15 (0.07-0.85).
- controls: tau_steam 10 s, tau_mill 60 s, tau_firing 60 s, T_bir 45 s, pressure PI
  K_p 1.5 (firing per relative pressure error), T_i 500 s (for the two-lag firing: with
  K_p 3, T_i 300 s the pressure loop's damping would be 0.14); level PI
  200 kg/s per m, T_i 200 s; tau_fw 5 s; valve 2 s lag and 10 %/s rate; thermocouple
  lags 5 s and 20 s (as the FSH plant). Plausible defaults, unverified, tuned on the
  linearized drum with its loops (slowest closed-loop mode ~400 s, damping >= 0.5).
"""

from __future__ import annotations

from dataclasses import dataclass

from steamtemp_gym.plants.base import K0
from steamtemp_gym.plants.param_ranges import ranged, validate_params
from steamtemp_gym.steam import sat_p


@dataclass(frozen=True)
class DrumBoilerParams:
    """Parameters of the drum boiler plant (units in the names; sources in the module doc)."""

    # drum, Astrom and Bell (2000)
    V_d_m3: float = 40.0
    V_r_m3: float = 37.0
    V_dc_m3: float = 11.0
    m_t_kg: float = 300e3
    m_r_kg: float = 160e3
    m_d_kg: float = 40e3  # drum metal in the condensation flow (plausible default, unverified)
    C_p_J_kgK: float = 550.0
    A_d_m2: float = 20.0
    A_dc_m2: float = 0.38
    k_friction: float = 25.0
    beta: float = ranged(0.3, 0.0, 2.0)
    T_d_s: float = 12.0
    V_sd0_m3: float = 4.9
    V_wt_nom_m3: float = 57.2  # total water volume at the normal level, rated load
    # operating point
    p_drum_MPa: float = ranged(8.5, 2.0, 16.0)
    q_s_nom_kg_s: float = 50.0  # drum steam flow at rated load
    T_fw_nom_C: float = ranged(242.0, 100.0, 300.0)
    # feedwater temperature drop per unit load reduction
    dT_fw_dload_K: float = ranged(40.0, 0.0, 100.0)
    p_fw_MPa: float = ranged(9.5, 2.0, 30.0)  # feedwater pressure for its properties
    T_out_C: float = ranged(505.0, 400.0, 600.0)  # main steam temperature setpoint
    T_primary_out_C: float = 440.0  # primary SH outlet at the rated design point
    # spray / main-steam flow at the rated design
    spray_design_fraction: float = ranged(0.05, 0.005, 0.2)
    # spray / rated main-steam flow, valve fully open
    spray_max_fraction: float = ranged(0.10, 0.01, 0.3)
    # protection: attemperator outlet >= Tsat(p_1) + margin
    attemp_margin_K: float = ranged(12.0, 1.0, 50.0)
    dp_spray_MPa: float = 1.5  # pressure drop across the spray valve
    dp_sh_nom_MPa: float = 0.4  # drum to SH outlet at rated flow
    # superheaters
    n_segments: int = ranged(5, 1, 40)  # per superheater
    n_tubes_1: int = 96
    tube_length_1_m: float = 70.0
    tube_id_1_m: float = 0.034
    tube_od_1_m: float = 0.042
    n_tubes_2: int = 72
    tube_length_2_m: float = 60.0
    tube_id_2_m: float = 0.032
    tube_od_2_m: float = 0.042
    rho_metal_kg_m3: float = 7800.0
    c_metal_J_kgK: float = 550.0
    alpha_nom_W_m2K: float = 3500.0
    Tg1_nom_C: float = 750.0
    dTg1_dload_K: float = 200.0
    Tg2_nom_C: float = 1050.0
    dTg2_dload_K: float = 300.0
    gas_flow_exponent: float = ranged(0.6, 0.0, 1.0)
    # controls and actuators
    tau_steam_s: float = 10.0
    # coal mill: grinding and pulverized-coal inventory lag
    tau_mill_s: float = ranged(60.0, 1.0, 600.0)
    tau_firing_s: float = ranged(60.0, 1.0, 900.0)  # furnace heat release behind the mills
    # boiler-input-rate feed-forward lead of the boiler master
    T_bir_s: float = ranged(45.0, 0.0, 600.0)
    n_line: int = ranged(3, 1, 8)  # mixing cells of the outlet header and main-steam line
    line_volume_m3: float = ranged(2.0, 0.01, 50.0)  # their steam volume
    line_metal_t: float = ranged(5.5, 0.01, 100.0)  # their effective metal at steam temperature
    Kp_pressure: float = 1.5  # firing fraction per relative pressure error
    Ti_pressure_s: float = 500.0
    Kp_level_kg_s_m: float = 200.0
    Ti_level_s: float = 200.0
    tau_fw_s: float = 5.0
    tau_valve_s: float = 2.0
    valve_rate_per_s: float = 0.1
    tau_tc1_s: float = 5.0
    tau_tc2_s: float = 20.0
    dt_s: float = 2.0
    n_substeps: int = 1

    def __post_init__(self) -> None:
        validate_params(
            self,
            positive=tuple(
                n for n in self.__dataclass_fields__ if n not in ("dT_fw_dload_K", "T_bir_s")
            ),
        )
        for i in (1, 2):
            if getattr(self, f"tube_od_{i}_m") <= getattr(self, f"tube_id_{i}_m"):
                raise ValueError(f"DrumBoilerParams.tube_od_{i}_m must exceed tube_id_{i}_m")
        if self.V_wt_nom_m3 <= self.V_dc_m3 + 0.5 * self.V_r_m3:
            raise ValueError("DrumBoilerParams.V_wt_nom_m3 leaves the drum without water")
        if self.V_wt_nom_m3 >= self.V_d_m3 + self.V_r_m3 + self.V_dc_m3:
            raise ValueError("DrumBoilerParams.V_wt_nom_m3 exceeds the total volume")
        if self.p_fw_MPa <= self.p_drum_MPa:
            raise ValueError("DrumBoilerParams.p_fw_MPa must exceed p_drum_MPa")
        if self.dp_sh_nom_MPa >= 0.5 * self.p_drum_MPa:
            raise ValueError("DrumBoilerParams.dp_sh_nom_MPa is too large for p_drum_MPa")
        if self.spray_design_fraction >= self.spray_max_fraction:
            raise ValueError("DrumBoilerParams.spray_design_fraction must be below the max")
        if self.T_fw_nom_C - self.dT_fw_dload_K < 100.0:
            raise ValueError("DrumBoilerParams.dT_fw_dload_K: feedwater below 100 C at zero load")
        if self.T_fw_nom_C + 20.0 >= self.p_drum_tsat_C():
            raise ValueError("DrumBoilerParams.T_fw_nom_C must be subcooled at p_drum_MPa")
        if not self.p_drum_tsat_C() < self.T_primary_out_C < self.T_out_C:
            raise ValueError("DrumBoilerParams.T_primary_out_C must lie between Tsat and T_out_C")
        for i in (1, 2):
            tg = getattr(self, f"Tg{i}_nom_C") - 0.8 * getattr(self, f"dTg{i}_dload_K")
            if tg <= self.T_out_C:
                raise ValueError(f"DrumBoilerParams.dTg{i}_dload_K: gas at 20 % firing below T_out")

    def p_drum_tsat_C(self) -> float:
        """Saturation temperature at the drum pressure (C)."""
        return float(sat_p(self.p_drum_MPa * 1e6)[0] - K0)
