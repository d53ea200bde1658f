"""``mt-accuracy fleet`` on a real Dask cluster of 2 worker processes, over bags the virtual
machine recorded: several machines and days, one bag truncated, one foreign.

What is asserted: every machine-day is diagnosed in a worker process (not the client)
with the same figures ``mt-accuracy check`` gives on that bag alone; the machine whose
guideway wears is the one ranked first and the only one drifting; the effect every
machine has is named common to all; the truncated and the foreign bag fail their own
task only, each named with its reason, in the output, the JSON and the report.
"""
from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import pytest

DRIFT = {"time_constant_s": 60, "rise_k": 4.0, "beta_m_per_k": [1.5e-6, 6.0e-6, 3.0e-6]}


@pytest.fixture(scope="module")
def plant(tmp_path_factory, data_dir=Path(__file__).resolve().parent.parent / "data"):
    from mt_accuracy_ros.sim.fleet import VirtualMachine, write_fleet

    root = tmp_path_factory.mktemp("plant")
    machines = [
        # its Y guideway wears: 8 um more at the TCP each day
        VirtualMachine("hmc-a", 11, {"structural_thermal_drift": DRIFT,
                                     "guideway_deterioration": {"axis": "Y", "start_m": -0.16,
                                                                "end_m": 0.0,
                                                                "tcp_change_m": 4e-6}},
                       grows={("guideway_deterioration", "tcp_change_m"): 8e-6}),
        VirtualMachine("hmc-b", 12, {"structural_thermal_drift": DRIFT,
                                     "ballscrew_pitch": {"axis": "X", "pitch_m": 0.01,
                                                         "amplitude_m": 3e-6,
                                                         "phase_rad": 0.7}}),
        VirtualMachine("hmc-c", 13, {"structural_thermal_drift": DRIFT})]
    bags = write_fleet(root, machines, {"hmc-a": 4, "hmc-b": 3, "hmc-c": 2})
    truncated = next(bags[-1].glob("*.mcap"))          # hmc-c's second day: a killed recorder
    truncated.write_bytes(truncated.read_bytes()[: truncated.stat().st_size // 2])
    shutil.copytree(data_dir / "rosbag2_samples" / "talker", root / "cell-7" / "talker")
    return root, bags


def _days(summary, machine):
    return {d["day"]: d for d in summary["machines"][machine]["days"]}


def test_a_plant_on_a_local_cluster_of_two_processes(plant, tmp_path, capsys):
    from mt_accuracy_ros.cli import main
    from mt_accuracy_ros.commands.check import check_bag

    root, bags = plant
    code = main(["fleet", str(root), "--workers", "2", "--quiet", "--json",
                 str(tmp_path / "fleet.json"), "--report", str(tmp_path / "fleet.html")])
    out = capsys.readouterr().out
    assert code == 0
    summary = json.loads((tmp_path / "fleet.json").read_text())
    assert summary["ran_on"]["scheduler"] == "local cluster"
    assert summary["ran_on"]["workers"] == 2 and summary["ran_on"]["tasks_s"] > 0
    assert summary["tasks"] == 4 + 3 + 2 + 1 and summary["machine_count"] == 4
    # every day ran in a worker process, not in the client
    assert all(r["worker"] and int(r["worker"].rsplit(":", 1)[1]) != os.getpid()
               for r in summary["results"] if r["rmse_m"] is not None)
    assert [len(summary["machines"][m]["days"]) for m in ("hmc-a", "hmc-b", "hmc-c")] == \
        [4, 3, 1]

    # gathered figures equal check's on that bag alone, in this process
    day = _days(summary, "hmc-b")["2026-11-17"]
    alone = check_bag(bags[5], "demo", [], 3, "", 0.05)
    assert day["rmse_m"] == pytest.approx(alone["baseline_rmse"], rel=1e-12)
    assert day["final_rmse_m"] == pytest.approx(alone["final_rmse"], rel=1e-12)
    assert day["named"] == sorted(n["name"] for n in alone["named"])

    # the wearing machine drifts, ranked first; the others do not
    ranking = summary["drift_ranking"]
    assert ranking[0]["machine"] == "hmc-a" and ranking[0]["drifting"]
    assert not any(item["drifting"] for item in ranking[1:])
    a_days = [d["rmse_m"] for d in summary["machines"]["hmc-a"]["days"]]
    assert a_days == sorted(a_days) and a_days[-1] > 1.5 * a_days[0]
    assert "1. hmc-a: +" in out and "DRIFTING" in out

    # the column's thermal drift every machine has: common to all three
    common = {c["effect"]: c["machines"] for c in summary["common_effects"]}
    assert common["structural_thermal_drift:column"] == ["hmc-a", "hmc-b", "hmc-c"]
    assert "common: structural_thermal_drift:column on 3 machines" in out

    # the truncated and the foreign bag: their own tasks failed, reasons given
    refused = {(r["machine"], Path(r["file"]).name): r["reason"] for r in summary["refused"]}
    assert set(refused) == {("hmc-c", "2026-11-17"), ("cell-7", "talker")}
    assert "is a truncated MCAP file" in refused[("hmc-c", "2026-11-17")]
    assert "no /reference/tcp_error topic" in refused[("cell-7", "talker")]
    assert summary["machines"]["cell-7"]["trend"] is None
    assert "refused: hmc-c 2026-11-17 2026-11-17: " in out
    assert "refused: cell-7 " in out and "no /reference/tcp_error topic" in out
    assert summary["failed_tasks"] == 2

    # the report: its figure, the ranking, the shared effect, the refusals
    from browser import validate_html

    validate_html(tmp_path / "fleet.html")
    assert (tmp_path / "fleet_over_time.png").stat().st_size > 10_000
    html = (tmp_path / "fleet.html").read_text()
    for text in ("Machines that drift, ranked", "Effects common to many machines",
                 "Refused data", "is a truncated MCAP file", "Machine hmc-a"):
        assert text in html
    titles = [s["title"] for s in summary["report"]["sections"]]
    assert titles[:4] == ["The fleet", "Machines that drift, ranked",
                          "Effects common to many machines", "Refused data"]


def test_an_existing_scheduler_and_a_manifest_with_a_survey(plant, tmp_path):
    """``--scheduler ADDRESS``: the tasks go to a cluster started elsewhere (here, by the
    test); a manifest names the machines, a model of their own and a survey's column map."""
    from distributed import LocalCluster

    from mt_accuracy_ros.commands.fleet import run_fleet
    from studies.foreign_machine import make_trial
    from studies.survey_files import write_logger_survey

    root, _ = plant
    trial = make_trial("kidani_hmc", ("ballscrew_pitch",), 1000, readings=300)
    write_logger_survey(trial, tmp_path / "survey_2026-11-20.csv", tmp_path / "map.yaml")
    (tmp_path / "fleet.yaml").write_text(
        "machines:\n"
        f"  line-1: {{model: demo, data: ['{root}/hmc-b/2026-11-1[67]']}}\n"
        "  lab: {model: '{machine: kidani_hmc}', columns: map.yaml,\n"
        "        data: [survey_*.csv]}\n")
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster:
        summary = run_fleet([str(tmp_path / "fleet.yaml")], scheduler=cluster.scheduler_address,
                            auto=2, progress=False)
    assert summary["ran_on"]["scheduler"] == cluster.scheduler_address
    assert summary["ran_on"]["workers"] == 2
    assert not summary["refused"]
    assert list(_days(summary, "line-1")) == ["2026-11-16", "2026-11-17"]
    (survey_day,) = summary["machines"]["lab"]["days"]
    assert survey_day["day"] == "2026-11-20" and survey_day["readings"] == 300
    (expected,) = trial.hidden[0].accepted
    assert expected in survey_day["named"]


def test_the_command_says_bad_input_in_one_line_and_fails_when_nothing_was_read(
        tmp_path, capsys):
    """A manifest with an unknown key: one line on stderr, exit 2, no cluster started. A
    fleet whose every file is refused: the refusals are printed and the exit status is 1
    (nothing was diagnosed)."""
    from mt_accuracy_ros.cli import main

    (tmp_path / "fleet.yaml").write_text("machines: {m1: {data: [x], colour: red}}\n")
    assert main(["fleet", str(tmp_path / "fleet.yaml"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("mt-accuracy fleet: ") and "unknown key 'colour'" in err
    assert "\n" not in err

    data = Path(__file__).resolve().parent.parent / "data" / "rosbag2_samples" / "talker"
    shutil.copytree(data, tmp_path / "plant" / "cell-9" / "talker")
    code = main(["fleet", str(tmp_path / "plant"), "--workers", "1", "--quiet"])
    out, err = capsys.readouterr()
    assert code == 1, err
    assert "fleet: 1 machines, 1 machine-days on 1 workers" in out
    assert "refused: cell-9 " in out and "no /reference/tcp_error topic" in out


def test_a_task_says_where_its_time_went(plant):
    """A machine-day run in this process (the worker's function, no cluster): its figures
    are ``check``'s on the same bag, and its time split - reading, search, result - are
    parts of the task's own time, the search measured by the check itself."""
    from mt_accuracy_ros.commands.check import check_bag
    from mt_accuracy_ros.commands.fleet import diagnose_day

    _, bags = plant
    bag = bags[0]
    task = {"machine": "hmc-a", "day": "d0", "day_number": 0.0, "auto": 3,
            "min_reduction": 0.05,
            "datasets": [{"path": str(bag), "kind": "bag", "model": None, "columns": None,
                          "machine_file": None}]}
    day = diagnose_day(task)
    expected = check_bag(bag, "demo", [], 3, "", 0.05)
    assert day["files"][0]["ok"] and day["rmse_m"] == pytest.approx(expected.baseline_rmse,
                                                                   rel=1e-12)
    split = day["split"]
    assert set(split) == {"reading_s", "search_s", "result_s"}
    assert all(value >= 0.0 for value in split.values())
    assert split["search_s"] > 0.0 and expected.seconds["search"] > 0.0
    assert sum(split.values()) <= day["seconds"]
    assert "seconds" not in expected.to_json()
