"""The README works as written: its quick start runs in a fresh interpreter and prints the
KPIs, its two commands are the ones CI runs, and the generated tables (README, docs/agents/zoo.md,
docs/difficulty.md) have their markers and are rewritten by their generators in place."""

from __future__ import annotations

import importlib.util
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[1]
README = ROOT / "README.md"


def _section(title: str) -> str:
    text = README.read_text(encoding="utf-8")
    start = text.index(f"\n## {title}\n")
    end = text.find("\n## ", start + 1)
    return text[start : end if end > 0 else None]


def _blocks(text: str, lang: str) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", text, flags=re.S)


def quick_start() -> str:
    """The quick start's code, as the README shows it."""
    (code,) = _blocks(_section("Quick start"), "python")
    return code


def test_quick_start_is_short():
    assert len(quick_start().strip().splitlines()) <= 15


def test_quick_start_runs_and_prints_the_kpis(tmp_path):
    """In a fresh interpreter, as a user pastes it (the project's code first on the path)."""
    script = tmp_path / "quick_start.py"
    script.write_text(quick_start())
    env = {"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"}
    for key in ("HOME", "XDG_CACHE_HOME", "STEAMTEMP_GYM_CACHE_DIR"):  # the compile cache
        if key in os.environ:
            env[key] = os.environ[key]
    proc = subprocess.run(
        [sys.executable, str(script)],
        cwd=tmp_path,
        env=env,
        text=True,
        capture_output=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    values = dict(re.findall(r"^\s*(\w+):\s+(-?\d+\.\d\d)$", proc.stdout, flags=re.M))
    assert list(values) == [
        "iae_K_s",
        "max_abs_dev_K",
        "time_outside_5K_s",
        "valve_travel",
        "return",
    ], proc.stdout
    assert float(values["iae_K_s"]) > 0 and float(values["return"]) < 0
    assert 0 < float(values["max_abs_dev_K"]) < 28  # held inside the trip band


def test_the_two_commands_are_the_ones_ci_runs():
    """The README's two commands are make targets that set everything up and run the
    leaderboard and the tests; CI runs the test command itself; the manual install below
    takes PyTorch's CPU build and compiles the plants ahead."""
    blocks = [b.strip() for b in _blocks(_section("The two commands"), "bash")]
    assert blocks == ["make leaderboard\nmake test"]
    make = (ROOT / "Makefile").read_text()
    assert "\nleaderboard: setup\n\t$(BIN)/steamtemp-leaderboard --out $(OUT)\n" in make
    assert "\ntest: setup\n\t$(BIN)/python -m pytest -n 2 -q\n" in make
    for step in (
        "-m venv",
        "--index-url $(TORCH_INDEX)",
        '-e ".[test]"',
        "-m steamtemp_gym.precompile",
    ):
        assert step in make, step
    assert "\nmake test\n" in (ROOT / ".ci" / "run").read_text()
    install = _blocks(_section("Your own environment"), "bash")[0]
    assert "pip install torch==2.13.0 --index-url https://download.pytorch.org/whl/cpu" in install
    assert 'pip install -e ".[test]"' in install
    assert "python -m steamtemp_gym.precompile" in install


def test_make_refuses_a_python_older_than_3_10(tmp_path):
    """The set-up names the Python it needs and stops before making anything."""
    fake = tmp_path / "python3.9"
    fake.write_text("#!/bin/sh\nexec python3 -c 'import sys; sys.exit(1)'\n")
    fake.chmod(0o755)
    venv = tmp_path / "venv"
    argv = ["make", "-C", str(ROOT), "setup", f"PYTHON={fake}", f"VENV={venv}"]
    proc = subprocess.run(argv, capture_output=True, text=True)
    assert proc.returncode != 0
    assert "needs Python >= 3.10" in proc.stdout + proc.stderr
    assert not venv.exists()


def test_readme_is_a_guide():
    text = README.read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 250
    assert not re.search(r"\[00\d\]", text)  # sources by the names of docs/references.md
    for link in re.findall(r"\]\(((?:docs|examples)/[^)#]+)", text):
        assert (ROOT / link).exists(), link


MARKERS = [
    (README, "leaderboard"),
    (README, "trend"),
    (ROOT / "docs" / "agents" / "zoo.md", "zoo"),
    (ROOT / "docs" / "agents" / "zoo.md", "training"),
    (ROOT / "docs" / "baselines.md", "baselines"),
    (ROOT / "docs" / "baselines" / "mpc_linear.md", "compare"),
    (ROOT / "docs" / "baselines.md", "realism"),
    (ROOT / "docs" / "robustness.md", "mismatch"),
    (ROOT / "docs" / "difficulty.md", "difficulty"),
]


@pytest.mark.parametrize(("page", "name"), MARKERS, ids=[f"{p.name}:{n}" for p, n in MARKERS])
def test_generated_blocks_have_their_markers_once(page, name):
    text = page.read_text(encoding="utf-8")
    assert text.count(f"<!-- {name}:start") == 1 and text.count(f"<!-- {name}:end -->") == 1


def _script(path: Path):
    spec = importlib.util.spec_from_file_location(path.stem, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_leaderboard_generator_rewrites_readme_and_agents_page(tmp_path, monkeypatch):
    from agents.leaderboard.summary import summarize

    gen = _script(ROOT / "scripts" / "update_readme_leaderboard.py")
    readme, agents_page = tmp_path / "README.md", tmp_path / "zoo.md"
    baselines_page, robustness_page = tmp_path / "baselines.md", tmp_path / "robustness.md"
    compare_page = tmp_path / "mpc_linear.md"
    shutil.copy(README, readme)
    pages = {
        (ROOT / "docs" / "agents" / "zoo.md", agents_page): gen.AGENTS_PAGE,
        (ROOT / "docs" / "baselines.md", baselines_page): gen.BASELINES_PAGE,
        (ROOT / "docs" / "baselines" / "mpc_linear.md", compare_page): gen.COMPARE_PAGE,
        (ROOT / "docs" / "robustness.md", robustness_page): gen.ROBUSTNESS_PAGE,
    }
    for (page, copy), written in pages.items():
        assert written == page  # the generator writes the pages that hold the markers
        shutil.copy(page, copy)
    monkeypatch.setattr(gen, "README", readme)
    monkeypatch.setattr(gen, "AGENTS_PAGE", agents_page)
    monkeypatch.setattr(gen, "BASELINES_PAGE", baselines_page)
    monkeypatch.setattr(gen, "COMPARE_PAGE", compare_page)
    monkeypatch.setattr(gen, "ROBUSTNESS_PAGE", robustness_page)
    monkeypatch.setattr(gen, "ROOT", tmp_path)
    monkeypatch.setattr(gen, "IMAGE", tmp_path / "img" / "trend.png")
    monkeypatch.setattr(gen, "PARETO_IMAGE", tmp_path / "img" / "leaderboard_pareto.png")
    env = "steamtemp/A-v0"
    rows = [
        {
            "env": env,
            "scenario": "s",
            "policy": p,
            "seed": s,
            "metrics": {"return": r - s, "tripped": 0.0, "iae_K_s": 100.0, "valve_travel": 1.0},
        }
        for p, r in (
            ("cascade_pi_ff", -100.0),
            ("oracle", -40.0),
            ("sb3:ppo", -70.0),
            ("lqi", -90.0),
        )
        for s in range(2)
    ]
    run = {
        "envs": [env],
        "scenarios": ["s"],
        "seeds": [0, 1],
        "steamtemp_gym_version": "x",
        "policies": {env: ["cascade_pi_ff", "oracle", "sb3:ppo", "lqi"]},
    }
    doc, _ = summarize(rows, run)
    out = tmp_path / "out"
    (out / "plots").mkdir(parents=True)
    (out / "leaderboard.json").write_text(json.dumps(dict(doc, episodes=rows)))
    (out / "plots" / "A-v0__heldout_sootblowing.png").write_bytes(b"png")
    before = readme.read_text()
    gen.main(["--out", str(out), "--plot", "A-v0__heldout_sootblowing.png"])
    assert "docs/img/leaderboard_pareto.png" not in readme.read_text()  # no figure, no link
    (out / "plots" / "pareto.png").write_bytes(b"pareto")
    gen.main(["--out", str(out), "--plot", "A-v0__heldout_sootblowing.png"])
    after = readme.read_text()
    assert "| 1 | sb3:ppo | 0.50" in after and "scenario `heldout:sootblowing`" in after
    assert "Rows are ordered by the mean over plants" in after and "| score over plants |" in after
    assert "](docs/img/leaderboard_pareto.png)" in after
    assert (tmp_path / "img" / "leaderboard_pareto.png").read_bytes() == b"pareto"
    assert "| `lqi` | 100 / 1.0x / - / 0/2 |" in baselines_page.read_text()  # actuator table
    # outside the markers nothing changed
    strip = re.compile(r"<!-- (leaderboard|trend):start.*?<!-- \1:end -->", re.S)
    assert strip.sub("", after) == strip.sub("", before)
    assert "| A-v0 | sb3:ppo | model-free | **0.50" in agents_page.read_text()
    assert "| A-v0 | lqi (best baseline) | baseline |" in agents_page.read_text()
    assert "| s | - / - / -100.5 | - / - / 100 | - / - / 1.00 | - / - / - |" in (
        compare_page.read_text()
    )  # mpc_linear / cascade_pi / cascade_pi_ff, two not run
    assert "1 of 1 baseline-plant pairs have no episode" in baselines_page.read_text()
    assert (tmp_path / "img" / "trend.png").read_bytes() == b"png"
    assert "<!-- mismatch:start" in robustness_page.read_text()  # no mismatch rows: empty


def test_difficulty_generator_replaces_only_its_block():
    diff = _script(ROOT / "benchmarks" / "difficulty.py")
    text = (ROOT / "docs" / "difficulty.md").read_text()
    block = "<!-- difficulty:start (generated) -->\nnew \\1 table\n<!-- difficulty:end -->"
    new = diff.replace_block(text, block)
    assert (
        block in new
        and new.split("<!-- difficulty:start")[0] == text.split("<!-- difficulty:start")[0]
    )
    with pytest.raises(SystemExit, match="0 difficulty"):
        diff.replace_block("no markers", block)
