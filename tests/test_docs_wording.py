"""Docs and command-line help speak to users: no project-history words ('issue 14',
'session 19', 'this round') in README.md, docs/, examples/ or any ``--help`` (history goes to
CHANGELOG.md)."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[1]
JARGON = re.compile(r"\b(?:issues?|sessions?)\s*#?\d+|\bthis (?:round|session)\b|\brounds?\b", re.I)


def _hits(text: str) -> list[str]:
    return [
        text[max(m.start() - 40, 0) : m.end() + 40].replace("\n", " ")
        for m in JARGON.finditer(text)
    ]


def test_the_pattern_finds_history_words():
    assert _hits("In session 19 (issue 14 filed) ... what changed in this round") != []
    assert len(_hits("Issue #7, 2 rounds")) == 2
    assert _hits("products are rounded differently; a sessionless run") == []


@pytest.mark.parametrize(
    "path",
    sorted([ROOT / "README.md", *ROOT.glob("docs/**/*.md"), *ROOT.glob("examples/*")]),
    ids=lambda p: str(p.relative_to(ROOT)),
)
def test_docs_have_no_history_words(path):
    assert not _hits(path.read_text(encoding="utf-8")), _hits(path.read_text(encoding="utf-8"))


def _package_helps() -> dict[str, str]:
    from agents import train, tune
    from agents.leaderboard import cli as leaderboard
    from steamtemp_gym import __main__ as listing
    from steamtemp_gym import docs
    from steamtemp_gym.testing import cli

    helps = {
        "steamtemp-leaderboard": leaderboard.make_parser().format_help(),
        "steamtemp-train": train.make_parser().format_help(),
        "steamtemp-check": cli.make_parser().format_help(),
        "python -m steamtemp_gym": listing.report(),
    }
    for name, main in (
        ("python -m agents.tune", tune.main),
        ("python -m steamtemp_gym.docs", docs.main),
    ):
        helps[name] = _captured_help(main)
    return helps


def _captured_help(main) -> str:
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf), pytest.raises(SystemExit):
        main(["--help"])
    return buf.getvalue()


def test_package_command_help_has_no_history_words():
    helps = _package_helps()
    assert all(len(h) > 200 for h in helps.values()), {k: len(v) for k, v in helps.items()}
    bad = {name: _hits(text) for name, text in helps.items() if _hits(text)}
    assert not bad, bad


def test_benchmark_and_script_help_has_no_history_words():
    files = sorted([*ROOT.glob("benchmarks/*.py"), *ROOT.glob("scripts/*.py")])
    procs = [
        subprocess.Popen(
            [sys.executable, str(f), "--help"],
            cwd=ROOT,
            text=True,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
        )
        for f in files
    ]
    bad = {}
    for f, p in zip(files, procs, strict=True):
        out, err = p.communicate(timeout=300)
        assert p.returncode == 0 and "usage" in out, (f, err[-500:])
        if _hits(out):
            bad[f.name] = _hits(out)
    assert not bad, bad
