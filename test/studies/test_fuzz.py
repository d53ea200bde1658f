"""A fast, derandomised sample of the fuzzing (bench/fuzz.py runs 10,000 cases per target):
bad input to any loader or message handler raises only the package's own errors."""
from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings

from studies import fuzz_targets

SAMPLE = settings(max_examples=60, derandomize=True, deadline=None, database=None,
                  suppress_health_check=list(HealthCheck))


def _run(strategy, check) -> None:
    SAMPLE(given(strategy)(check))()


@pytest.mark.parametrize("target", fuzz_targets.loader_targets(), ids=lambda t: t.name)
def test_loaders_raise_only_package_errors(target):
    _run(target.strategy, target.check)


@pytest.fixture(scope="module")
def harness():
    nodes = fuzz_targets.NodeHarness()
    yield nodes
    nodes.close()


@pytest.mark.parametrize("name", ["estimator.scales", "estimator.temperatures",
                                  "broadcaster.scales", "broadcaster.temperatures",
                                  "broadcaster.profiles", "broadcaster.model",
                                  "monitor.references", "monitor.model_parameter"])
def test_message_handlers_raise_only_package_errors(harness, name):
    strategy, check = fuzz_targets.message_targets(harness)[name]
    _run(strategy, check)


def test_the_property_can_fail():
    # Not vacuous: an exception of another type escapes the check.
    def broken(_):
        raise TypeError("deep inside numpy")

    with pytest.raises(TypeError):
        fuzz_targets._only_package_errors(broken, None)
