"""pytest plugin (entry point ``pytest11``, loaded wherever steamtemp_gym is installed):
registers the ``slow`` mark that :func:`~steamtemp_gym.testing.parametrize_with_checks` puts
on slow checks, so a test suite using it runs with ``--strict-markers`` and without
``PytestUnknownMarkWarning``; ``-m "not slow"`` leaves those checks out."""

from __future__ import annotations

#: The mark's line in ``pytest --markers``.
SLOW = "slow: a long contract check of steamtemp_gym.testing (deselect with -m 'not slow')"


def pytest_configure(config) -> None:
    """Register the ``slow`` mark."""
    config.addinivalue_line("markers", SLOW)
