"""A plant of one's own: ``steamtemp_gym.register_plant`` and the toy plant the suite
registers (tests/toy_plant.py, tests/conftest.py)."""

from __future__ import annotations

import gymnasium as gym
import pytest

import steamtemp_gym
from agents import specs
from steamtemp_gym import catalog, provenance
from steamtemp_gym.docs import page_name, pages

TOY = "test/ToyLags-v0"


def test_the_toy_plant_is_registered_as_the_package_plants_are():
    assert TOY in steamtemp_gym.ENV_IDS and TOY in gym.registry and TOY in catalog.PLANTS
    assert not catalog.packaged(TOY) and catalog.packaged("steamtemp/Cascade300MW-v0")
    assert page_name(TOY) not in pages()  # the reference pages are the package's plants'
    files = provenance.outside_plant_files(TOY)
    assert [f.name for f in files] == ["toy_plant.py"]
    assert provenance.outside_plant_files("steamtemp/Cascade300MW-v0") == []
    assert specs.source_digest(TOY) != specs.source_digest("steamtemp/Cascade300MW-v0")


@pytest.mark.parametrize(
    ("plant_id", "entry", "match"),
    [
        ("ToyLags-v0", "toy_plant:ToyLags", "namespace/Name-vN"),
        (7, "toy_plant:ToyLags", "namespace/Name-vN"),
        (TOY, "toy_plant:ToyLags", "is taken"),
        ("steamtemp/SupercriticalFSH-v0", "toy_plant:ToyLags", "is taken"),
        ("test/Other-v0", "no_such_module:X", "No module named 'no_such_module'"),
        ("test/Other-v0", "toy_plant:NoSuchClass", "NoSuchClass"),
        ("test/Other-v0", "toy_plant", "must name a subclass of Plant"),
        ("test/Other-v0", "toy_plant:ToyParams", "must name a subclass of Plant"),
        ("test/Other-v0", "toy_plant:ToyLags", "whose id is 'test/Other-v0'"),
        # Gymnasium reads -v00 as -v0: it replaced the shipped env, fingerprints and all
        ("steamtemp/SupercriticalFSH-v00", "toy_plant:ToyLags", "without leading zeros"),
        # an id Gymnasium already holds, or whose unversioned name it holds
        ("test/CartPole-v1", "toy_plant:ToyLags", "taken in Gymnasium's registry"),
        ("test/Unversioned-v0", "toy_plant:ToyLags", "taken in Gymnasium's registry"),
        # a module that fails at import in any way, and a Plant with no declarations
        ("test/Other-v0", "hostile_plants_raise:X", "RuntimeError: at import"),
        ("test/Other-v0", "hostile_plants_syntax:X", "SyntaxError"),
        ("test/Other-v0", "hostile_plants_exit:X", "SystemExit"),
        ("test/Bare-v0", "hostile_plants:Bare", "not a complete plant"),
    ],
)
def test_a_bad_registration_is_refused_and_registers_nothing(
    plant_id, entry, match, tmp_path, monkeypatch
):
    (tmp_path / "hostile_plants.py").write_text(
        "from steamtemp_gym.plants import Plant\n\n\nclass Bare(Plant):\n    id = 'test/Bare-v0'\n"
    )
    (tmp_path / "hostile_plants_raise.py").write_text("raise RuntimeError('at import')\n")
    (tmp_path / "hostile_plants_syntax.py").write_text("def (:\n")
    (tmp_path / "hostile_plants_exit.py").write_text("raise SystemExit(3)\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    for name in ("test/CartPole-v1", "test/Unversioned"):
        monkeypatch.setitem(gym.registry, name, gym.registry["CartPole-v1"])
    ids, plants_, envs = steamtemp_gym.ENV_IDS, dict(catalog.PLANTS), set(gym.registry)
    with pytest.raises(ValueError, match=match):
        steamtemp_gym.register_plant(plant_id, entry)
    assert (steamtemp_gym.ENV_IDS, catalog.PLANTS, set(gym.registry)) == (ids, plants_, envs)
