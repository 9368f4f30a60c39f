"""The offline CLIs (agents/behaviour_cloning.py, agents/datasets.py) refuse bad flags with
an argparse error naming the flag, before anything is read or written (a seed of 2**70,
an --out or --data-dir naming a file ended in tracebacks)."""

from __future__ import annotations

import pytest

from agents import behaviour_cloning, datasets


@pytest.fixture
def a_file(tmp_path):
    path = tmp_path / "not_a_folder"
    path.write_text("x")
    return path


@pytest.mark.parametrize("case", ["seed", "out", "data_dir"])
def test_behaviour_cloning_names_the_bad_flag(case, a_file, tmp_path, capsys):
    argv = ["--dataset", "steamtemp/SupercriticalFSH/mpc_linear-v0", "--out", str(tmp_path / "o")]
    if case == "seed":
        argv += ["--seed", str(2**70)]
    elif case == "out":
        argv[3] = str(a_file)
    else:
        argv += ["--data-dir", str(a_file)]
    with pytest.raises(SystemExit) as exc:
        behaviour_cloning.main(argv)
    err = capsys.readouterr().err
    flag = "--" + case.replace("_", "-")
    assert exc.value.code == 2 and f"argument {flag}" in err and "Traceback" not in err, err
    assert not (tmp_path / "o").exists()


def test_datasets_names_a_data_dir_that_is_a_file(a_file, capsys):
    with pytest.raises(SystemExit) as exc:
        datasets.main(
            ["--env", "SupercriticalFSH-v0", "--policy", "mpc_linear", "--data-dir", str(a_file)]
        )
    err = capsys.readouterr().err
    assert exc.value.code == 2 and "argument --data-dir" in err and "is a file" in err, err
