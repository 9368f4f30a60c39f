"""Agents: the evaluation loop, the leaderboard CLI, training and the trained-agent zoo.

``agents.load(env_id, algo) -> Policy`` loads a shipped trained agent from
``agents/zoo/`` (ValueError listing what is shipped otherwise): the SB3 model with its
observation pipeline (controller memory, normalization statistics; agents/policy.py),
as ``steamtemp-train`` (agents/train.py) wrote it. A trained agent's files elsewhere
(``steamtemp-train --out``, an RL Zoo run) are found by ``agents.files.find``. An agent
may have several independent training runs (``agents.runs``; ``load(..., run=k)``).
"""

from __future__ import annotations

from pathlib import Path

ZOO = Path(__file__).with_name("zoo")

#: What kind of agent each algorithm's entry trains: the question "does RL beat the
#: controllers" has one answer per kind.
KINDS = {
    "ppo": "model-free",
    "sac": "model-free",
    "td3": "model-free",
    "trpo": "model-free",
    "recurrentppo": "model-free",
    "sac_caps": "model-free",
    "ppo_privileged": "model-free, critic trained on privileged signals",
    "ppo_residual": "residual over cascade_pi_ff",
    "ppo_residual_pi": "residual over cascade_pi_ff_tuned",
    "ppo_residual_mpc": "residual over mpc_linear",
    "ppo_imitation_mpc": "imitation of mpc_linear",
    "ppo_imitation_mpc_rl": "imitation of mpc_linear, then RL",
    "bc": "offline: behaviour cloning of mpc_linear's noisy dataset",
}


def kind(algo: str) -> str:
    """The kind of agent ``algo`` trains (:data:`KINDS`); "trained agent" for another."""
    return KINDS.get(algo, "trained agent")


def shipped() -> list[tuple[str, str]]:
    """(env_id, algo) pairs of the shipped trained agents (a model .zip with its .json),
    each pair once however many training runs it has (:func:`runs`)."""
    # lazy: agents.files would add 0.2 s and 75 modules to every agents.* import
    from agents.files import zoo_runs

    return list(zoo_runs(ZOO))


def runs(env_id: str, algo: str, zoo: Path | str | None = None) -> list[int]:
    """The training runs of a trained agent in ``zoo`` (default: the shipped zoo), sorted:
    ``[0]`` for a single file without a run index (agents/files.py); ``[]`` for none."""
    # lazy: agents.files would add 0.2 s and 75 modules to every agents.* import
    from agents.files import zoo_runs

    return zoo_runs(Path(zoo) if zoo is not None else ZOO).get((env_id, algo), [])


def load(env_id: str, algo: str, zoo: Path | str | None = None, run: int = 0):
    """A trained agent as a Policy: ``predict`` takes the env's raw observation.

    Args:
        env_id: Registered id.
        algo: Algorithm name of the file (``ppo``, ``sac``, ``td3``, ``ppo_residual``,
            ``ppo_residual_pi``, ``ppo_residual_mpc``, ``ppo_imitation_mpc``,
            ``ppo_imitation_mpc_rl``, ``recurrentppo``, ``sac_caps``).
        zoo: Directory holding ``<env>__<algo>.zip`` and ``.json``, or the run-indexed
            ``<env>__<algo>__run<k>`` files (default: the shipped zoo).
        run: Which training run (0: ``__run0``, else the file without a run index).

    Raises:
        ValueError: no such agent or run (listing the shipped ones for the shipped zoo).
    """
    # lazy: agents.files would add 0.2 s and 75 modules to every agents.* import
    from agents.files import steamtemp_files

    if zoo is None and run not in runs(env_id, algo):
        raise ValueError(
            f"no trained agent {algo!r} run {run} shipped for {env_id!r}; shipped: "
            f"{ {f'{e} {a}': runs(e, a) for e, a in shipped()} }"
        )
    return steamtemp_files(Path(zoo) if zoo is not None else ZOO, env_id, algo, run).load()
