"""The docs site (mkdocs.yml, mkdocs_hooks.py): `mkdocs build --strict` passes, so every link
and anchor of README.md and docs/ resolves and every page is in the nav; a broken link or
anchor fails it (the negative control); and no page of docs/ is longer than a reader reads
in one go."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: Lines a page of docs/ may have: a longer page is split by topic (docs/notes/ for history).
MAX_LINES = 300


def _build(config: Path, site: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")  # mkdocs-material's notice, not ours
    return subprocess.run(
        [
            sys.executable,
            "-m",
            "mkdocs",
            "build",
            "--strict",
            "--config-file",
            str(config),
            "-d",
            str(site),
        ],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_the_site_builds_strictly(tmp_path):
    done = _build(ROOT / "mkdocs.yml", tmp_path / "site")
    assert done.returncode == 0, (
        "mkdocs build --strict failed (mkdocs-material is in the [test] extra):\n"
        + done.stdout
        + done.stderr
    )
    for page in (
        "index.html",
        "examples/index.html",
        "changelog/index.html",
        "agents/plant_scale/index.html",
        "envs/index.html",
    ):
        assert (tmp_path / "site" / page).is_file(), page


def test_a_broken_link_or_anchor_fails_the_build(tmp_path):
    """The same site with one missing page and one missing anchor linked: the build fails
    and names both."""
    docs = tmp_path / "docs"
    shutil.copytree(ROOT / "docs", docs)
    page = docs / "agents.md"
    page.write_text(
        page.read_text(encoding="utf-8")
        + "\n[a](agents/zoo.md#no-such-anchor) [b](no_such_page.md)\n",
        encoding="utf-8",
    )
    config = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    assert config.count("docs_dir: docs\n") == 1 and config.count("  - mkdocs_hooks.py\n") == 1
    config = config.replace("docs_dir: docs\n", f"docs_dir: {docs}\n").replace(
        "  - mkdocs_hooks.py\n", f"  - {ROOT / 'mkdocs_hooks.py'}\n"
    )
    (tmp_path / "mkdocs.yml").write_text(config, encoding="utf-8")
    done = _build(tmp_path / "mkdocs.yml", tmp_path / "site")
    out = done.stdout + done.stderr
    assert done.returncode != 0, out
    assert "no-such-anchor" in out and "no_such_page.md" in out, out


def test_no_docs_page_is_longer_than_the_limit():
    pages = sorted(ROOT.glob("docs/**/*.md"))
    assert len(pages) > 40
    long = {
        str(p.relative_to(ROOT)): n
        for p in pages
        if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES
    }
    assert not long, f"pages over {MAX_LINES} lines (split them by topic): {long}"
