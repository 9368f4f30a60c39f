"""Every plant's declared layout against its plant class: the named output slots are the
outputs' order, the parameter and state slots its packing and state vector hold, and the
slots declared copied (COPIED) hold their Params fields."""

from __future__ import annotations

import dataclasses
import importlib
import importlib.util
import math
from types import SimpleNamespace

import pytest

import steamtemp_gym
from steamtemp_gym import plants
from steamtemp_gym.plants.base import K0
from steamtemp_gym.plants.copies import Copy, as_copy, kelvin
from steamtemp_gym.slots import blocks, slots


def _layout(env_id: str) -> str | None:
    """The layout module of a plant package (None for a plant in one module)."""
    module = plants.PLANTS[env_id].split(":")[0]
    if importlib.util.find_spec(module).submodule_search_locations is None:
        return None
    return module + ".layout" if importlib.util.find_spec(module + ".layout") else None


#: plants whose kernels read a declarative layout module (steamtemp_gym/slots.py)
LAYOUTS = {env_id: _layout(env_id) for env_id in steamtemp_gym.ENV_IDS if _layout(env_id)}


@pytest.mark.parametrize("env_id", sorted(LAYOUTS))
def test_the_output_slots_are_the_plants_outputs_in_order(env_id):
    layout = importlib.import_module(LAYOUTS[env_id])
    cls = plants.plant_class(env_id)
    assert cls.outputs is layout.OUTPUTS
    assert layout.IZ._fields == tuple(s.name for s in cls.outputs)
    assert tuple(layout.IZ) == tuple(range(len(cls.outputs)))


@pytest.mark.parametrize("env_id", sorted(LAYOUTS))
def test_parameter_and_state_slots_lie_inside_the_packed_arrays(env_id):
    """Every parameter slot indexes the packed P (of length N_P where the layout fixes it),
    every state slot the state vector, and the valve actuators name slots of both."""
    layout = importlib.import_module(LAYOUTS[env_id])
    plant = plants.make(env_id)
    assert plant.P.shape == (getattr(layout, "N_P", plant.P.size),)
    assert len(set(layout.IP)) == len(layout.IP) and max(layout.IP) < plant.P.size
    assert len(set(layout.IX)) == len(layout.IX) and max(layout.IX) < plant.n_x
    for x_slot, tau_slot, rate_slot in plant.actuators:
        assert x_slot in tuple(layout.IX)
        assert {tau_slot, rate_slot} <= set(layout.IP)


@pytest.mark.parametrize("env_id", sorted(LAYOUTS))
def test_copied_slots_hold_their_fields_in_the_packed_parameters(env_id):
    """Every slot the layout declares copied (COPIED) is a parameter slot and names a field
    of the plant's Params, and the default plant's P holds that field with its conversion."""
    layout = importlib.import_module(LAYOUTS[env_id])
    fields = {f.name for f in dataclasses.fields(plants.plant_class(env_id).Params)}
    copies = {slot: as_copy(spec) for slot, spec in layout.COPIED.items()}
    assert copies
    for slot, copy in copies.items():
        assert slot in layout.IP._fields, f"COPIED names no parameter slot {slot!r}"
        assert copy.field in fields, f"COPIED[{slot!r}] names no field {copy.field!r}"
    plant = plants.make(env_id)
    for slot, copy in copies.items():
        v = getattr(plant.params, copy.field)
        expected = v * (1.0 if copy.scale is None else copy.scale) + (copy.offset or 0.0)
        assert plant.P[getattr(layout.IP, slot)] == expected, (slot, copy)


def test_a_copy_applies_only_the_conversion_it_declares():
    """No scale or offset: the value itself (a -0.0 keeps its sign); a scale multiplies, an
    offset adds (kelvin: + K0)."""
    params = SimpleNamespace(x=-0.0, T_C=20.0)
    assert math.copysign(1.0, Copy("x").value(params)) == -1.0
    assert math.copysign(1.0, Copy("x", scale=1e6).value(params)) == -1.0
    assert kelvin("T_C").value(params) == 20.0 + K0
    assert Copy("T_C", scale=1e6, offset=1.0).value(params) == 20.0 * 1e6 + 1.0


def test_slots_number_names_consecutively_and_blocks_by_their_sizes():
    s = slots("S", "a", "b", "c", start=4)
    assert (s.a, s.b, s.c) == (4, 5, 6) and s._fields == ("a", "b", "c")
    b, end = blocks("B", ("x", 1), ("table", 21), ("y", 1), start=2)
    assert (b.x, b.table, b.y, end) == (2, 3, 24, 25)
