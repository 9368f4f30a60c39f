"""Fixtures shared by the test files."""

from __future__ import annotations

import pytest


@pytest.fixture
def argparse_error(capsys, tmp_path):
    """A function ``(main, argv) -> stderr``: runs ``main`` on ``argv`` plus ``--out`` a
    folder under ``tmp_path``, asserts that it exits with argparse's code 2 and creates no
    such folder, and returns what it wrote to stderr."""

    def run(main, argv: list[str]) -> str:
        out = tmp_path / "out"
        with pytest.raises(SystemExit) as exc:
            main([*argv, "--out", str(out)])
        assert exc.value.code == 2
        assert not out.exists()
        return capsys.readouterr().err

    return run
