"""Fixtures shared by the test files, and the toy plant (tests/toy_plant.py) registered
for the session: the registry-wide tests run on it as on the package's own plants."""

from __future__ import annotations

import pytest

import steamtemp_gym

steamtemp_gym.register_plant("test/ToyLags-v0", "toy_plant:ToyLags")


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
