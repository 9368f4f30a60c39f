"""The packages point one way (steamtemp_gym <- baselines <- agents) and policies reach the
checker through a policy source, never through an import of steamtemp_gym's own."""

from __future__ import annotations

import ast
import subprocess
import sys
import types
from importlib.metadata import entry_points
from pathlib import Path

import pytest

from steamtemp_gym import policy_sources, provenance
from steamtemp_gym.testing.cli import main

ROOT = Path(__file__).resolve().parent.parent
#: Each package and the packages of this distribution it may import.
ALLOWED = {
    "steamtemp_gym": set(),
    "baselines": {"steamtemp_gym"},
    "agents": {"steamtemp_gym", "baselines"},
}


def _imports(path: Path) -> list[tuple[int, str]]:
    out = []
    for node in ast.walk(ast.parse(path.read_bytes())):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom) and not node.level and node.module:
            out.append((node.lineno, node.module))
    return out


def _code_words(tree: ast.AST) -> list[tuple[int, str]]:
    """(line, text) of every name, attribute, imported module and string constant but the
    docstrings of a module's syntax tree (removed as the provenance digests remove them)."""
    out = []
    for node in ast.walk(provenance.strip_docstrings(tree)):
        if isinstance(node, ast.Name):
            out.append((node.lineno, node.id))
        elif isinstance(node, ast.Attribute):
            out.append((node.lineno, node.attr))
        elif isinstance(node, ast.Import | ast.ImportFrom):
            out += [(node.lineno, a.name) for a in node.names]
            out += [(node.lineno, node.module)] if getattr(node, "module", None) else []
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            out.append((node.lineno, node.value))
    return out


def test_no_code_outside_a_plants_package_names_a_plant():
    """A plant's facts are declared in its package: outside it, only the catalog's lines
    name a plant (docstrings, which cite the papers' plants and give examples, aside)."""
    from steamtemp_gym.catalog import PLANTS, packaged

    ids = [env_id for env_id in PLANTS if packaged(env_id)]
    own = {PLANTS[i].split(":")[0].split(".")[2] for i in ids}  # the plants' packages
    # their classes and ids (the ids' names are the classes')
    names = own | {PLANTS[i].split(":")[1] for i in ids} | {i.split("/")[1][:-3] for i in ids}
    assert len(names) == 2 * len(ids) >= 10, names
    bad = []
    for package in sorted(ALLOWED):
        for f in sorted((ROOT / package).rglob("*.py")):
            rel = f.relative_to(ROOT)
            if rel.as_posix() == "steamtemp_gym/catalog.py" or (
                rel.parts[:2] == ("steamtemp_gym", "plants")
                and (rel.parts[2] if len(rel.parts) > 3 else f.stem) in own
            ):
                continue
            words = _code_words(ast.parse(f.read_bytes()))
            bad += [
                f"{rel}:{line} {text[:60]!r}"
                for line, text in words
                if any(name in text for name in names)
            ]
    assert not bad, bad


@pytest.mark.parametrize("package", sorted(ALLOWED))
def test_a_package_imports_only_the_packages_below_it(package):
    own = set(ALLOWED) - {package} - ALLOWED[package]
    bad = [
        f"{f.relative_to(ROOT)}:{line} imports {name}"
        for f in sorted((ROOT / package).rglob("*.py"))
        for line, name in _imports(f)
        if name.split(".")[0] in own
    ]
    assert not bad, bad


def test_importing_the_envs_and_scenarios_loads_no_plant_and_no_policy():
    code = (
        "import sys, gymnasium as gym, steamtemp_gym, steamtemp_gym.scenarios as s\n"
        "own = s.names('steamtemp/Cascade300MW-v0')\n"
        "print(sorted(m.split('.')[0] for m in sys.modules if m.split('.')[0] in "
        "('baselines', 'agents')), 'steamtemp_gym.plants.supercritical_fsh' in sys.modules,"
        " 'setpoint_step_535_545' in own)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True
    ).stdout.split()
    # the plant's own scenarios are found through the catalog without a prior import
    assert out == ["[]", "False", "True"]


def test_the_distribution_declares_its_policy_source():
    (ep,) = [e for e in entry_points(group=policy_sources.GROUP) if e.name == "steamtemp"]
    from agents import specs

    assert ep.load() is specs and policy_sources.find() is specs
    spec = policy_sources.parse("cascade_pi")
    assert spec.available("steamtemp/SupercriticalFSH-v0") and not spec.is_factory
    assert not spec.needs_extra and policy_sources.parse("sb3:ppo").needs_extra


def _source(names: dict) -> types.SimpleNamespace:
    def parse(name):
        if name not in names:
            raise ValueError(f"unknown policy {name!r}; mine: {sorted(names)}")
        return names[name]

    return types.SimpleNamespace(
        parse=parse,
        FORMS="one of mine",
        listing=lambda: ["mine"],
        everyday_names=lambda: ["my_everyday"],
    )


def test_a_registered_source_takes_precedence_and_leaves_cleanly(capsys):
    from steamtemp_gym import __main__ as listing

    mine = _source({})
    policy_sources.register(mine)
    try:
        assert policy_sources.find() is mine
        with pytest.raises(ValueError, match="unknown policy 'cascade_pi'; mine"):
            policy_sources.parse("cascade_pi")
        assert "\nmine\n" in listing.report()
        with pytest.raises(SystemExit) as exit_:  # 'all' is the source's everyday names
            main(["--policy", "all", "--no-env-checks", "SupercriticalFSH-v0"])
        assert exit_.value.code == 2 and "'my_everyday'; mine" in capsys.readouterr().err
    finally:
        policy_sources.unregister(mine)
    assert policy_sources.find() is not mine


def test_without_a_source_names_are_refused_and_factories_still_work(monkeypatch, capsys):
    monkeypatch.setattr(policy_sources, "entry_points", lambda group: [])
    assert policy_sources.find() is None
    with pytest.raises(ValueError, match="no policy source is installed"):
        policy_sources.parse("cascade_pi")
    with pytest.raises(SystemExit) as exit_:
        main(["--policy", "all", "SupercriticalFSH-v0"])
    assert exit_.value.code == 2 and "no policy source" in capsys.readouterr().err
    from steamtemp_gym import __main__ as listing

    assert "Baselines" not in listing.report()


def test_a_source_without_its_attributes_is_refused():
    before = policy_sources.find()
    with pytest.raises(ValueError, match=r"lacks \['FORMS', 'everyday_names', 'listing'\]"):
        policy_sources.register(types.SimpleNamespace(parse=str))
    with pytest.raises(ValueError, match="is not a registered policy source"):
        policy_sources.unregister(object())
    assert policy_sources.find() is before
