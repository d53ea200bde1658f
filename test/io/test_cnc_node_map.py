"""Node maps of a CNC's OPC UA server: units and refusals."""
from __future__ import annotations

from pathlib import Path

import pytest

from mt_accuracy_ros.core.errors import ParameterError
from mt_accuracy_ros.io.cnc import UNITS, connect, load_node_map, node_map_from_dict

EXAMPLE = Path(__file__).resolve().parents[2] / "config" / "cnc_nodes.example.yaml"


def test_the_example_node_map_loads_with_its_units():
    node_map = load_node_map(EXAMPLE)
    assert list(node_map.axes) == ["X", "Y", "Z"]
    assert node_map.axes["X"].unit == "mm" and UNITS["mm"] == 1e-3
    assert node_map.compensation["x"].unit == "um" and UNITS["um"] == 1e-6
    assert node_map.temperatures["column"].unit == "degC"


def test_default_units_are_si_and_rotary_axes_radians():
    node_map = node_map_from_dict({"axes": {"x": "ns=2;s=X", "B": "ns=2;s=B"},
                                   "compensation": {c: f"ns=2;s={c}" for c in "xyz"}})
    assert node_map.axes["X"].unit == "m" and node_map.axes["B"].unit == "rad"
    assert UNITS["deg"] == pytest.approx(0.017453292519943295, rel=1e-15)


@pytest.mark.parametrize("data, words", [
    ({"axes": {"X": {"node": "a", "unit": "inch"}},
      "compensation": {c: c for c in "xyz"}}, "unknown unit 'inch'"),
    ({"axes": {"X": "a"}, "compensation": {"x": "a"}}, "missing y, z"),
    ({"axes": {}, "compensation": {c: c for c in "xyz"}}, "no axes"),
    ({"axes": {"X": 42}, "compensation": {c: c for c in "xyz"}}, "axes.X"),
    ([1, 2], "a mapping")])
def test_bad_node_maps_are_refused_naming_the_entry(data, words):
    with pytest.raises(ParameterError, match=words):
        node_map_from_dict(data)


def test_an_unknown_scheme_is_refused():
    with pytest.raises(ParameterError, match="opc.tcp"):
        connect("mtconnect://cnc", node_map_from_dict({"axes": {"X": "a"}, "compensation": {
            c: c for c in "xyz"}}))
