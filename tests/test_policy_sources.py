"""A broken policy source (steamtemp_gym/policy_sources.py) is passed over, said once on
stderr: steamtemp-check's env checks and ``python -m steamtemp_gym`` still run (a module
that raised at import, or a source without ``parse``, crashed both)."""

from __future__ import annotations

import types

import pytest

from steamtemp_gym import __main__ as listing
from steamtemp_gym import policy_sources
from steamtemp_gym.testing.cli import main as check

CASCADE = "steamtemp/Cascade300MW-v0"


class _Broken:
    def __init__(self, name: str, load) -> None:
        self.name, self.value, self.load = name, f"broken_{name}:source", load


def _raises():
    raise RuntimeError("no policies for you")


@pytest.fixture(params=["raises", "lacks_parse"])
def broken(request, monkeypatch):
    load = _raises if request.param == "raises" else (lambda: types.SimpleNamespace(FORMS=""))
    monkeypatch.setattr(
        policy_sources, "entry_points", lambda group: [_Broken(request.param, load)]
    )
    monkeypatch.setattr(policy_sources, "_registered", [])
    monkeypatch.setattr(policy_sources, "_warned", set())
    return request.param


def test_a_broken_source_is_passed_over_and_said_once(broken, capsys):
    assert policy_sources.find() is None
    assert policy_sources.find() is None
    err = capsys.readouterr().err
    assert err.count("is passed over") == 1 and f"broken_{broken}:source" in err


def test_the_checker_and_the_listing_run_with_a_broken_source(broken, capsys):
    assert check([CASCADE, "--check", "check_render_frame"]) == 0
    assert listing.main() == 0
    assert "is passed over" in capsys.readouterr().err
