"""Positioning tables a control loads (issue 30): written, read back by a reader written
here from the formats' rules, applied, and compared with the model."""
from __future__ import annotations

import re

import numpy as np
import pytest

from mt_accuracy_ros.core.compensation.controller_tables import (POINTS_PER_PERIOD,
                                                                  fanuc_pitch, siemens_eec,
                                                                  spacing_for)
from mt_accuracy_ros.core.compensation.error_model import ErrorModel
from mt_accuracy_ros.core.errors import ParameterError
from mt_accuracy_ros.core.kinematics.machine import load_machine

BAND = 1e-6


def _model(k=5e-6):
    """A 10 mm ball-screw pitch of X (2.2 um) and a user effect k x - the export used to
    write all-zero tables for the latter."""
    return ErrorModel(load_machine("kidani_hmc"), {
        "positioning_periodic:EXX": {
            "family": "positioning_periodic", "variant": "EXX", "setting": {"period_m": 0.01},
            "coefficients": {"cos1": 2e-6, "sin1": 1e-6, "cos2": 0.0, "sin2": 0.0}},
        "scale": {"expression": "k * x", "parameters": ["k"], "acts_on": "X",
                  "values": {"k": k}}})


def _truth(x):
    """E_XX by hand from the model's definition: the sinusoid and k x."""
    phase = 2 * np.pi * x / 0.01
    return 2e-6 * np.cos(phase) + 1e-6 * np.sin(phase) + 5e-6 * x


def _read_siemens(text):
    """SINUMERIK EEC: $AA_ENC_COMP[e,N,AX]=mm, _STEP, _MIN, _MAX per axis."""
    tables = {}
    for line in text.splitlines():
        match = re.fullmatch(r"\$AA_ENC_COMP\[0,(\d+),(\w+)\]=(-?[\d.]+)", line)
        if match:
            tables.setdefault(match[2], {}).setdefault("values", {})[int(match[1])] = \
                float(match[3]) * 1e-3
        match = re.fullmatch(r"\$AA_ENC_COMP_(STEP|MIN|MAX|IS_MODULO)\[0,(\w+)\]=(-?[\d.]+)",
                             line)
        if match:
            tables.setdefault(match[2], {})[match[1]] = float(match[3]) * 1e-3
    assert text.startswith("%_N_AX_EEC_INI\nCHANDATA(1)\n") and text.rstrip().endswith("M17")
    return tables


def test_sinumerik_eec_round_trip_holds_the_model_within_the_band():
    model = _model()
    choice = spacing_for(model, BAND)
    # 8 points a 10 mm period at least, and the round trip within the band.
    assert choice.spacing_m <= 0.01 / POINTS_PER_PERIOD + 1e-12
    text, shifts = siemens_eec(model, choice.spacing_m)
    table = _read_siemens(text)["X1"]
    n = len(table["values"])
    assert table["MAX"] == pytest.approx(table["MIN"] + table["STEP"] * (n - 1), abs=1e-9)
    assert table["IS_MODULO"] == 0 and table["STEP"] == pytest.approx(choice.spacing_m)
    points = table["MIN"] + table["STEP"] * np.arange(n)
    values = np.array([table["values"][k] for k in range(n)])
    # The value at the reference point (X = 0 here) is zero; a positive value moves the
    # axis negative, so what is left of the error is E - C = the shift (a datum).
    assert np.interp(0.0, points, values) == pytest.approx(0.0, abs=1e-9)
    x = np.linspace(0.0, 0.39, 5001)
    left = _truth(x) - np.interp(x, points, values)
    assert np.ptp(left) / 2 <= BAND and abs(np.mean(left) - shifts["X"]) < BAND
    assert shifts["X"] == pytest.approx(_truth(np.array([0.0]))[0], abs=1e-12)


def _read_fanuc(text):
    """FANUC parameter tape: N<param>A<axis>P<value>...; N<10000+n>P<increment>."""
    lines = text.strip().splitlines()
    assert lines[0] == "%" and lines[-1] == "%"
    parameters, data = {}, {}
    for line in lines[1:-1]:
        if line.startswith("("):
            continue
        number = int(re.match(r"N(\d+)", line)[1])
        if number >= 10000:
            data[number - 10000] = int(re.fullmatch(r"N\d+P(-?\d+)", line)[1])
        else:
            parameters[number] = {int(a): int(p) for a, p in re.findall(r"A(\d+)P(-?\d+)", line)}
    return parameters, data


def test_fanuc_pitch_error_data_round_trip():
    model = _model()
    choice = spacing_for(model, BAND, max_points=128)
    assert choice.limited_by.startswith("the control holds 128 points per axis")
    text, _ = fanuc_pitch(model, choice.spacing_m, step_limit=7)
    parameters, data = _read_fanuc(text)
    axis = 1                                          # X: the control's first axis
    reference, low, high = (parameters[p][axis] for p in (3620, 3621, 3622))
    unit = 1e-6 * parameters[3623][axis]              # detection unit x magnification
    interval = parameters[3624][axis] * 1e-6
    assert interval == pytest.approx(choice.spacing_m) and high - low + 1 <= 128
    # Absolute compensation: zero at the reference point, the increment of point n over
    # the section from n - 1 to n.
    absolute = {reference: 0}
    for n in range(reference + 1, high + 1):
        absolute[n] = absolute[n - 1] + data[n]
    for n in range(reference - 1, low - 1, -1):
        absolute[n] = absolute[n + 1] - data[n + 1]
    assert all(abs(data[n]) <= 7 for n in range(low, high + 1))
    numbers = np.arange(low, high + 1)
    points = (numbers - reference) * interval        # the reference position is X = 0
    compensation = np.array([absolute[n] for n in numbers]) * unit
    x = np.linspace(0.0, 0.39, 5001)
    # The compensation is added to the command: what is left is E + C, its datum E(0).
    left = _truth(x) + np.interp(x, points, compensation) - _truth(np.array([0.0]))[0]
    assert np.max(np.abs(left)) <= choice.errors_m["X"] + 0.5 * unit + 1e-9
    # The limit forced a coarser table and said what it leaves (over the band here).
    assert choice.max_error_m > BAND and "leaves up to" in choice.limited_by


def test_a_spacing_that_cannot_hold_the_model_is_refused_with_one_that_can():
    model = _model()
    with pytest.raises(ParameterError, match=r"spacing 5 mm cannot hold this model: "
                       r"positioning_periodic:EXX has a 10 mm period .*coarsest spacing that "
                       r"holds it is 1.25 mm"):
        spacing_for(model, BAND, asked_m=0.005)
    with pytest.raises(ParameterError, match="exceeds the control's 1"):
        fanuc_pitch(model, 0.004, step_limit=1)
    with pytest.raises(ParameterError, match="0..1023 for all axes"):
        fanuc_pitch(model, 0.0005, step_limit=32767)


def test_a_user_effect_reaches_the_controller_tables():
    model = _model(k=5e-6)
    text, _ = siemens_eec(model, 0.0025)
    values = np.array([v for _, v in sorted(_read_siemens(text)["X1"]["values"].items())])
    flat = _model(k=0.0)
    flat_values = np.array([v for _, v in sorted(
        _read_siemens(siemens_eec(flat, 0.0025)[0])["X1"]["values"].items())])
    points = 0.0025 * np.arange(values.size)
    np.testing.assert_allclose(values - flat_values, 5e-6 * points, atol=1e-9)


def _read_isg(text):
    """ISG leadscrew error compensation list, read from its rules: '# ' comment lines,
    'name value' lines; kw.ssfk.unit 1 = 0.1 um; equidistant points interval apart from
    kw_startpos, kw_nr_max of them; table[i].pos (and .neg when bilateral)."""
    values = {}
    for line in text.splitlines():
        if not line.strip() or line.startswith("# "):
            continue
        name, value = line.split()
        values[name] = value
    assert values["kw.ssfk.unit"] == "1" and values["kw.ssfk.modulo"] == "0"
    n = int(values["kw.ssfk.kw_nr_max"])
    unit = 1e-7
    points = (int(values["kw.ssfk.kw_startpos"]) +
              int(values["kw.ssfk.interval"]) * np.arange(n)) * unit
    pos = np.array([int(values[f"kw.ssfk.table[{i}].pos"]) for i in range(n)]) * unit
    bilateral = values["kw.ssfk.bilateral"] == "1"
    neg = np.array([int(values[f"kw.ssfk.table[{i}].neg"]) for i in range(n)]) * unit \
        if bilateral else pos
    assert bilateral or not any(k.endswith(".neg") for k in values)
    return values, points, pos, neg


@pytest.mark.parametrize("bilateral", [True, False])
def test_isg_twincat_leadscrew_list_round_trip(bilateral):
    """Both list forms through a reader written here: the table holds E_XX within the band
    (and rounding to 0.1 um); bilateral, the directions differ by the reversal."""
    from mt_accuracy_ros.core.compensation.controller_tables import isg_leadscrew_lists

    model = _model()
    model = model.with_effect("reversal:X", {"family": "reversal", "variant": "X",
                                             "setting": {}, "coefficients": {"backlash_m": 3e-6}})
    backlash = model.backlash_m("X")
    assert backlash == pytest.approx(3e-6)
    choice = spacing_for(model, BAND)
    texts, axes = isg_leadscrew_lists(model, choice.spacing_m, bilateral=bilateral)
    assert list(texts)[0] == "achskw1.lis"
    values, points, pos, neg = _read_isg(texts["achskw1.lis"])
    assert values["kopf.log_achs_name"] == "X" and values["kopf.achs_nr"] == "1"
    assert points[1] - points[0] == pytest.approx(choice.spacing_m, abs=1e-12)
    x = np.linspace(0.0, 0.39, 5001)
    for table, shift in ((pos, -backlash / 2), (neg, backlash / 2)) if bilateral else \
            ((pos, 0.0),):
        left = _truth(x) + shift - np.interp(x, points, table)
        assert np.max(np.abs(left)) <= BAND / 2 + 0.5e-7
    if bilateral:
        assert np.allclose(neg - pos, backlash, atol=1.01e-7)
    with pytest.raises(ParameterError, match="holds fewer than 1500"):
        isg_leadscrew_lists(model, 0.0001)
    with pytest.raises(ParameterError, match="not a whole number of 0.1 um"):
        isg_leadscrew_lists(model, 0.00100005)


def _read_linuxcnc(text, file_type):
    """LinuxCNC's loader, from its rules: three numbers a line (it stops at the first line
    that is not), nominals strictly ascending, at most 256; type 0 gives actual positions
    (the trim the control adds is nominal - actual), type 1 the trims themselves."""
    nominal, forward_trim, reverse_trim = [], [], []
    for line in text.splitlines():
        parts = line.split()
        if len(parts) != 3:
            break
        nom, fwd, rev = (float(p) * 1e-3 for p in parts)        # machine units: mm
        assert not nominal or nom > nominal[-1]
        nominal.append(nom)
        forward_trim.append(nom - fwd if file_type == 0 else fwd)
        reverse_trim.append(nom - rev if file_type == 0 else rev)
    assert 2 <= len(nominal) <= 256 and len(nominal) == len(text.splitlines())
    return np.array(nominal), np.array(forward_trim), np.array(reverse_trim)


@pytest.mark.parametrize("file_type", [0, 1])
def test_linuxcnc_comp_file_round_trip(file_type):
    """Each COMP_FILE_TYPE through a reader written here: the machine commanded nominal +
    trim lands within the band of nominal, either way it moves (the reversal is in the
    file: a joint with COMP_FILE uses no BACKLASH)."""
    from mt_accuracy_ros.core.compensation.controller_tables import linuxcnc_comp_files

    model = _model().with_effect("reversal:X", {
        "family": "reversal", "variant": "X", "setting": {},
        "coefficients": {"backlash_m": 4e-6}})
    # 256 points a joint: over the HMC's strokes a coarser spacing than the band wants,
    # said by the choice with the error it leaves.
    choice = spacing_for(model, BAND, max_points=256)
    assert choice.limited_by and choice.spacing_m > 0.01 / POINTS_PER_PERIOD
    texts, ini = linuxcnc_comp_files(model, choice.spacing_m, file_type=file_type)
    assert set(texts) == {"X.comp", "Y.comp", "Z.comp"}
    assert ini["X"] == f"[JOINT_0]\nCOMP_FILE = X.comp\nCOMP_FILE_TYPE = {file_type}"
    nominal, forward_trim, reverse_trim = _read_linuxcnc(texts["X.comp"], file_type)
    x = np.linspace(0.0, 0.39, 5001)
    for trims, lag in ((forward_trim, -2e-6), (reverse_trim, 2e-6)):
        # Where the axis lands: command + trim, plus its error at the command.
        landed = np.interp(x, nominal, trims) + _truth(x) + lag
        assert np.max(np.abs(landed)) <= choice.errors_m["X"] + 1e-9
    with pytest.raises(ParameterError, match="LinuxCNC holds 256 a joint"):
        linuxcnc_comp_files(model, 0.001)
