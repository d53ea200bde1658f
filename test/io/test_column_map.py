"""Any data logger's CSV: columns mapped to roles, units to SI, bad input named."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.errors import InputDataError, ParameterError
from mt_accuracy_ros.io.column_map import (ColumnMap, column_map_from_dict, parse_col_flags,
                                           read_mapped_csv)

MAP = {"time": {"column": "t", "unit": "min"},
       "positions": {"X": {"column": "x", "unit": "mm"}, "B": {"column": "b", "unit": "deg"}},
       "errors": {"x": {"column": "dx", "unit": "um"}},
       "temperatures": {"bed": {"column": "Tb", "unit": "degF"}, "col": {"column": "Tc",
                                                                     "unit": "K"}},
       "velocities": {"X": {"column": "f", "unit": "mm/min"}},
       "spindle_speed": {"column": "S", "unit": "rpm"},
       "uncertainty": {"value": 1.4, "unit": "um"}}


def _write(path, rows, header="t,x,b,dx,Tb,Tc,f,S,note"):
    path.write_text(header + "\n" + "\n".join(rows) + "\n")
    return path


def _rows(n=25):
    return [f"{k},{10 * k},{k},{k / 10},{68 + k},{293.15 + k},{600},{3000},ok" for k in range(n)]


def test_units_are_converted_to_si(tmp_path):
    survey = read_mapped_csv(_write(tmp_path / "a.csv", _rows()), column_map_from_dict(MAP))
    k = np.arange(25)
    np.testing.assert_allclose(survey.time_s, 60.0 * k)
    np.testing.assert_allclose(survey.positions["X"], 0.01 * k)
    np.testing.assert_allclose(survey.positions["B"], np.radians(k))
    np.testing.assert_allclose(survey.errors["x"], 1e-7 * k)
    np.testing.assert_allclose(survey.temperatures["bed"], (68 + k - 32) * 5 / 9)
    np.testing.assert_allclose(survey.temperatures["col"], 20.0 + k)
    np.testing.assert_allclose(survey.velocities["X"], 0.01)
    np.testing.assert_allclose(survey.spindle_speed_rad_s, 100 * np.pi)
    assert column_map_from_dict(MAP).uncertainty_m == pytest.approx(1.4e-6)


def test_a_map_without_units_reads_them_off_the_column_names(tmp_path):
    """A millimetre column named ``x_mm`` is never read as metres: without a unit in the
    map, a known unit at the end of the column's name is taken; a name without one is
    refused (no quantity defaults to SI)."""
    path = tmp_path / "named.csv"
    path.write_text("t_min,x_mm,y,dev_um,T_K\n" +
                    "\n".join(f"{k},{10 * k},{k / 10},{k},{293.15 + k}" for k in range(25)) +
                    "\n")
    named = {"time": "t_min", "positions": {"X": "x_mm", "Y": "y"}, "errors": {"x": "dev_um"},
             "temperatures": {"bed": "T_K"}}
    with pytest.raises(ParameterError, match=r"^column y \(pos.Y\) has no unit: give it in "
                       r"the map \(\{column: y, unit: mm\}\), the flag \(--col pos.Y=y:mm\) "
                       r"or the name \(y_mm\)$"):
        read_mapped_csv(path, column_map_from_dict(named))
    named["positions"]["Y"] = {"column": "y", "unit": "m"}
    survey = read_mapped_csv(path, column_map_from_dict(named))
    k = np.arange(25)
    np.testing.assert_allclose(survey.time_s, 60.0 * k)
    np.testing.assert_allclose(survey.positions["X"], 0.01 * k)
    np.testing.assert_allclose(survey.positions["Y"], 0.1 * k)        # stated: metres
    np.testing.assert_allclose(survey.errors["x"], 1e-6 * k)
    np.testing.assert_allclose(survey.temperatures["bed"], 20.0 + k)


def test_flags_and_row_order_as_time(tmp_path):
    column_map = parse_col_flags(["pos.X=x:mm", "err.x=dx:um"])
    column_map.row_period_s = 15.0
    survey = read_mapped_csv(_write(tmp_path / "a.csv", _rows()), column_map)
    np.testing.assert_allclose(survey.time_s, 15.0 * np.arange(25))


def test_a_bad_cell_drops_its_row_and_is_counted(tmp_path):
    rows = _rows()
    rows[3] = rows[3].replace(",3,", ",n/a,", 1)
    survey = read_mapped_csv(_write(tmp_path / "a.csv", rows), column_map_from_dict(MAP))
    assert survey.rows_read == 25 and survey.rows_dropped == 1
    assert "row 5 column b" in survey.drop_reasons[0]
    # A bad cell in a column no role uses does not cost the row.
    rows = _rows()
    rows[4] = rows[4].replace("ok", "??")
    assert read_mapped_csv(_write(tmp_path / "b.csv", rows), column_map_from_dict(MAP)
                           ).rows_dropped == 0


@pytest.mark.parametrize("change, error, message", [
    (lambda m: m["positions"].update({"Y": {"column": "y", "unit": "mm"}}), InputDataError,
     "no column 'y' \\(for pos.Y\\)"),
    (lambda m: m["errors"]["x"].update({"unit": "furlong"}), ParameterError,
     "err.x: unknown length unit 'furlong'"),
    (lambda m: m["temperatures"]["bed"].update({"unit": "Rankine"}), ParameterError,
     "temp.bed: unknown temperature unit 'Rankine'"),
    (lambda m: m.update({"colour": 1}), ParameterError, "unknown key\\(s\\) colour"),
    (lambda m: m.pop("errors"), ParameterError, "no error column"),
])
def test_bad_maps_are_one_line_errors(tmp_path, change, error, message):
    data = {k: (dict(v) if isinstance(v, dict) else v) for k, v in MAP.items()}
    data = {k: ({kk: dict(vv) if isinstance(vv, dict) else vv for kk, vv in v.items()}
                if isinstance(v, dict) else v) for k, v in data.items()}
    change(data)
    with pytest.raises(error, match=message):
        read_mapped_csv(_write(tmp_path / "a.csv", _rows()), column_map_from_dict(data))


def test_bad_files_are_one_line_errors(tmp_path):
    column_map = column_map_from_dict(MAP)
    with pytest.raises(InputDataError, match="3 usable rows; at least 20"):
        read_mapped_csv(_write(tmp_path / "short.csv", _rows(3)), column_map)
    words = [",".join(f if j != 4 else "warm" for j, f in enumerate(r.split(",")))
             for r in _rows()]
    with pytest.raises(InputDataError, match="column 'Tb' \\(temp.bed\\) is not numeric"):
        read_mapped_csv(_write(tmp_path / "words.csv", words), column_map)
    back = _rows()
    back[10] = back[10].replace("10,", "2,", 1)
    with pytest.raises(InputDataError, match="goes back at data row 11"):
        read_mapped_csv(_write(tmp_path / "back.csv", back), column_map)
    # Equal stamps (a logger at coarse resolution) are read, not refused (issue 40).
    equal = _rows()
    equal[10] = equal[10].replace("10,", "9,", 1)
    survey = read_mapped_csv(_write(tmp_path / "equal.csv", equal), column_map)
    assert survey.time_s[9] == survey.time_s[10] == 540.0 and survey.time_s.size == 25
    with pytest.raises(ParameterError, match="--col 'pos.X': expected ROLE=COLUMN"):
        parse_col_flags(["pos.X"], ColumnMap())


def test_the_machine_facts_a_map_may_give_tool_offset_and_work_axes(tmp_path):
    """Issue 28: without a machine YAML, the map's tool offset (signed z of the tip) and the
    axes that carry the workpiece make the generic machine's chain and Abbe arms."""
    from mt_accuracy_ros.core.errors import ParameterError
    from mt_accuracy_ros.core.kinematics.machine import generic_cartesian
    from mt_accuracy_ros.io.column_map import column_map_from_dict

    column_map = column_map_from_dict({"tool_offset": {"value": -150, "unit": "mm"},
                                       "work_axes": ["y", "X"]})
    assert column_map.tool_offset_m == pytest.approx(-0.15, abs=1e-15)
    assert column_map.work_axes == ("Y", "X")
    assert column_map_from_dict({"tool_offset": 0}).tool_offset_m == 0.0
    machine = generic_cartesian({"X": (0, 0.5), "Y": (0, 0.4), "Z": (-0.3, 0)},
                                tool_length_m=column_map.tool_offset_m,
                                work_axes=column_map.work_axes)
    # Bed outwards: Y on the bed carries X, which carries the workpiece; Z carries the tool.
    assert tuple(machine.workpiece_branch) == ("Y", "X")
    assert tuple(machine.tool_branch) == ("Z",) and machine.tool[2] == pytest.approx(-0.15)
    for bad in ({"work_axes": ["X", "X"]}, {"work_axes": "XY"}, {"work_axes": ["W"]},
                {"tool_offset": {"value": "long", "unit": "mm"}},
                {"tool_offset": {"value": 5, "unit": "furlong"}}):
        with pytest.raises(ParameterError):
            column_map_from_dict(bad)
    from mt_accuracy_ros.core.errors import MachineDescriptionError

    with pytest.raises(MachineDescriptionError, match="work axes"):
        generic_cartesian({"X": (0, 0.5), "Z": (0, 0.3)}, work_axes=("Y",))


def test_the_tool_offset_is_the_abbe_arm_of_an_angular_error_on_the_generic_machine():
    """The map's tool offset reaches the TCP through an angular error: e = eps x (tip -
    origin), first order, by hand."""
    import numpy as np

    from mt_accuracy_ros.core.effects import Context
    from mt_accuracy_ros.core.effects.variables import Variables
    from mt_accuracy_ros.core.kinematics.machine import generic_cartesian

    machine = generic_cartesian({"X": (0, 0.5), "Y": (0, 0.4), "Z": (-0.3, 0)},
                                tool_length_m=-0.1)
    rng = np.random.default_rng(2)
    q = {a: rng.uniform(*machine.axes[a].stroke, 6) for a in "XYZ"}
    ctx = Context(machine, Variables(q))
    # All on the tool side: X's pitch EBX turns Y, Z and the tool about y through X's
    # origin: lever (0, y, z + t) from it, so e = eps y x (0, y, z + t) = (z + t, 0, 0).
    np.testing.assert_allclose(ctx.jacobian("EBX"),
                               np.column_stack([q["Z"] - 0.1, 0 * q["X"], 0 * q["X"]]),
                               atol=1e-15)


def test_a_survey_of_many_runs_restarts_its_clock_and_lags_each_run(tmp_path):
    """`run:` in the column map (issue 40): each day's clock restarts; without the run the
    file is refused at the restart, with it the days lie end to end, a heat source's lag
    restarts from rest each morning, and whole runs are the folds."""
    from mt_accuracy_ros.commands.check import check_mapped_csv

    rng = np.random.default_rng(2)
    lines = ["day,t_min,x_mm,S_rpm,dx_um"]
    for day in range(4):
        t = np.arange(90) * 4.0                                    # min, every 4 min
        speed = np.where((t // 40) % 2 == 0, 8000.0, 2000.0) * (0.7 + 0.1 * day)
        # Spindle heat through a 20 min lag from a cold start, each day on its own (the
        # exact recurrence for a piecewise-constant input, written here by hand).
        growth = np.zeros(t.size)
        for k in range(1, t.size):
            decay = np.exp(-(t[k] - t[k - 1]) / 20.0)
            growth[k] = growth[k - 1] * decay + (1 - decay) * 0.001 * speed[k - 1]
        x = rng.uniform(0, 500, t.size)
        dx = growth + rng.normal(0, 0.05, t.size)
        lines += [f"d{day + 1},{a:.1f},{b:.3f},{c:.0f},{d:.4f}"
                  for a, b, c, d in zip(t, x, speed, dx)]
    (tmp_path / "days.csv").write_text("\n".join(lines) + "\n")
    base = {"time": {"column": "t_min", "unit": "min"},
            "positions": {"X": {"column": "x_mm", "unit": "mm"}},
            "errors": {"x": {"column": "dx_um", "unit": "um"}},
            "spindle_speed": {"column": "S_rpm", "unit": "rpm"},
            "uncertainty": {"value": 0.1, "unit": "um"}}
    with pytest.raises(InputDataError, match="goes back at data row 91"):
        read_mapped_csv(tmp_path / "days.csv", column_map_from_dict(base))
    column_map = column_map_from_dict({**base, "run": "day"})
    survey = read_mapped_csv(tmp_path / "days.csv", column_map)
    assert survey.run_names == ["d1", "d2", "d3", "d4"]
    assert np.all(np.diff(survey.time_s) > 0) and survey.time_s[90] == 60.0 * (89 * 4 + 4)
    result = check_mapped_csv(tmp_path / "days.csv", column_map, None, [], 1, 0.05)
    assert result["validation"] == "by whole runs"
    assert [r["rows"] for r in result["runs"]] == [90] * 4
    assert result["named"][0]["name"] == "heat_source:spindle_speed"
    assert result["named"][0]["setting"]["tau_s"] == pytest.approx(1200.0, rel=0.3)
    # The same days stitched into one record (no run): the lag runs on over the night
    # and every morning's cold start is missed.
    stitched = [lines[0]] + [
        ",".join([f"{float(row.split(',')[1]) + 360.0 * (int(row.split(',')[0][1:]) - 1):.1f}"]
                 + row.split(",")[2:]) for row in lines[1:]]
    (tmp_path / "one.csv").write_text("\n".join(["t_min,x_mm,S_rpm,dx_um"] + stitched[1:])
                                      + "\n")
    one = check_mapped_csv(tmp_path / "one.csv", column_map_from_dict(base), None, [], 1, 0.05)
    assert result["final_rmse"] < 0.5 * one["final_rmse"]


def test_chunks_read_as_row_by_row_across_boundaries_blank_lines_and_bad_rows(
        tmp_path, monkeypatch):
    # Clean chunks are converted column by column; the result must equal reading every
    # row alone (the path a chunk with a bad row takes), bit for bit, messages included.
    from mt_accuracy_ros.io import column_map as module

    rng = np.random.default_rng(7)
    rows = [f"{k / 7:.9g},{rng.normal(0, 100):.12g},{rng.uniform(-90, 90)!r},"
            f"{rng.normal(0, 3):.6e},{68 + rng.normal():.4f},{293.15 + rng.normal():.5f},"
            f"{600},{3000},ok" for k in range(2500)]
    rows[1234] = rows[1234].replace(",600,", ",nan,")           # a bad row in chunk 2
    rows[2001] = rows[2001].replace(",3000,", ",,")               # an empty cell
    rows.insert(1500, "")                                          # blank lines: not rows
    rows.insert(1700, ",,,,,,,,")
    path = _write(tmp_path / "long.csv", rows)
    monkeypatch.setattr(module, "CSV_CHUNK_ROWS", 1000)
    chunked = read_mapped_csv(path, column_map_from_dict(MAP))
    monkeypatch.setattr(module, "_parse_clean_chunk", lambda *args: False)
    alone = read_mapped_csv(path, column_map_from_dict(MAP))
    assert chunked.rows_read == alone.rows_read == 2500
    assert chunked.rows_dropped == alone.rows_dropped == 2
    assert chunked.drop_reasons == alone.drop_reasons
    assert "row 1236 column f" in alone.drop_reasons[0]
    for name in ("time_s", "positions", "errors", "temperatures", "velocities",
                 "spindle_speed_rad_s"):
        a, b = getattr(chunked, name), getattr(alone, name)
        if isinstance(a, dict):
            assert a.keys() == b.keys()
            assert all(np.array_equal(a[k], b[k]) for k in a)
        else:
            assert np.array_equal(a, b)
    # A row with the wrong number of fields is refused by its number on either path.
    rows = _rows(30)
    rows[20] += ",extra"
    with pytest.raises(InputDataError, match="row 22 has 10 fields"):
        read_mapped_csv(_write(tmp_path / "c.csv", rows), column_map_from_dict(MAP))


def test_a_survey_with_semicolons_and_decimal_commas_reads_as_its_plain_twin(
        tmp_path, monkeypatch):
    """A spreadsheet's German export of the same survey, a line of preamble before its
    header: every mapped value equal, bit for bit, on the chunked path and row by row (a
    bad row in it is named alike, rows counted from the header)."""
    from mt_accuracy_ros.io import column_map as module

    rng = np.random.default_rng(3)
    rows = [f"{k / 7:.9g},{rng.normal(0, 100):.12g},{rng.uniform(-90, 90):.10f},"
            f"{rng.normal(0, 3):.6e},{68 + rng.normal():.4f},{293.15 + rng.normal():.5f},"
            f"600,3000,ok" for k in range(300)]
    rows[40] = rows[40].replace(",600,", ",n/a,")
    plain = read_mapped_csv(_write(tmp_path / "plain.csv", rows), column_map_from_dict(MAP))
    german = [";".join(cell.replace(".", ",") for cell in row.split(",")) for row in rows]
    path = tmp_path / "german.csv"
    path.write_bytes(("Messprotokoll;Maschine 7\r\n\r\nt;x;b;dx;Tb;Tc;f;S;note\r\n" +
                      "\r\n".join(german) + "\r\n").encode("cp1252"))
    surveys = [read_mapped_csv(path, column_map_from_dict(MAP))]
    monkeypatch.setattr(module, "_parse_clean_chunk", lambda *args: False)
    surveys.append(read_mapped_csv(path, column_map_from_dict(MAP)))
    for survey in surveys:
        assert survey.summary("german.csv") == "german.csv: 299 of 300 rows used (read as " \
            "semicolon-separated, with decimal commas; 1 line before the header skipped); " \
            "1 dropped (row 42 column f: 'n/a')"
        assert survey.drop_reasons == plain.drop_reasons
        for name in ("time_s", "positions", "errors", "temperatures", "velocities",
                     "spindle_speed_rad_s"):
            a, b = getattr(survey, name), getattr(plain, name)
            if isinstance(a, dict):
                assert a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)
            else:
                assert np.array_equal(a, b)


def test_a_survey_time_column_of_date_times_reads_as_seconds_since_the_first(tmp_path):
    import datetime as dt

    start = dt.datetime(2026, 11, 20, 23, 59, 0)
    rows = _rows()
    dated = [f"{start + dt.timedelta(seconds=15 * k):%Y-%m-%d %H:%M:%S}" + row[row.index(","):]
             for k, row in enumerate(rows)]
    dated[7] = "yesterday" + dated[7][dated[7].index(","):]
    survey = read_mapped_csv(_write(tmp_path / "dated.csv", dated), column_map_from_dict(MAP))
    assert survey.rows_dropped == 1 and survey.drop_reasons == ["row 9 column t: 'yesterday'"]
    kept = np.delete(np.arange(25), 7)
    # The map's unit (min) is for numbers: date-times are seconds, counted from the first.
    np.testing.assert_array_equal(survey.time_s, 15.0 * kept)
    plain = read_mapped_csv(_write(tmp_path / "plain.csv", rows), column_map_from_dict(MAP))
    np.testing.assert_array_equal(survey.positions["X"], np.delete(plain.positions["X"], 7))


def test_no_quantity_defaults_to_si_and_the_default_uncertainty_is_announced(tmp_path):
    """A bare uncertainty or tool offset, an unknown role or unit are one line that says
    how to give it; a map without an uncertainty takes the 1 um default and says so."""
    with pytest.raises(ParameterError, match=r"^m.yaml: uncertainty: 1.4 has no unit; give it "
                                             r"as uncertainty: \{value: 1.4, unit: um\}$"):
        column_map_from_dict({"uncertainty": 1.4}, "m.yaml")
    with pytest.raises(ParameterError, match=r"tool_offset: -150 has no unit; give it as "
                                             r"tool_offset: \{value: -150, unit: mm\}"):
        column_map_from_dict({"tool_offset": {"value": -150}})
    with pytest.raises(ParameterError, match=r"unknown role 'pos_X'; known roles: time, pos.X"):
        parse_col_flags(["pos_X=x:mm"])
    with pytest.raises(ParameterError, match=r"unknown temperature unit 'Rankine'; known: "
                                             r"degC, C, K, degF"):
        parse_col_flags(["temp.bed=Tb:Rankine"])
    assert parse_col_flags(["temp.bed=Tb:°C"]).roles["temp.bed"] == ("Tb", "degC")
    silent = column_map_from_dict({"positions": {"X": "x_mm"}})
    assert silent.uncertainty_m == pytest.approx(1e-6)
    assert silent.uncertainty_note().startswith("uncertainty: the column map states none; "
                                                "1 um (k = 2) assumed")
    assert column_map_from_dict(MAP).uncertainty_note() == ""


def test_a_time_column_of_date_times_needs_no_unit_but_numbers_do(tmp_path):
    import datetime as dt

    start = dt.datetime(2026, 11, 20, 7, 0, 0)
    rows = _rows()
    dated = [f"{start + dt.timedelta(seconds=15 * k):%Y-%m-%d %H:%M:%S}" + row[row.index(","):]
             for k, row in enumerate(rows)]
    data = dict(MAP, time="t")
    survey = read_mapped_csv(_write(tmp_path / "dated.csv", dated), column_map_from_dict(data))
    np.testing.assert_array_equal(survey.time_s, 15.0 * np.arange(25))
    with pytest.raises(ParameterError, match=r"^column t \(time\) has no unit"):
        read_mapped_csv(_write(tmp_path / "plain.csv", rows), column_map_from_dict(data))


def test_implausible_values_are_refused_naming_the_unit_they_look_like(tmp_path):
    kelvin = dict(MAP, temperatures={"col": {"column": "Tc", "unit": "degC"}})
    with pytest.raises(ParameterError, match=r"^column Tc \(temp.col\): values 293.1 … 317.1 "
                                             r"declared °C look like K"):
        read_mapped_csv(_write(tmp_path / "a.csv", _rows()), column_map_from_dict(kelvin))
    metres = dict(MAP, errors={"x": {"column": "x", "unit": "m"}})
    with pytest.raises(ParameterError, match=r"column x \(err.x\): values 0 … 240 declared m "
                                             r"look like µm"):
        read_mapped_csv(_write(tmp_path / "a.csv", _rows()), column_map_from_dict(metres))
