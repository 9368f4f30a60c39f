"""Contract checks for plants, variants, scenarios and controllers.

Every contract the suite promises is a named check function taking an env id (or an env
factory), or a policy and an env id, and raising an AssertionError that says what failed
and how to reproduce it. The project's own tests run exactly these (tests/test_envs.py,
tests/test_baselines.py); ``steamtemp-check`` runs them outside pytest. See
docs/checking.md. Modelled on scikit-learn's ``sklearn.utils.estimator_checks``
(``check_estimator``, ``parametrize_with_checks``).

    from steamtemp_gym.testing import parametrize_with_checks

    @parametrize_with_checks(ids=["steamtemp/SupercriticalFSH-v0"], policies=["cascade_pi"])
    def test_contract(env_id, check):
        check(env_id)
"""

from steamtemp_gym.testing.env_checks import (
    check_bad_inputs_rejected,
    check_determinism,
    check_gymnasium_env,
    check_info_keys_and_units,
    check_named_scenarios_run_to_end,
    check_physical_under_random_and_corner_runs,
    check_pickle_and_deepcopy,
    check_render_frame,
    check_sb3_env,
    check_spaces_match_signals,
)
from steamtemp_gym.testing.policy_checks import (
    check_actions_in_bounds,
    check_bad_observations_rejected,
    check_batched_equals_unbatched,
    check_completes_a_scenario,
    check_completes_every_scenario,
    check_policy_determinism,
    check_predict_signature,
    check_reset_clears_state,
)
from steamtemp_gym.testing.runner import (
    CHECK_NAMES,
    ENV_CHECKS,
    POLICY_CHECKS,
    SLOW_CHECKS,
    BoundCheck,
    Result,
    check_env_id,
    check_policy,
    parametrize_with_checks,
)
from steamtemp_gym.testing.subjects import CheckSkipped
from steamtemp_gym.testing.vector_checks import check_vector_env_matches_single_env

__all__ = [
    "CHECK_NAMES",
    "ENV_CHECKS",
    "POLICY_CHECKS",
    "SLOW_CHECKS",
    "BoundCheck",
    "CheckSkipped",
    "Result",
    "check_actions_in_bounds",
    "check_bad_inputs_rejected",
    "check_bad_observations_rejected",
    "check_batched_equals_unbatched",
    "check_completes_a_scenario",
    "check_completes_every_scenario",
    "check_determinism",
    "check_env_id",
    "check_gymnasium_env",
    "check_info_keys_and_units",
    "check_named_scenarios_run_to_end",
    "check_physical_under_random_and_corner_runs",
    "check_pickle_and_deepcopy",
    "check_policy",
    "check_policy_determinism",
    "check_predict_signature",
    "check_render_frame",
    "check_reset_clears_state",
    "check_sb3_env",
    "check_spaces_match_signals",
    "check_vector_env_matches_single_env",
    "parametrize_with_checks",
]
