"""``mt-accuracy model``: the live model changed from a terminal, against a real monitor."""
from __future__ import annotations

import subprocess
import sys

from mt_accuracy_ros.commands.processes import start_node


def _cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mt_accuracy_ros.cli", "model", *args],
                          capture_output=True, text=True, timeout=120)


def test_model_remove_show_and_refusals_on_a_running_monitor(tmp_path):
    model = tmp_path / "model.yaml"
    model.write_text("machine: kidani_hmc\neffects:\n  geometric: {}\n"
                     "  squareness: {errors_rad: {EC0Y: 1.0e-5}}\n")
    monitor = start_node("model_monitor", {"model": str(model)}, quiet=True)
    try:
        shown = _cli("show", "--timeout", "30")
        assert shown.returncode == 0, shown.stderr
        assert shown.stdout.startswith("version 1: start")
        removed = _cli("remove", "squareness")
        assert removed.returncode == 0 and "accepted" in removed.stdout, removed.stderr
        shown = _cli("show", "--timeout", "30")
        assert "version 2: removed squareness (user)" in shown.stdout
        assert "effects: geometric\n" in shown.stdout
        # Removing what the model does not hold: one line, exit 2, the model unchanged.
        again = _cli("remove", "squareness")
        assert again.returncode == 2
        assert "not in the model (it holds geometric)" in again.stderr
        assert len(again.stderr.strip().splitlines()) == 1
        # Adding needs reference readings to fit to; an unknown effect is named.
        early = _cli("add", "structural_thermal_drift")
        assert early.returncode == 2 and "reference readings" in early.stderr, early.stderr
        unknown = _cli("add", "flux_capacitor")
        assert unknown.returncode == 2 and "unknown effect 'flux_capacitor'" in unknown.stderr
        # Refitting (no names: every fitted effect) needs readings too: one line, exit 2.
        refit = _cli("refit")
        assert refit.returncode == 2, refit.stderr
        assert "refit all refused: cannot refit: only 0 reference readings" in refit.stderr
        assert monitor.popen.poll() is None
    finally:
        monitor.stop()


def test_model_commands_without_a_monitor_say_so(tmp_path):
    result = _cli("remove", "squareness", "--monitor", "/nobody_here", "--timeout", "2")
    assert result.returncode == 2 and "not available" in result.stderr, result.stderr
