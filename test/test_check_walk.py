"""`check LOG --walk-forward PERIOD`: the log replayed in time, against plain re-implementations;
a model judged on a regime its training rows never held says so."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from mt_accuracy_ros.cli import main
from mt_accuracy_ros.commands.check_log import check_csv

STEP_S = 60.0


def _lag(drive: np.ndarray, tau_s: float) -> np.ndarray:
    """A first-order lag of ``drive`` at :data:`STEP_S`."""
    a = np.exp(-STEP_S / tau_s)
    out = np.zeros_like(drive)
    for k in range(1, drive.size):
        out[k] = a * out[k - 1] + (1.0 - a) * drive[k]
    return out


def _log(path: Path, power: np.ndarray, seed: int = 1) -> Path:
    """A spindle's heat ``power`` (per row) seen by three sensors (two on its thermal path,
    lagging it by 30 min and 1.5 h; one off it, following the room) and a displacement
    lagging it by 50 min [um]."""
    rng = np.random.default_rng(seed)
    n = power.size
    t = np.arange(n) * STEP_S
    t1 = 20 + 15 * _lag(power, 1800) + rng.normal(0, 0.03, n)
    t2 = 20 + 8 * _lag(power, 5400) + rng.normal(0, 0.03, n)
    t3 = 20 + 0.5 * np.sin(t / 20000) + rng.normal(0, 0.03, n)
    d = 30 * _lag(power, 3000) + rng.normal(0, 0.3, n)
    rows = "\n".join(",".join(f"{v:.4f}" for v in row) for row in zip(t, t1, t2, t3, d))
    path.write_text("time_s,t1_C,t2_C,t3_C,d_um\n" + rows + "\n")
    return path


def _heat_then_idle(n: int = 600) -> np.ndarray:
    """Full power for a third, a third of the power for a quarter, then off."""
    k = np.arange(n)
    return np.where(k < n // 3, 1.0, np.where(k < n // 3 + n // 4, 0.3, 0.0))


ARGS = ["--target", "d_um", "--auto", "2", "--uncertainty-um", "0.6"]


@pytest.fixture(scope="module")
def walked(tmp_path_factory):
    """The walk-forward of a heating / part-load / cooling log, 100 min periods."""
    directory = tmp_path_factory.mktemp("walk")
    log = _log(directory / "log.csv", _heat_then_idle())
    json_path = directory / "s.json"
    code = main(["check", str(log), *ARGS, "--walk-forward", "100min", "--json",
                 str(json_path)])
    return log, code, json.loads(json_path.read_text())


def test_the_baselines_walk_as_a_plain_loop_fits_them(walked):
    log, code, summary = walked
    assert code == 0
    walk = summary["walk_forward"]
    data = np.loadtxt(log, delimiter=",", skiprows=1)
    temperatures, target = data[:, 1:4], data[:, 4] * 1e-6
    assert walk["methods"] == ["workbench", "constant", "least squares on every input",
                               "no model"]
    assert [(p["period"]["start"], p["period"]["stop"]) for p in walk["periods"]] == \
        [(100 * k, 100 * (k + 1)) for k in range(1, 6)]
    pooled = {"constant": 0.0, "least squares": 0.0, "no model": 0.0}
    for figures in walk["periods"]:
        a, b = figures["period"]["start"], figures["period"]["stop"]
        # Least squares on every sensor's rise over its first reading, and an offset.
        design = np.column_stack([np.ones(a), temperatures[:a] - temperatures[0]])
        gains = np.linalg.lstsq(design, target[:a], rcond=None)[0]
        ahead = np.column_stack([np.ones(b - a), temperatures[a:b] - temperatures[0]])
        errors = {"constant": target[a:b] - target[:a].mean(),
                  "least squares": target[a:b] - ahead @ gains,
                  "no model": target[a:b] - target[0]}
        for name, error in errors.items():
            key = "least squares on every input" if name == "least squares" else name
            assert figures["rmse_m"][key] == pytest.approx(np.sqrt(np.mean(error ** 2)),
                                                           rel=1e-9)
            pooled[name] += float(np.sum(error ** 2))
    for name, total in pooled.items():
        key = "least squares on every input" if name == "least squares" else name
        assert walk["pooled_m"][key] == pytest.approx(np.sqrt(total / 500), rel=1e-9)


def test_each_period_s_workbench_figure_is_a_check_of_the_log_cut_at_its_end(walked, tmp_path):
    """The workbench at a period's end is the check of the rows so far: the same search on
    the same rows, judged on the next period (the held-out rows of the log cut there)."""
    log, _, summary = walked
    lines = log.read_text().splitlines()
    for figures in summary["walk_forward"]["periods"][::2]:
        a, b = figures["period"]["start"], figures["period"]["stop"]
        cut = tmp_path / f"cut{b}.csv"
        cut.write_text("\n".join(lines[:b + 1]) + "\n")
        result = check_csv(cut, "d_um", "time_s", ["*"], [], [], 2, (a + 0.5) / b, 0.05, [],
                           uncertainty_m=0.6e-6)
        assert result["train_rows"] == a
        assert figures["rmse_m"]["workbench"] == pytest.approx(result["final_rmse"], rel=1e-9)
        assert figures["described"]["workbench"] == (", ".join(result["added"]) or
                                                     "nothing added")


def test_the_walk_is_printed_per_period_and_pooled(walked, capsys, tmp_path):
    log, _, summary = walked
    assert main(["check", str(log), *ARGS, "--walk-forward", "100min"]) == 0
    out, err = capsys.readouterr()
    walk = summary["walk_forward"]
    assert "walk-forward, each 100min predicted by a fit on every row before it (RMS, um; " \
        "first fit on 100 rows):" in out
    pooled = "  ".join(f"{walk['pooled_m'][m] * 1e6:12.4g}" for m in walk["methods"])
    assert f"  {'pooled':>18s} {500:6d}  {pooled}" in out
    wins = all(walk["pooled_m"]["workbench"] < walk["pooled_m"][m]
               for m in ("constant", "least squares on every input"))
    assert ("the workbench beats both" in out) == wins
    # Progress on stderr, one line per period.
    assert err.count("walk-forward ") == 5 and "walk-forward 5/5: " in err


@pytest.mark.parametrize("period, words", [("4x", "give a period of data time"),
                                           ("run", "needs runs")])
def test_a_walk_that_cannot_be_made_is_refused_in_one_line_nothing_written(
        walked, tmp_path, capsys, period, words):
    log, _, _ = walked
    json_path = tmp_path / "s.json"
    assert main(["check", str(log), *ARGS, "--walk-forward", period, "--json",
                 str(json_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert words in err and "--walk-forward" in err and len(err.splitlines()) == 1
    assert not json_path.exists()


def test_a_model_trained_on_heating_alone_and_judged_on_cooling_says_so(tmp_path):
    """The power is on for the first 60 % of the rows, the training rows are the first half:
    the held-out rows cool, which the training rows never did. The check names the regime
    it never saw and how far the model's inputs leave their training range there."""
    n = 500
    power = (np.arange(n) < 0.6 * n).astype(float)
    log = _log(tmp_path / "log.csv", power, seed=3)
    result = check_csv(log, "d_um", "time_s", ["*"], [], [], 2, 0.5, 0.05, [],
                       uncertainty_m=0.6e-6)
    (note,) = [n for n in result["notes"] if n.startswith("the held-out rows hold")]
    # The power goes off at row 300: the trend's window finds it within a few rows.
    start = int(note.split("(cooling rows ", 1)[1].split("-", 1)[0])
    assert abs(start - 301) <= 10
    # The sensors settle within the first 250 rows: heating, then a dwell.
    assert "which the training rows never held (they held heating, dwell)" in note
    chosen = next(e for e in result["model_contest"] if e["chosen"])
    assert f"leave their training range by {chosen['held_out_range_excess']:.2g} of its " \
        "span there" in note
    # The room's sensor, off the thermal path, goes beyond what it read in training: named.
    assert "on the held-out rows t3_C reached" in note
    # Inside the training rows, each regime was predicted from the other.
    assert [b["regime"] for b in chosen["cross_regime_blocks"]] == ["heating", "dwell"]


def test_a_regimes_rows_are_named_as_the_file_numbers_them_when_rows_were_left_out(tmp_path):
    """Twenty rows early in the log read an impossible temperature: the sensors' judge sets
    those readings aside and the observations leave the rows out, and the cooling that
    starts at the file's data row 301 is still named from there (not twenty rows early,
    as counting the rows kept would)."""
    n = 500
    power = (np.arange(n) < 0.6 * n).astype(float)
    log = _log(tmp_path / "log.csv", power, seed=3)
    lines = log.read_text().splitlines()
    for k in range(50, 70):     # data rows 51-70 (file line k + 1 after the header)
        values = lines[k + 1].split(",")
        values[1] = "300.0"     # t1_C
        lines[k + 1] = ",".join(values)
    log.write_text("\n".join(lines) + "\n")
    result = check_csv(log, "d_um", "time_s", ["*"], [], [], 2, 0.5, 0.05, [],
                       uncertainty_m=0.6e-6)
    (note,) = [n for n in result["notes"] if n.startswith("the held-out rows hold")]
    start = int(note.split("(cooling rows ", 1)[1].split("-", 1)[0])
    assert abs(start - 301) <= 10, note


def test_when_no_regime_tells_the_models_apart_the_forward_figure_decides(tmp_path,
                                                                          monkeypatch):
    """The heating-then-cooling log: every regime tells models apart, and the cross-regime
    figure pools them all. With a constant made to predict every regime perfectly, no
    regime tells: the note says so, no regime decides, each contestant's score is its
    forward figure, and the contest's winner is the one the forward figures choose."""
    import mt_accuracy_ros.commands.check_log as check_log

    n = 500
    log = _log(tmp_path / "log.csv", (np.arange(n) < 0.6 * n).astype(float), seed=3)
    args = (log, "d_um", "time_s", ["*"], [], [], 3, 0.5, 0.05, [])
    telling = check_csv(*args, uncertainty_m=0.6e-6)
    assert not any(n.startswith("no model predicts") for n in telling["notes"])
    for entry in telling["model_contest"]:
        told = [b for b in entry["cross_regime_blocks"] if b["decides"]]
        assert told and len(told) == len(entry["cross_regime_blocks"])
        pooled = np.sqrt(sum(b["rmse"] ** 2 * b["judged_rows"] for b in told) /
                         sum(b["judged_rows"] for b in told))
        assert entry["cross_regime_rmse"] == pytest.approx(pooled, rel=1e-12)

    blocks = check_log.regime_blocks

    def perfect_constant(terms, *rest):
        out = blocks(terms, *rest)
        return [dict(b, rmse=0.0) for b in out] if not terms else out

    monkeypatch.setattr(check_log, "regime_blocks", perfect_constant)
    untold = check_csv(*args, uncertainty_m=0.6e-6)
    assert any(n.startswith("no model predicts the training regimes heating, dwell") and
               n.endswith("(the forward figure does)") for n in untold["notes"])
    scores = {}
    for entry in untold["model_contest"]:
        assert entry.get("cross_regime_rmse") is None
        assert not any(b["decides"] for b in entry["cross_regime_blocks"])
        assert entry["score"] == entry["forward_rmse"]
        scores[entry["name"]] = entry["score"]
    excess = {e["name"]: e["range_excess"] for e in untold["model_contest"]}
    chosen = next(e["name"] for e in untold["model_contest"] if e["chosen"])
    assert chosen == check_log.contest_winner(scores, excess)
