"""The provenance digests (steamtemp_gym/provenance.py) behind the leaderboard's
fingerprints, the stored tunings and the score's ends, and the compile cache: a docstring
or a comment changes none; a baseline's code changes its rows' digests only; a plant's code
its own digest only. Checked on a copy of the source tree, edited."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

import baselines
import steamtemp_gym
from agents import specs
from agents.leaderboard.plan import policy_digest
from steamtemp_gym import catalog, provenance

POLICIES = (
    "cascade_pi",
    "cascade_pi_ff",
    "cascade_pi_ff_tuned",
    "fao_sf",
    "fao_fac",
    "mpc_linear",
    "lqi",
    "neuro_pid_mee",
    "oracle",
    "frozen_valve",
)

#: The package's own plants (a plant registered from outside depends on every file of the
#: package and on its own).
OWN = [i for i in steamtemp_gym.ENV_IDS if catalog.packaged(i)]


@pytest.fixture
def tree(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A copy of the three packages' Python sources, which the digests then read."""
    for pkg in ("steamtemp_gym", "baselines", "agents"):
        skip = shutil.ignore_patterns("__pycache__", "zoo", "*.npz", "*.zip")
        shutil.copytree(provenance.ROOT / pkg, tmp_path / pkg, ignore=skip)
    monkeypatch.setattr(provenance, "ROOT", tmp_path)
    return tmp_path


def _digests() -> dict[tuple[str, str], str]:
    """The digests of the package's own plants (one registered from outside depends on
    every file of the package and its own)."""
    out = {}
    for e in OWN:
        out[e, "source"] = specs.source_digest(e)
        for n in POLICIES:
            out[e, n] = policy_digest(e, n)
    return out


def _edit(path: Path, old: str, new: str) -> None:
    text = path.read_text()
    assert old in text, f"{old!r} not in {path}"
    path.write_text(text.replace(old, new, 1))


def test_the_digests_read_the_copy(tree):
    """Sanity: the fixture's copy is what the digests hash (an edit there shows)."""
    before = _digests()
    _edit(tree / "agents" / "oracle.py", "import sys\n", "import sys\n_PROBE = 1\n")
    after = _digests()
    assert {k for k in before if before[k] != after[k]} == {(e, "oracle") for e in OWN}


def test_a_docstring_or_comment_edit_changes_no_digest(tree):
    before = _digests()
    _edit(tree / "steamtemp_gym" / "envs" / "core.py", '"""', '"""Edited. ')
    _edit(tree / "baselines" / "cascade_pi.py", '"""', '"""Edited. ')
    _edit(tree / "agents" / "oracle.py", '"""', '"""Edited. ')
    _edit(
        tree / "agents" / "evaluation.py",
        "import numpy as np\n",
        "import numpy as np  # a comment\n\n\n",
    )
    plant = tree / "steamtemp_gym" / "plants" / "drum_boiler" / "kernel.py"
    _edit(plant, '"""', '"""Edited. ')
    assert _digests() == before


def test_editing_one_baseline_changes_only_the_rows_of_the_controllers_that_use_it(tree):
    before = _digests()
    _edit(
        tree / "baselines" / "fao.py",
        "from __future__ import annotations\n",
        "from __future__ import annotations\n\n_PROBE = 1\n",
    )
    after = _digests()
    changed = {n for (e, n) in before if before[e, n] != after[e, n]}
    assert changed == {"fao_sf", "fao_fac"}
    assert all(before[e, "source"] == after[e, "source"] for e in OWN)


def test_editing_one_plant_changes_only_that_plants_digests(tree):
    before = _digests()
    drum = "steamtemp/DrumBoilerSH-v0"
    _edit(
        tree / "steamtemp_gym" / "plants" / "drum_boiler" / "kernel.py",
        "from __future__ import annotations\n",
        "from __future__ import annotations\n\n_PROBE = 1\n",
    )
    after = _digests()
    assert {k for k in before if before[k] != after[k]} == {(drum, "source")}


def test_editing_shared_code_changes_every_plants_digest(tree):
    before = _digests()
    _edit(
        tree / "steamtemp_gym" / "rewards.py",
        "from __future__ import annotations\n",
        "from __future__ import annotations\n\n_PROBE = 1\n",
    )
    after = _digests()
    assert all(before[e, "source"] != after[e, "source"] for e in OWN)


def test_a_policys_code_digest_follows_its_imports():
    module = baselines.factory("mpc_linear").__module__
    files = {f.name for f in provenance.module_files(module, specs.POLICY_PACKAGES)}
    assert {"mpc_linear.py", "mpc_linear_design.py", "linear_models.py"} <= files
    assert "fao.py" not in files and "cascade_pi.py" not in files
    with pytest.raises(ValueError, match="not a module of steamtemp_gym.plants"):
        provenance.plant_files("steamtemp_gym.envs")
