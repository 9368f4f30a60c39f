"""Every plant's parameter ranges: declared with the field, enforced on construction."""

from __future__ import annotations

import dataclasses

import pytest

from steamtemp_gym.plants import PLANTS, plant_class
from steamtemp_gym.plants.param_ranges import COMMON_RANGES, field_range, ranged

PARAMS = sorted({plant_class(i).Params for i in PLANTS}, key=lambda c: c.__name__)


def _ranged_fields(cls):
    return [(f, field_range(f)) for f in dataclasses.fields(cls) if field_range(f) is not None]


@pytest.mark.parametrize("cls", PARAMS, ids=lambda c: c.__name__)
def test_every_plant_declares_ranges_and_its_defaults_lie_in_them(cls):
    spans = _ranged_fields(cls)
    names = {f.name for f, _ in spans}
    assert set(COMMON_RANGES) <= names
    assert len(spans) > len(COMMON_RANGES)
    for f, (lo, hi) in spans:
        assert lo <= f.default <= hi, f.name


@pytest.mark.parametrize("cls", PARAMS, ids=lambda c: c.__name__)
def test_a_value_just_outside_its_range_is_rejected_naming_the_field(cls):
    for f, (lo, hi) in _ranged_fields(cls):
        step = 1 if isinstance(f.default, int) else max(abs(hi - lo) * 1e-3, 1e-9)
        with pytest.raises(ValueError, match=rf"{cls.__name__}\.{f.name}\b"):
            cls(**{f.name: type(f.default)(hi + step)})


def test_a_default_outside_its_own_range_is_a_definition_error():
    with pytest.raises(ValueError, match=r"outside its own range \[0.0, 1.0\]"):
        ranged(2.0, 0.0, 1.0)
