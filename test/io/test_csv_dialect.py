"""CSV files as shops write them: `;` and decimal commas, tabs, a byte-order mark,
Windows-1252, date-times in the time column. Each reads as its plain twin does."""
from __future__ import annotations

from datetime import datetime, timezone

import numpy as np
import pytest

from mt_accuracy_ros.core.errors import InputDataError
from mt_accuracy_ros.io.csv_dialect import CsvDialect, sniff_dialect, to_number, to_seconds
from mt_accuracy_ros.io.csv_table import read_csv_table

ROWS = [["time_s", "T1 [°C]", "T2 [°C]", "dial [µm]"],
        ["0", "20.125", "19.5", "-1.25"],
        ["60", "20.5", "19.625", "0.5"],
        ["120", "21.0", "19.75", "2.0e-1"]]


def _write(path, rows, delimiter=",", decimal_comma=False, encoding="utf-8", bom=False):
    cells = [[c.replace(".", ",") if decimal_comma and i else c for c in row]
             for i, row in enumerate(rows)]
    text = "\r\n".join(delimiter.join(row) for row in cells) + "\r\n"
    path.write_bytes((b"\xef\xbb\xbf" if bom else b"") + text.encode(encoding))
    return path


@pytest.mark.parametrize("delimiter, decimal_comma, encoding, bom, note", [
    (",", False, "utf-8", False, ""),
    (";", True, "cp1252", False,
     "read as semicolon-separated, with decimal commas, in Windows-1252 (not UTF-8)"),
    (";", False, "utf-8", True, "read as semicolon-separated"),
    ("\t", True, "utf-8", True, "read as tab-separated, with decimal commas"),
])
def test_each_dialect_is_found_and_reads_as_the_plain_file(tmp_path, delimiter, decimal_comma,
                                                           encoding, bom, note):
    plain = read_csv_table(_write(tmp_path / "plain.csv", ROWS))
    path = _write(tmp_path / "shop.csv", ROWS, delimiter, decimal_comma, encoding, bom)
    dialect = sniff_dialect(path)
    assert (dialect.delimiter, dialect.decimal_comma) == (delimiter, decimal_comma)
    assert dialect.encoding == ("cp1252" if encoding == "cp1252" else "utf-8-sig")
    assert dialect.note() == note
    table = read_csv_table(path)
    assert table.names == ROWS[0]      # the BOM and the encoding do not touch the names
    for name in ROWS[0]:
        np.testing.assert_array_equal(table.columns[name], plain.columns[name])
    assert table.summary().endswith(f"({note})" if note else "rows used")


def test_a_comma_inside_quotes_does_not_make_a_file_semicolon_separated(tmp_path):
    path = tmp_path / "quoted.csv"
    path.write_text('name,value\n"a; b",1.5\n"c; d",2.5\n', encoding="utf-8")
    assert sniff_dialect(path) == CsvDialect(",", False, "utf-8-sig")


def test_numbers_and_date_times():
    assert to_number("20,35", CsvDialect(";", True)) == 20.35
    with pytest.raises(ValueError):
        to_number("20,35", CsvDialect(",", False))
    epoch = datetime(2026, 11, 20, 7, 0, tzinfo=timezone.utc).timestamp()
    for text in ("2026-11-20 07:00:00", "2026-11-20T07:00:00", "2026-11-20T07:00:00Z",
                 "20.11.2026 07:00:00", "20.11.2026 07:00", "2026/11/20 07:00:00",
                 "2026-11-20T08:00:00+01:00"):
        assert to_seconds(text) == epoch, text
    assert to_seconds("2026-11-20 07:00:00.250") == epoch + 0.25
    assert to_seconds("20.11.2026 07:00:00,250") == epoch + 0.25
    for text in ("soon", "31.02.2026 07:00:00", "12"):
        with pytest.raises(ValueError):
            to_seconds(text)


def test_a_time_column_of_date_times_is_read_as_seconds_and_a_bad_stamp_names_its_row(
        tmp_path):
    rows = [["stamp", "T1", "g_um"], ["2026-11-20 23:59:30", "20.0", "1.0"],
            ["2026-11-21 00:00:30", "20.5", "2.0"], ["yesterday", "20.6", "2.1"],
            ["2026-11-21 00:01:30", "21.0", "3.0"]]
    path = _write(tmp_path / "dated.csv", rows)
    table = read_csv_table(path, time_columns=("stamp",))
    assert table.date_time_columns == ("stamp",)
    stamps = table.columns["stamp"]
    np.testing.assert_array_equal(stamps - stamps[0], [0.0, 60.0, 120.0])
    assert table.rows_dropped == 1 and table.drop_reasons == [
        "row 4 column stamp: 'yesterday' is not a date-time like the first row's"]
    # Numbers in a time column stay numbers.
    plain = read_csv_table(_write(tmp_path / "plain.csv", ROWS), time_columns=("time_s",))
    assert plain.date_time_columns == () and list(plain.columns["time_s"]) == [0, 60, 120]


def test_a_file_that_is_no_text_is_refused_in_one_line(tmp_path):
    path = tmp_path / "binary.csv"
    path.write_bytes(b"a,b\n1,2\n\x00\x01\x02")
    with pytest.raises(InputDataError, match="not a text CSV file"):
        read_csv_table(path)


def test_a_row_of_units_under_the_header_is_read_as_units_not_dropped(tmp_path):
    rows = [["t", "T1", "g"], ["min", "°C", "µm"], ["0", "20.0", "1.0"], ["1", "x", "2.0"],
            ["2", "21.0", "3.0"]]
    table = read_csv_table(_write(tmp_path / "units.csv", rows))
    assert table.units == {"t": "min", "T1": "°C", "g": "µm"}
    assert table.rows_read == 3 and table.rows_dropped == 1
    assert table.drop_reasons == ["row 4 column T1: 'x' is not a number"]   # the file's row
    assert list(table.data_rows) == [1, 3]                                  # after the units
    np.testing.assert_array_equal(table.columns["g"], [1.0, 3.0])
    # A first row of words that are no units is a bad data row, as before.
    rows[1] = ["soon", "hot", "far"]
    table = read_csv_table(_write(tmp_path / "words.csv", rows))
    assert table.units == {} and table.rows_read == 4 and table.rows_dropped == 2


def test_a_loggers_preamble_before_the_header_is_skipped_and_said(tmp_path):
    preamble = ["Plot Title: spindle warm-up", "Serial Number: 20551234",
                "Start; 20.11.2026 07:00"]
    path = tmp_path / "hobo.csv"
    lines = preamble + [";".join(row) for row in ROWS]
    path.write_text("\n".join(lines[:3] + [""] + lines[3:]) + "\n", encoding="utf-8")
    dialect = sniff_dialect(path)
    assert (dialect.delimiter, dialect.preamble_lines) == (";", 3)
    table = read_csv_table(path)
    assert table.names == ROWS[0] and table.rows_read == 3
    assert dialect.note() == "read as semicolon-separated; 3 lines before the header skipped"
    np.testing.assert_array_equal(table.columns["dial [µm]"], [-1.25, 0.5, 0.2])


def test_a_damaged_row_near_the_top_is_not_taken_for_a_preamble(tmp_path):
    """Data rows before a row with a field too many split like the header: they are no
    preamble, and the damaged row is named as before."""
    rows = [",".join(r) for r in ROWS] + ["180,21.5,19.9,0.3,extra", "240,21.6,20.0,0.4"]
    path = tmp_path / "damaged.csv"
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    assert sniff_dialect(path).preamble_lines == 0
    with pytest.raises(InputDataError, match="row 5 has 5 fields, the header 4"):
        read_csv_table(path)


def test_a_header_that_does_not_match_its_data_is_named_in_the_datas_separator(tmp_path):
    path = tmp_path / "mismatch.csv"
    path.write_text("Datum;Uhrzeit;T1 [°C]\n20.03.2026 06:00:00;20,5\n"
                    "20.03.2026 06:02:00;20,6\n", encoding="utf-8")
    assert sniff_dialect(path).delimiter == ";"
    with pytest.raises(InputDataError, match="row 2 has 2 fields, the header 3"):
        read_csv_table(path)


def test_a_clock_without_a_date_counts_the_midnights_it_passes(tmp_path):
    rows = [["Uhrzeit", "T1", "g_um"], ["23:58:00", "20.0", "1.0"], ["23:59:30,5", "20.1", "1.1"],
            ["00:01:00", "20.2", "1.2"], ["25:00:00", "20.3", "1.3"], ["13:00:00", "20.4", "1.4"],
            ["00:00:30", "20.5", "1.5"]]
    table = read_csv_table(_write(tmp_path / "clock.csv", rows, ";"), time_columns=("Uhrzeit",))
    assert table.clock_columns == ("Uhrzeit",) == table.date_time_columns
    start = 23 * 3600 + 58 * 60
    np.testing.assert_allclose(table.columns["Uhrzeit"] - start,
                               [0.0, 90.5, 180.0, 13 * 3600 + 120.0, 24 * 3600 + 150.0])
    assert table.drop_reasons == [
        "row 5 column Uhrzeit: '25:00:00' is not a date-time like the first row's"]


def test_a_date_and_a_time_of_day_in_two_columns_join_and_a_bad_pair_drops_its_row(tmp_path):
    rows = [["Datum", "Uhrzeit", "T1", "g_um"], ["20.11.2026", "23:59:00", "20,0", "1,0"],
            ["21.11.2026", "00:00:30", "20,1", "1,1"], ["21.11.2026", "später", "20,2", "1,2"],
            ["21.11.2026", "00:01:00", "20,3", "1,3"]]
    table = read_csv_table(_write(tmp_path / "split.csv", rows, ";"),
                           time_columns=("Datum+Uhrzeit",))
    assert table.date_time_columns == ("Datum+Uhrzeit",)
    stamps = table.columns["Datum+Uhrzeit"]
    np.testing.assert_array_equal(stamps - stamps[0], [0.0, 90.0, 120.0])
    assert list(table.columns["Uhrzeit"]) == ["23:59:00", "00:00:30", "00:01:00"]
    np.testing.assert_array_equal(table.columns["T1"], [20.0, 20.1, 20.3])
    assert table.rows_dropped == 1 and table.drop_reasons == [
        "row 4 column Datum+Uhrzeit: '21.11.2026 später' is not a date-time"]


@pytest.mark.parametrize("encoding, note", [("utf-16", "read as UTF-16 (BOM)"),
                                            ("utf-16-be", "read as UTF-16 (BOM)"),
                                            ("utf-32", "read as UTF-32 (BOM)")])
def test_a_unicode_text_export_is_read_by_its_byte_order_mark_and_said(tmp_path, encoding,
                                                                       note):
    """Excel's "Unicode text" is UTF-16 with a byte-order mark: read as the plain file."""
    plain = read_csv_table(_write(tmp_path / "plain.csv", ROWS))
    path = tmp_path / "unicode.csv"
    text = "\r\n".join(",".join(row) for row in ROWS) + "\r\n"
    mark = {"utf-16-be": b"\xfe\xff"}.get(encoding, b"")
    path.write_bytes(mark + text.encode(encoding))
    dialect = sniff_dialect(path)
    assert dialect.note() == note
    table = read_csv_table(path)
    assert table.names == ROWS[0]      # "°C", "µm" decoded, the mark not in the first name
    for name in ROWS[0]:
        np.testing.assert_array_equal(table.columns[name], plain.columns[name])
    assert table.summary().endswith(f"({note})")


def test_a_long_utf16_file_is_sniffed_on_whole_characters(tmp_path):
    """The sniffed bytes end where they end: never inside a UTF-16 character."""
    rows = [ROWS[0]] + [[str(60 * i), "20.5", "19.5", "0.25"] for i in range(3000)]
    path = tmp_path / "long.csv"
    path.write_bytes(("\n".join(",".join(r) for r in rows) + "\n").encode("utf-16"))
    assert path.stat().st_size > 64 * 1024
    table = read_csv_table(path)
    assert table.rows_read == 3000 and table.rows_dropped == 0


@pytest.mark.parametrize("content, words", [
    ("a,b\n1,2\n".encode("utf-16-le"), "holds NUL bytes); a UTF-16 export without a "
     "byte-order mark? save it as UTF-8 CSV"),
    (b"\xff\xfe" + b"a\x00,\x00\x00\xd8", "starts with a UTF-16 (BOM) byte-order mark but is "
     "not such text"),
    (b"\x89PNG\r\n\x1a\n" + bytes(50), "is a PNG image, not a CSV"),
    (b"\x89MCAP0\r\n" + bytes(50), "is an MCAP bag, not a CSV; `mt-accuracy check FILE` "
     "reads a bag"),
    (b"PK\x03\x04" + bytes(50), "is a ZIP archive (a spreadsheet .xlsx"),
])
def test_a_file_that_is_no_csv_is_named_for_what_it_is(tmp_path, content, words):
    path = tmp_path / "data.csv"
    path.write_bytes(content)
    with pytest.raises(InputDataError) as error:
        read_csv_table(path)
    assert words in str(error.value) and "\n" not in str(error.value)
