"""Closed-form checks of the independent convention-survey generator.

Every expected value here is written from the physics (or from the documented
machine.yaml semantics, re-implemented below from the YAML text), not from the
generator's own code paths.
"""
import ast
import csv
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from studies import convention_surveys as cs  # noqa: E402

LEN = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "in": 0.0254}
ANG = {"rad": 1.0, "mrad": 1e-3, "urad": 1e-6, "deg": math.pi / 180, "arcsec": math.pi / 648000}


def rot(k, a):
    """Right-handed rotation by ``a`` [rad] about x (0), y (1) or z (2)."""
    c, s = math.cos(a), math.sin(a)
    return [np.array([[1, 0, 0], [0, c, -s], [0, s, c]]),
            np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]),
            np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])][k]


def machine(topology, seed=3, **setup_deg):
    """A drawn machine with chosen setup angles [deg] and no workpiece vector."""
    m = cs.build_machine(topology, np.random.default_rng(seed))
    m["work_vec"] = np.zeros(3)
    for k, v in setup_deg.items():
        m["setup"][k] = math.radians(v)
    return m


def rtest_rows(m, poses_deg, target):
    """RTCP rows following one sphere; the first pose is the setup pose."""
    target = np.asarray(target, float)
    q = [cs.solve_linear(m, {k: math.radians(v) for k, v in p.items()}, target)
         for p in poses_deg]
    return {"q": q, "target": np.tile(target, (len(q), 1)), "group": [0] * len(q),
            "setup": {0: 0}, "tool_setup": 0}


def sign_of(m, name):
    return next(a["sign"] for a in m["work"] + m["tool"] if a["name"] == name)


def test_offset_c_line_moves_point_by_i_minus_r_times_d():
    m = machine("trunnion_AC", A=0, C=45)
    d = np.array([23e-6, -14e-6, 0.0])
    angles = [45] + list(range(-180, 180, 15))
    rows = rtest_rows(m, [{"A": 0, "C": c} for c in angles], [0.08, -0.03, 0.05])
    pos, _ = cs.located_errors(m, {"C": {"offset": d}}, rows)
    s = sign_of(m, "C")
    for c, e in zip(angles, pos):
        moved = (np.eye(3) - rot(2, s * math.radians(c - 45))) @ d  # material moves
        np.testing.assert_allclose(e, -moved, atol=1e-12)          # tool - work
    assert np.abs(pos[0]).max() < 1e-15


def test_tilted_c_line_gives_tilt_times_radius_in_z_as_sine():
    m = machine("trunnion_BC", B=0, C=0)
    tau, r, h = 40e-6, 0.11, 0.07
    angles = list(range(0, 360, 15))
    rows = rtest_rows(m, [{"B": 0, "C": c} for c in angles], [r, 0.0, h])
    pos, _ = cs.located_errors(m, {"C": {"tilt": np.array([tau, 0.0, 0.0])}}, rows)
    s = sign_of(m, "C")
    expected = [-tau * r * math.sin(s * math.radians(c)) for c in angles]
    np.testing.assert_allclose(pos[:, 2], expected, atol=1e-9)
    assert np.abs(pos[:, 2]).max() > 0.9 * tau * r


def test_a_pivot_offset_reaches_the_point_through_the_cradle():
    m = machine("trunnion_AC", A=0, C=0)
    d = np.array([0.0, 17e-6, -31e-6])
    poses = [{"A": 0, "C": 0}] + [{"A": a, "C": c} for a in (-90, -40, 0, 20)
                                  for c in (0, 75, 210)]
    rows = rtest_rows(m, poses, [-0.05, 0.09, 0.12])
    pos, _ = cs.located_errors(m, {"A": {"offset": d}}, rows)
    s = sign_of(m, "A")
    for p, e in zip(poses, pos):  # whatever C does, the cradle carries the point
        np.testing.assert_allclose(e, -(np.eye(3) - rot(0, s * math.radians(p["A"]))) @ d,
                                   atol=1e-12)


def test_head_b_offset_moves_tool_by_i_minus_r_from_the_tool_setup():
    m = machine("mixed_table_head", B=30, C=0)
    d = np.array([-19e-6, 0.0, 27e-6])
    angles = [30, -90, -60, -20, 0, 45, 90]
    rows = rtest_rows(m, [{"B": b, "C": 0} for b in angles], [0.02, 0.05, 0.08])
    pos, _ = cs.located_errors(m, {"B": {"offset": d}}, rows)
    s = sign_of(m, "B")
    for b, e in zip(angles, pos):  # the tool side moves: tool - work takes +
        np.testing.assert_allclose(e, (np.eye(3) - rot(1, s * math.radians(b - 30))) @ d,
                                   atol=1e-12)


def test_table_pitch_turns_the_tool_direction_relative_to_the_work():
    m = machine("trunnion_AC", A=0, C=0)
    c0, c1 = 40e-6, 90e-6
    poly = np.zeros((3, 3))
    poly[1, :2] = c0, c1                      # EBX about the X carriage's y
    targets = np.random.default_rng(1).uniform([-0.1, -0.1, 0.02], [0.1, 0.1, 0.2], (12, 3))
    q = [cs.solve_linear(m, {"A": 0.0, "C": 0.0}, t) for t in targets]
    rows = {"q": q, "target": targets, "group": [0] * 12, "setup": {0: 0}, "tool_setup": 0}
    _, d = cs.located_errors(m, {"X": {"poly": poly}}, rows)
    eps = [c0 + c1 * qq["X"] for qq in q]     # tool along -z, seen from a table tilted by eps
    np.testing.assert_allclose(d[:, 0], np.sin(eps) - np.sin(eps[0]), atol=1e-14)
    np.testing.assert_allclose(d[:, 1], 0.0, atol=1e-14)


def test_c_zero_error_is_absorbed_by_locating_the_sphere():
    m = machine("trunnion_AC", A=-90, C=90)
    poses = [{"A": -90, "C": 90}] + [{"A": a, "C": c} for a in (-90, -30, 10) for c in (0, 135)]
    rows = rtest_rows(m, poses, [0.06, 0.04, 0.1])
    pos, _ = cs.located_errors(m, {"C": {"zero": 50e-6}}, rows)
    assert np.abs(pos).max() < 1e-12


@pytest.mark.parametrize("pivot", [[0.0, 0.0, 0.0], [0.1, 0.2, -0.3]])
def test_table_pitch_constant_part_acts_through_height_above_table(pivot):
    m = machine("vmc_3axis")
    x_ax = next(a for a in m["work"] if a["name"] == "X")
    c0, c1 = 35e-6, -80e-6                       # rad, rad/m: EBX = c0 + c1 q
    poly = np.zeros((3, 3))
    poly[1, :2] = c0, c1
    errs = {"X": {"poly": poly, "pivot": np.array(pivot)}}
    rng = np.random.default_rng(0)
    for _ in range(20):
        target = rng.uniform([-0.2, -0.2, 0.02], [0.2, 0.2, 0.3])
        q = cs.solve_linear(m, {}, target)
        v = x_ax["offset"] + target - pivot            # work point from the pivot
        eps = c0 + c1 * q["X"]
        ex = cs.raw_row(m, errs, q, target)["pos"][0]
        assert ex == pytest.approx(-eps * v[2], abs=1e-9)   # c0 h plus the varying part
        exact = -(math.sin(eps) * v[2] + (math.cos(eps) - 1.0) * v[0])
        assert ex == pytest.approx(exact, abs=1e-13)


# ------------------------------------------------------------ YAML semantics
def yaml_end(doc, names, vec, q):
    """Documented semantics: frames from the bed, moved by the parent's offset."""
    r, o = np.eye(3), np.zeros(3)
    for n in names:
        ax = doc["axes"][n]
        s = ax.get("sign", 1)
        if n in "XYZ":
            o = o + r @ (np.eye(3)["XYZ".index(n)] * s * q[n])
        else:
            r = r @ rot("ABC".index(n), s * q[n])
        o = o + r @ np.array(ax["offset"], float)
    return o, r


def yaml_tool_minus_target(doc, q, target):
    tokens = doc["chain"].strip("[]").split()
    work = tokens[tokens.index("w") + 1:tokens.index("b")][::-1]
    tool = tokens[tokens.index("b") + 1:tokens.index("t")]
    ot, rt = yaml_end(doc, tool, None, q)
    ow, rw = yaml_end(doc, work, None, q)
    tip = ot + rt @ np.array(doc["tool"], float)
    return tip - (ow + rw @ (np.array(doc["workpiece"], float) + target))


def si(value, unit):
    return np.asarray(value, float) * (LEN.get(unit) or ANG[unit])


def read_trial(folder):
    mp = yaml.safe_load((folder / "map.yaml").read_text())
    doc = yaml.safe_load((folder / "machine.yaml").read_text())
    with open(folder / "survey.csv") as fh:
        data = list(csv.DictReader(fh))
    q = [{n: float(si(float(r[c["column"]]), c["unit"])) for n, c in mp["positions"].items()}
         for r in data]
    return mp, doc, data, q


@pytest.mark.parametrize("topology", cs.TOPOLOGIES)
def test_machine_yaml_semantics_reproduce_nominal_and_the_survey(topology, tmp_path):
    for seed, inst in ((11, None), (12, "probing"), (13, "laser_tracker")):
        rng = np.random.default_rng(seed)
        trial = cs.draw_trial(rng, "t", topology, inst, n_rows=30)
        cs.write_trial(trial, tmp_path / str(seed), rng)
        mp, doc, data, q = read_trial(tmp_path / str(seed))
        m = trial["machine"]
        for _ in range(10):   # random commands anywhere in the strokes
            qq = {a["name"]: rng.uniform(*a["stroke"]) for a in m["work"] + m["tool"]}
            t = rng.uniform(-0.1, 0.1, 3)
            np.testing.assert_allclose(cs.nominal_relative(m, qq, t),
                                       yaml_tool_minus_target(doc, qq, t), atol=1e-12)
        tp = mp["target_point"]
        for row, qq in zip(data, q):  # the tool sits nominally on the declared target
            t = si(tp["value"], tp["unit"]) if "value" in tp else \
                si([float(row[tp["columns"][c]]) for c in "xyz"], tp["unit"])
            np.testing.assert_allclose(yaml_tool_minus_target(doc, qq, t), 0.0, atol=1e-9)


def test_errors_zero_at_setup_and_noise_declared(tmp_path):
    rng = np.random.default_rng(21)
    trial = cs.draw_trial(rng, "t", "trunnion_AC", "probing", n_rows=40, null=False)
    pos, _ = cs.located_errors(trial["machine"], cs.errs_from_effects(trial["effects"]),
                               trial["rows"])
    assert np.abs(pos[list(trial["rows"]["setup"].values())]).max() < 1e-15
    cs.write_trial(trial, tmp_path, rng)
    mp = yaml.safe_load((tmp_path / "map.yaml").read_text())
    u = mp["uncertainty"]
    assert si(u["value"], u["unit"]) >= 2 * trial["sigma_m"]


def test_same_seed_identical_files(tmp_path, capsys):
    for sub in ("a", "b"):
        cs.generate(tmp_path / sub, 3, 7, topology="vmc_3axis", n_rows=25)
    files = sorted(p.relative_to(tmp_path / "a") for p in (tmp_path / "a").rglob("*")
                   if p.is_file())
    assert len(files) == 3 * 4 + 1
    for f in files:
        assert (tmp_path / "a" / f).read_bytes() == (tmp_path / "b" / f).read_bytes()


def test_generator_imports_nothing_of_the_package():
    src = Path(cs.__file__).read_text()
    allowed = {"__future__", "argparse", "csv", "json", "math", "pathlib", "numpy", "yaml"}
    for node in ast.walk(ast.parse(src)):
        if isinstance(node, ast.Import):
            assert {a.name.split(".")[0] for a in node.names} <= allowed
        elif isinstance(node, ast.ImportFrom):
            assert node.module.split(".")[0] in allowed
    assert "mt_accuracy_ros" not in src and "importlib" not in src


# ------------------------------------------------------------ error conventions
def yaml_end_rotations(doc, q):
    """Nominal tool-side and work-side end orientations from machine.yaml's text."""
    tokens = doc["chain"].strip("[]").split()
    work = tokens[tokens.index("w") + 1:tokens.index("b")][::-1]
    tool = tokens[tokens.index("b") + 1:tokens.index("t")]
    return yaml_end(doc, tool, None, q)[1], yaml_end(doc, work, None, q)[1]


def column_triplet(mp, key, data):
    """The x, y, z columns of ``key`` (errors, direction_errors) in SI, n x 3."""
    spec = mp[key]
    return np.array([[float(si(float(r[spec[c]["column"]]), spec[c]["unit"])) for c in "xyz"]
                     for r in data])


def to_default(values, conv, doc, q):
    """Written errors back to the default convention: e = s R e_written (README's words)."""
    sign = (-1.0 if conv["of"] == "work" else 1.0) * (-1.0 if conv["as"] == "correction"
                                                      else 1.0)
    out = []
    for v, qq in zip(values, q):
        r_tool, r_work = yaml_end_rotations(doc, qq)
        r = {"machine": np.eye(3), "work": r_work, "tool": r_tool}[conv["frame"]]
        out.append(sign * r @ v)
    return np.array(out)


@pytest.fixture(scope="module")
def on_off(tmp_path_factory):
    """The first trials of one seed, with and without drawn error conventions."""
    root = tmp_path_factory.mktemp("conv")
    for sub, flag in (("on", True), ("off", False)):
        cs.generate(root / sub, 14, 2026, n_rows=40, error_conventions=flag)
    return root


def test_conventions_leave_every_other_draw_unchanged(on_off):
    seen = set()
    for k in range(14):
        on, off = on_off / "on" / f"trial_{k:03d}", on_off / "off" / f"trial_{k:03d}"
        assert (on / "machine.yaml").read_bytes() == (off / "machine.yaml").read_bytes()
        t_on, t_off = (json.loads((f / "truth.json").read_text()) for f in (on, off))
        conv = t_on["conventions"].pop("error_convention")
        written = t_on["conventions"].pop("error_convention_in_map")
        assert t_off["conventions"].pop("error_convention") == cs.DEFAULT_ERROR_CONVENTION
        assert t_off["conventions"].pop("error_convention_in_map") is False
        assert t_on == t_off
        mp_on, doc, d_on, q = read_trial(on)
        mp_off, _, d_off, q_off = read_trial(off)
        assert mp_on.pop("error_convention", None) == (conv if written else None)
        assert mp_on == mp_off and q == q_off
        assert list(d_on[0]) == list(d_off[0])         # same columns, same order
        moved = {mp_on["errors"][c]["column"] for c in "xyz"} | (
            {mp_on["direction_errors"][c]["column"] for c in "xyz"}
            if "direction_errors" in mp_on else set())
        for r_on, r_off in zip(d_on, d_off):          # positions, time, targets: bit for bit
            assert {c: v for c, v in r_on.items() if c not in moved} == \
                   {c: v for c, v in r_off.items() if c not in moved}
        for key in ("errors", "direction_errors"):
            if key in mp_on:
                back = to_default(column_triplet(mp_on, key, d_on), conv, doc, q)
                np.testing.assert_allclose(back, column_triplet(mp_off, key, d_off),
                                           rtol=0, atol=1e-12)
        seen.add((written, conv == cs.DEFAULT_ERROR_CONVENTION, conv["frame"]))
    # the draw reaches the omitted default, a written non-default in a turned frame
    assert (False, True, "machine") in seen and any(s[0] and s[2] != "machine" for s in seen)


def test_written_frames_turn_where_the_machine_turns(on_off):
    """A non-machine frame changes the written numbers on a five-axis rotary survey."""
    changed = 0
    for k in range(14):
        on = on_off / "on" / f"trial_{k:03d}"
        t = json.loads((on / "truth.json").read_text())
        conv = t["conventions"]["error_convention"]
        if conv["frame"] == "machine" or t["topology"] not in cs.FIVE_AXIS:
            continue
        mp, doc, data, q = read_trial(on)
        written = column_triplet(mp, "errors", data)
        read_as_machine = to_default(written, dict(conv, frame="machine"), doc, q)
        changed += bool(np.abs(read_as_machine - to_default(written, conv, doc, q)).max() > 1e-7)
    assert changed >= 1


@pytest.mark.parametrize("conv", [{"of": o, "as": a, "frame": f}
                                  for o in ("tool", "work") for a in ("deviation", "correction")
                                  for f in ("machine", "work", "tool")])
@pytest.mark.parametrize("topology", ["swivel_head_BC", "trunnion_AC"])
def test_each_convention_round_trips_and_matches_closed_form(conv, topology):
    m = machine(topology)
    rng = np.random.default_rng(5)
    tilt = "B" if topology == "swivel_head_BC" else "A"
    s = {n: sign_of(m, n) for n in (tilt, "C")}
    poses = [{tilt: float(b), "C": float(c)} for b, c in rng.uniform(-1.5, 1.5, (6, 2))]
    rows = {"q": [cs.solve_linear(m, p, np.zeros(3)) for p in poses],
            "target": np.zeros((6, 3))}
    r_tool, r_work = cs.nominal_end_rotations(m, rows)
    e = rng.normal(0.0, 20e-6, (6, 3))
    written = cs.to_error_convention(e, conv, r_tool, r_work)
    np.testing.assert_allclose(cs.from_error_convention(written, conv, r_tool, r_work), e,
                               rtol=0, atol=1e-18)
    sign = (-1.0 if conv["of"] == "work" else 1.0) * (-1.0 if conv["as"] == "correction"
                                                      else 1.0)
    for p, w, ee in zip(poses, written, e):
        # chains from the bed: the head's C carries B; the trunnion's A carries C
        turned = rot(2, s["C"] * p["C"]) @ rot(1, s["B"] * p["B"]) if tilt == "B" else \
            rot(0, s["A"] * p["A"]) @ rot(2, s["C"] * p["C"])
        r_tool, r_work = (turned, np.eye(3)) if tilt == "B" else (np.eye(3), turned)
        r = {"machine": np.eye(3), "work": r_work, "tool": r_tool}[conv["frame"]]
        np.testing.assert_allclose(w, sign * r.T @ ee, rtol=0, atol=1e-18)


def test_drawn_conventions_are_the_documented_words():
    draws = [cs.draw_error_convention(np.random.default_rng([7, k, 7])) for k in range(400)]
    default = [w for c, w in draws if c == cs.DEFAULT_ERROR_CONVENTION]
    assert 150 < len(default) < 250 and 0 < sum(default) < len(default)
    others = {tuple(c.values()) for c, w in draws if c != cs.DEFAULT_ERROR_CONVENTION}
    assert len(others) == 11 and all(w for c, w in draws if c != cs.DEFAULT_ERROR_CONVENTION)
    for c, _ in draws:
        assert set(c) == {"of", "as", "frame"}
        assert all(c[k] in cs.ERROR_CONVENTION_WORDS[k] for k in c)
