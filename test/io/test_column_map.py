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
    (lambda m: m["positions"].update({"Y": {"column": "y"}}), InputDataError,
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
    with pytest.raises(InputDataError, match="does not increase at data row 11"):
        read_mapped_csv(_write(tmp_path / "back.csv", back), column_map)
    with pytest.raises(ParameterError, match="--col 'pos.X': expected ROLE=COLUMN"):
        parse_col_flags(["pos.X"], ColumnMap())
