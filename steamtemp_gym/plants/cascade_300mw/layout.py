"""The 300 MW cascade plant's layout: its outputs, and the named slots of the packed
parameters P (a header, then the section models over load), the states x and the outputs
z (steamtemp_gym/slots.py)."""

from __future__ import annotations

from steamtemp_gym.plants.base import Signal, design_spray_signal
from steamtemp_gym.slots import slots

#: The physical outputs, in the order of z.
OUTPUTS = (
    Signal("outlet_temp_C", "C", 535.0, 20.0, observed=False, description="superheated steam y"),
    Signal("outlet_temp_meas_C", "C", 535.0, 20.0, noisy=True, description="measured y"),
    Signal(
        "intermediate_temp_C",
        "C",
        470.0,
        20.0,
        noisy=True,
        description="attemperator outlet y_i (measured, inner loop)",
    ),
    Signal("spray_valve", "1", 0.5, 0.5, description="valve position feedback"),
    Signal("spray_flow_kg_s", "kg/s", 4.0, 4.0, description="secondary spray water flow"),
    Signal("omega_K", "K", 0.0, 4.0, description="measured outer disturbance omega (next step)"),
    Signal(
        "omega2_kg_s",
        "kg/s",
        0.0,
        1.0,
        description="measured inner disturbance omega_2 (next step)",
    ),
    Signal(
        "outer_disturbance_K",
        "K",
        0.0,
        10.0,
        observed=False,
        description="heat-absorption input q at the inertia section (hidden)",
    ),
    design_spray_signal(4.0, 4.0, "spray holding 535 C undisturbed at this load"),
)
#: Index of each output in z, by name.
IZ = slots("CascadeOutputs", *(s.name for s in OUTPUTS))

LOAD_STEP = 0.01  # spacing of the load grid of section models
N_GRID = 101  # loads LOAD_MIN .. LOAD_MAX (params.py)
#: The header of P (lead and inertia orders, load dependence, interval, spray capacity and
#: design sprays, the heat-absorption and spray-water coefficients, temperatures, the
#: omega generators' scales, the block length and the omega correlation), one spare entry,
#: then GRID: N_GRID + 2 blocks of the discretized model, the load grid, the exact 100 %
#: block and a copy of it.
IP = slots("CascadeParams", "N1", "N2", "LD", "DT", "WMAX", "W100", "W50", "CQ", "CSW",
           "TOUT", "TI", "AOM", "BOM2", "NB", "COM", "spare", "GRID")  # fmt: skip
#: The slots of P that hold a CascadeParams field (steamtemp_gym/plants/copies.py).
COPIED = {
    "N1": "lead_order", "N2": "inertia_order", "LD": "load_dependent", "DT": "dt_s",
    "WMAX": "spray_max_kg_s", "W100": "spray_rated_kg_s", "W50": "spray_half_load_kg_s",
    "TOUT": "T_out_C", "AOM": "omega_halfwidth_K", "BOM2": "omega2_scale_kg_s",
}  # fmt: skip
#: The states: the measured disturbances omega and omega_2, the generator's seed and step
#: counter, the valve, the gas-side state, then the lag chain from X.
IX = slots("CascadeStates", "OM", "OM2", "SEED", "CNT", "V", "G", "X")
