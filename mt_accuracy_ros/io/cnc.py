"""Connections to a real CNC: where machine data comes from and where compensation goes.

The package talks to a machine through two small interfaces:

* a **machine-data source** - axis command positions [m, rad] and
  temperatures [degC] (:meth:`CncConnection.read`);
* a **compensation sink** - the TCP correction [m] the CNC adds to its
  command, with the model version and the stamp it was computed for
  (:meth:`CncConnection.write_compensation`).

The virtual machine tool is one such machine (its nodes speak the topics
directly); :class:`OpcUaCnc` is the other: a CNC's OPC UA server (most
controllers offer one: Siemens SINUMERIK, Heidenhain, Fanuc via
gateways), addressed by a **node map** - which OPC UA node holds which axis,
temperature and compensation input, and the unit of each. :func:`connect`
picks the connection by the URL's scheme, so a further protocol (MTConnect,
a fieldbus gateway) is one more class.

Values are converted to SI on the way in (``unit`` per node: ``m``, ``mm``,
``um``, ``rad``, ``deg``, ``degC``, ``K`` offset-free) and from SI on the way out.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

from ..core.errors import MALFORMED_INPUT, InputDataError, ParameterError

#: Factor to SI per unit name (temperatures: degC stays degC, as sensor_msgs/Temperature).
UNITS = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "rad": 1.0, "deg": 3.141592653589793 / 180.0,
         "degC": 1.0}


@dataclass(frozen=True)
class MappedNode:
    """One OPC UA node and the unit of its value."""

    node_id: str
    unit: str


@dataclass
class NodeMap:
    """Which OPC UA node is which quantity.

    ``axes``: axis name (``X``, ``B``, ...) -> node of its command position;
    ``temperatures``: sensor name -> node; ``compensation``: ``x``, ``y``, ``z``
    (the correction), optionally ``version`` (model version, UInt32) and
    ``stamp`` (the sample time it was computed for, ns since the epoch, Int64).
    """

    axes: dict[str, MappedNode] = field(default_factory=dict)
    temperatures: dict[str, MappedNode] = field(default_factory=dict)
    compensation: dict[str, MappedNode] = field(default_factory=dict)


def _mapped(where: str, value) -> MappedNode:
    if isinstance(value, str):
        value = {"node": value}
    if not isinstance(value, dict) or not isinstance(value.get("node"), str):
        raise ParameterError(f"{where}: expected a node id or {{node: ID, unit: UNIT}}")
    unit = str(value.get("unit", "degC" if where.startswith("temperatures") else
                         "rad" if where.startswith("axes.") and where[-1] in "ABC" else "m"))
    if unit not in UNITS:
        raise ParameterError(f"{where}: unknown unit {unit!r}; known: {', '.join(UNITS)}")
    return MappedNode(value["node"], unit)


def node_map_from_dict(data: dict, source: str = "<node map>") -> NodeMap:
    """A node map from its YAML form; raises :class:`ParameterError` naming the entry."""
    if not isinstance(data, dict):
        raise ParameterError(f"{source}: a node map is a mapping with axes, temperatures, "
                             "compensation")
    try:
        result = NodeMap(
            axes={str(k).upper(): _mapped(f"axes.{str(k).upper()}", v)
                  for k, v in (data.get("axes") or {}).items()},
            temperatures={str(k): _mapped(f"temperatures.{k}", v)
                          for k, v in (data.get("temperatures") or {}).items()},
            compensation={str(k): _mapped(f"compensation.{k}", v)
                          for k, v in (data.get("compensation") or {}).items()})
    except MALFORMED_INPUT as exc:
        raise ParameterError(f"{source}: {exc}") from exc
    if not result.axes:
        raise ParameterError(f"{source}: no axes mapped")
    missing = {"x", "y", "z"} - set(result.compensation)
    if missing:
        raise ParameterError(f"{source}: compensation needs nodes for x, y and z "
                             f"(missing {', '.join(sorted(missing))})")
    return result


def load_node_map(path: str | Path) -> NodeMap:
    import yaml

    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text())
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as exc:
        raise ParameterError(f"{path}: cannot read the node map ({exc})") from exc
    return node_map_from_dict(data, str(path))


class CncConnection(Protocol):
    """A machine-data source and compensation sink."""

    def read(self) -> tuple[dict[str, float], dict[str, float]]:
        """(axis -> command position [m or rad], sensor -> temperature [degC])."""

    def write_compensation(self, correction_m: tuple[float, float, float], version: int,
                           stamp_ns: int) -> None:
        """Hand the TCP correction [m] to the CNC."""

    def close(self) -> None:
        """Release the connection."""


class OpcUaCnc:
    """A CNC's OPC UA server through ``asyncua``'s synchronous client.

    Parameters
    ----------
    url : str
        ``opc.tcp://host:port/path``.
    node_map : NodeMap
    timeout_s : float
        Request timeout [s].
    """

    def __init__(self, url: str, node_map: NodeMap, timeout_s: float = 4.0) -> None:
        from asyncua import ua
        from asyncua.sync import Client

        self._ua = ua
        self.node_map = node_map
        self._client = Client(url, timeout=timeout_s)
        try:
            self._client.connect()
        except Exception as exc:  # noqa: BLE001 - refused, timed out, not OPC UA: one line
            # The client's own event-loop thread would keep the process alive.
            self._client._stop_own_tloop()  # noqa: SLF001
            raise InputDataError(f"no OPC UA server at {url}: {type(exc).__name__}: "
                                 f"{exc}") from exc
        try:
            self._axes = list(node_map.axes)
            self._sensors = list(node_map.temperatures)
            self._read_nodes = [self._client.get_node(node_map.axes[a].node_id)
                                for a in self._axes] + \
                [self._client.get_node(node_map.temperatures[s].node_id) for s in self._sensors]
            self._read_units = [UNITS[node_map.axes[a].unit] for a in self._axes] + \
                [UNITS[node_map.temperatures[s].unit] for s in self._sensors]
            self._write = {key: self._client.get_node(mapped.node_id)
                           for key, mapped in node_map.compensation.items()}
            # Fail now, naming the node, rather than at the first cycle.
            self.read()
        except Exception:
            self.close()
            raise

    def read(self) -> tuple[dict[str, float], dict[str, float]]:
        try:
            values = self._client.read_values(self._read_nodes)
        except Exception as exc:  # noqa: BLE001 - any server-side failure: one clear error
            raise InputDataError(f"OPC UA read failed: {type(exc).__name__}: {exc}") from exc
        scaled = []
        for node, value, factor in zip(self._read_nodes, values, self._read_units):
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise InputDataError(f"OPC UA node {node.nodeid.to_string()} holds "
                                     f"{type(value).__name__}, not a number")
            scaled.append(float(value) * factor)
        n = len(self._axes)
        return dict(zip(self._axes, scaled[:n])), dict(zip(self._sensors, scaled[n:]))

    def write_compensation(self, correction_m, version: int, stamp_ns: int) -> None:
        ua = self._ua
        nodes, values = [], []
        for key, value in zip("xyz", correction_m):
            nodes.append(self._write[key])
            values.append(ua.DataValue(ua.Variant(float(value) / UNITS[
                self.node_map.compensation[key].unit], ua.VariantType.Double)))
        if "version" in self._write:
            nodes.append(self._write["version"])
            values.append(ua.DataValue(ua.Variant(int(version), ua.VariantType.UInt32)))
        if "stamp" in self._write:
            nodes.append(self._write["stamp"])
            values.append(ua.DataValue(ua.Variant(int(stamp_ns), ua.VariantType.Int64)))
        try:
            self._client.write_values(nodes, values)
        except Exception as exc:  # noqa: BLE001
            raise InputDataError(f"OPC UA write failed: {type(exc).__name__}: {exc}") from exc

    def close(self) -> None:
        try:
            self._client.disconnect()
        except Exception:  # noqa: BLE001 - the server may be gone already
            self._client._stop_own_tloop()  # noqa: SLF001


def connect(url: str, node_map: NodeMap) -> CncConnection:
    """The connection for ``url``'s scheme (``opc.tcp://`` -> :class:`OpcUaCnc`)."""
    if url.startswith("opc.tcp://"):
        return OpcUaCnc(url, node_map)
    raise ParameterError(f"no CNC connection for {url!r}: supported opc.tcp://")
