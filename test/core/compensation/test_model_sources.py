"""Where a model may come from: a network-named model opens no file outside the node's
model_dir, no file is read unless it is a regular one of bounded size, and no error
quotes a file's content (issue 29, item 1)."""
from __future__ import annotations

import os
import threading

import pytest

from mt_accuracy_ros.core.compensation.error_model import resolve_model
from mt_accuracy_ros.core.errors import MachineDescriptionError, ParameterError
from mt_accuracy_ros.core.kinematics.machine import BUNDLED_MACHINES, load_machine
from mt_accuracy_ros.core.inputs.safe_files import MAX_DESCRIPTION_BYTES

SECRET = "hunter2"


@pytest.fixture()
def files(tmp_path):
    """A model directory with a machine and a model in it, and files outside it."""
    model_dir = tmp_path / "models"
    model_dir.mkdir()
    (model_dir / "cell3.yaml").write_text((BUNDLED_MACHINES / "kidani_hmc.yaml").read_text())
    (model_dir / "mine.yaml").write_text("machine: cell3\neffects: {squareness: {}}\n")
    outside = tmp_path / "elsewhere"
    outside.mkdir()
    (outside / "valid.yaml").write_text("machine: kidani_hmc\neffects: {squareness: {}}\n")
    (outside / "secret.yaml").write_text(f'user: root\npassword: "{SECRET}\n')
    (model_dir / "link.yaml").symlink_to(outside / "valid.yaml")
    fifo = tmp_path / "fifo.yaml"
    os.mkfifo(fifo)
    return {"dir": model_dir, "outside": outside, "fifo": fifo}


@pytest.mark.parametrize("text", ["/etc/passwd", "/proc/self/environ", "../models/mine.yaml",
                                  "{machine: ../../../../etc/passwd}",
                                  "{machine: /etc/hostname}", "machine: ../cell3\n"])
def test_a_network_model_names_no_path(files, text):
    with pytest.raises(ParameterError, match="never a path|no bundled machine"):
        resolve_model(text, from_network=True, model_dir=files["dir"])


def test_a_network_model_reads_only_the_model_dir(files):
    model = resolve_model("mine.yaml", from_network=True, model_dir=files["dir"])
    assert "squareness" in model.effects and model.machine_source.endswith("cell3.yaml")
    inline = resolve_model("{machine: cell3.yaml, effects: {}}", from_network=True,
                           model_dir=files["dir"])
    assert inline.machine.name == load_machine("kidani_hmc").name
    # A valid model anywhere else on disk is not reachable by its path ...
    valid = str(files["outside"] / "valid.yaml")
    with pytest.raises(ParameterError, match="never a path"):
        resolve_model(valid, from_network=True, model_dir=files["dir"])
    # ... nor through a link in the model directory.
    with pytest.raises(ParameterError, match="links outside"):
        resolve_model("link.yaml", from_network=True, model_dir=files["dir"])
    # Without a model_dir: inline YAML and bundled names only.
    with pytest.raises(ParameterError, match="none configured"):
        resolve_model("mine.yaml", from_network=True)
    assert resolve_model("demo", from_network=True).machine.name
    # The command line keeps its paths.
    assert "squareness" in resolve_model(valid).effects


def test_the_start_up_machine_may_be_named_by_path(files):
    machine = str(files["dir"] / "cell3.yaml")
    text = f"{{machine: {machine}, effects: {{}}}}"
    with pytest.raises(ParameterError, match="never a path"):
        resolve_model(text, from_network=True)
    assert resolve_model(text, from_network=True, trusted_machines=(machine,)).machine


def test_no_error_quotes_a_file(files):
    secret = files["outside"] / "secret.yaml"
    for call in (lambda: resolve_model(str(secret)),
                 lambda: load_machine(str(secret)),
                 lambda: resolve_model(f"{{machine: {secret}}}")):
        with pytest.raises((ParameterError, MachineDescriptionError)) as caught:
            call()
        assert SECRET not in str(caught.value) and "line" in str(caught.value), caught.value


def _finishes(call, seconds=10.0):
    """Run ``call`` in a thread: (finished in time, what it raised)."""
    outcome = []

    def run():
        try:
            call()
            outcome.append(None)
        except Exception as exc:  # noqa: BLE001 - the test inspects it
            outcome.append(exc)
    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(seconds)
    return bool(outcome), (outcome or [None])[0]


def test_special_and_huge_files_are_refused_without_reading_them(files, tmp_path):
    # A FIFO would block forever, /dev/zero fill memory: neither is a regular file.
    for path in (files["fifo"], "/dev/zero"):
        done, error = _finishes(lambda: resolve_model(str(path)))
        assert done, f"reading {path} blocked"
        assert isinstance(error, ParameterError) and "not a regular file" in str(error)
        done, error = _finishes(lambda: load_machine(f"{path}"))
        assert done and isinstance(error, MachineDescriptionError)
    big = tmp_path / "big.yaml"
    big.write_text("# padding\n" * (MAX_DESCRIPTION_BYTES // 10 + 1))
    with pytest.raises(ParameterError, match="byte limit"):
        resolve_model(str(big))


def test_a_machine_name_cannot_leave_the_bundled_directory():
    for name in ("../../../../etc/passwd", "..", "kidani_hmc/../kidani_hmc", "nope"):
        with pytest.raises(MachineDescriptionError, match="no bundled machine"):
            load_machine(name)


BIG = "1" + "0" * 1500


@pytest.mark.parametrize("expression, reason", [
    ("k * x * 9**9**9", "NaN/inf"),                 # loads in a parser, overflows in use
    (f"k * x * {BIG}", "beyond the floating-point range"),
    ("k * log(x)", "NaN/inf"),                      # x = 0 is in the travel
    ("k * x / (y - y)", "NaN/inf"),
    ("k * x * exp(60 * T_bed)", "NaN/inf"),         # overflows within the +-15 K range
])
def test_a_model_that_loads_is_a_model_that_evaluates(expression, reason):
    """Issue 29: user expressions are evaluated at load over the machine's travel and
    temperature range; what cannot be evaluated there does not load."""
    for values in ("", ", values: {k: 1.0e-3}"):
        text = (f"{{machine: kidani_hmc, effects: {{mine: {{expression: '{expression}', "
                f"parameters: [k]{values}}}}}}}")
        with pytest.raises(ParameterError, match=reason) as caught:
            resolve_model(text)
        assert "user effect 'mine'" in str(caught.value)


def test_fitted_values_are_evaluated_too():
    # Finite per unit parameter, not at the fitted value.
    text = ("{machine: kidani_hmc, effects: {mine: {expression: 'k * x * exp(30 * T_bed)', "
            "parameters: [k], values: {k: 1.0e+300}}}}")
    with pytest.raises(ParameterError, match="not finite at its fitted values"):
        resolve_model(text)
    good = resolve_model(text.replace("1.0e+300", "1.0e-200"))
    assert "mine" in good.effects


def test_check_refuses_an_overflowing_model_in_one_line(tmp_path, capsys):
    from mt_accuracy_ros.cli import main

    model = tmp_path / "bigint_model.yaml"
    model.write_text(f"machine: kidani_hmc\neffects:\n  mine:\n    expression: k * x * {BIG}\n"
                     "    parameters: [k]\n    values: {k: 1.0e-3}\n")
    survey = tmp_path / "s.csv"
    survey.write_text("t_s,x_mm,y_mm,z_mm,ex_um\n" + "".join(
        f"{i},{i % 300},{-(i % 200)},{i % 100},{0.1 * (i % 7)}\n" for i in range(60)))
    status = main(["check", str(survey), "--col", "time=t_s:s", "--col", "pos.X=x_mm:mm",
                   "--col", "pos.Y=y_mm:mm", "--col", "pos.Z=z_mm:mm", "--col",
                   "err.x=ex_um:um", "--model", str(model)])
    captured = capsys.readouterr()
    assert status == 2 and "Traceback" not in captured.err
    assert "beyond the floating-point range" in captured.err
