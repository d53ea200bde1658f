"""Issue 39: a worker process that cannot start falls back to a thread - and says so (the
nodes put the reason on /diagnostics as a WARN), never silently."""
from __future__ import annotations

import concurrent.futures

import pytest


@pytest.mark.parametrize("module, factory, what", [
    ("mt_accuracy_ros.nodes._search_worker", "search_pool", "the diagnosis runs in a thread"),
    ("mt_accuracy_ros.nodes._model_inputs", "_gate_pool", "the model gate runs in a thread"),
])
def test_a_pool_whose_process_cannot_start_is_a_thread_that_says_why(monkeypatch, module,
                                                                      factory, what):
    import importlib

    def refuse(*args, **kwargs):
        raise OSError("no more processes (test)")

    monkeypatch.setattr(concurrent.futures, "ProcessPoolExecutor", refuse)
    pool = getattr(importlib.import_module(module), factory)()
    try:
        assert isinstance(pool, concurrent.futures.ThreadPoolExecutor)
        assert pool.fallback_reason.startswith(what)
        assert "no more processes (test)" in pool.fallback_reason
        assert pool.submit(int, "7").result(timeout=10) == 7
    finally:
        pool.shutdown(wait=True)


def test_the_monitor_and_the_broadcaster_put_the_fallback_on_diagnostics():
    """Both nodes hand the reason to their health's WARN (read from the source: starting
    a node whose pool cannot start is what the test above stands in for)."""
    from pathlib import Path

    import mt_accuracy_ros

    root = Path(mt_accuracy_ros.__file__).parent / "nodes"
    monitor = (root / "model_monitor.py").read_text()
    inputs = (root / "_model_inputs.py").read_text()
    assert "self.health.warn(self._pool.fallback_reason)" in monitor
    assert monitor.count("self._say_fallback()") == 2
    assert "health.warn(self._pool.fallback_reason)" in inputs
