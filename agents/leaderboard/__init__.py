"""steamtemp-leaderboard: every policy on every env, scenario and seed (docs/leaderboard.md).

The command line and its outputs are described in :mod:`agents.leaderboard.cli`. Modules,
each importing only those listed before it:

- ``mismatch``: the model-mismatch variants and the robustness column;
- ``summary``: leaderboard.json's summary (scores, ranks, admissibility) from the rows;
- ``report``: leaderboard.md and the console's headline table from the summary;
- ``plots``: the score and profile figures, with the colours every figure shares;
- ``trends``: the trend figure of one plant and scenario;
- ``records``: episodes.jsonl, read back and repaired after a crash;
- ``plan``: the flags checked, the envs built and the fingerprints, before anything runs;
- ``episodes``: one policy on one env and scenario for several seeds, as rows;
- ``backends``: local worker processes or Ray tasks, with the progress bar;
- ``outputs``: leaderboard.json, leaderboard.md and plots/ rebuilt from episodes.jsonl;
- ``cli``: the argument parser and :func:`main`.
"""

__all__ = ["main"]


def main(argv: list[str] | None = None) -> None:
    """The ``steamtemp-leaderboard`` command (:func:`agents.leaderboard.cli.main`), imported
    when called: ``python -m agents.leaderboard.<module>`` then runs a module the package
    has not already imported."""
    from agents.leaderboard.cli import main as run

    run(argv)
