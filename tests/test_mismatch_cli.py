"""python -m agents.mismatch: flags checked before anything runs, and a real run's table."""

from __future__ import annotations

import re

import pytest

from agents import mismatch
from steamtemp_gym.plants import perturb

BENSON = "steamtemp/BensonSubcritical-v0"


@pytest.mark.parametrize(
    "argv, match",
    [
        (["--env", "NoSuchPlant-v0"], "--env.*not a plant with mismatch variants"),
        (["--policies", "no_such_policy"], "--policies"),
        (["--policies", ""], "--policies: empty list"),
        (["--seeds", "x"], "--seeds: invalid seed"),
        (["--seeds", "3-1"], "--seeds: empty range"),
        (["--heldout", "load_ramp_100_50"], "--heldout.*not a held-out scenario"),
        (["--heldout", "heldout:no_such"], "--heldout"),
        (["--out", "/no/such/dir/table.md"], "--out"),
    ],
)
def test_bad_flags_are_argparse_errors(argv, match, capsys):
    with pytest.raises(SystemExit) as exc:
        mismatch.main(["--env", BENSON, *argv] if argv[0] != "--env" else argv)
    assert exc.value.code == 2
    assert re.search(match, capsys.readouterr().err)


def test_a_run_writes_the_robustness_table(tmp_path, capsys):
    out = tmp_path / "table.md"
    mismatch.main(
        [
            "--env",
            "BensonSubcritical-v0",
            "--policies",
            "cascade_pi",
            "--seeds",
            "0",
            "--out",
            str(out),
        ]
    )
    text = out.read_text()
    assert text in capsys.readouterr().out
    rows = [line.split(" | ") for line in text.splitlines() if line.startswith("| cascade_pi |")]
    assert [r[1] for r in rows] == ["nominal", *perturb.mismatch(BENSON)]
    assert rows[0][3] == "1.00" and rows[0][5] == "1.00"  # nominal relative to itself
    for r in rows:
        ramp, rel = float(r[2]), float(r[3])
        assert ramp < 0 and rel == pytest.approx(ramp / float(rows[0][2]), abs=0.006)
