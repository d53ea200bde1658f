"""The main jobs' outcome, recomputed from the bag by code that shares nothing with the
demo's own verdict: the reference readings decoded with the MCAP ROS 2 decoder Foxglove
uses (not the package's reader), the phases cut and the RMS taken here."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np


@dataclass
class Readings:
    """Every reference reading of a bag, in stamp order."""

    time_s: np.ndarray          # (N,) data time from the first reading [s]
    stamp_ns: np.ndarray        # (N,) the readings' stamps [ns]
    measured_m: np.ndarray      # (N, 3) what the instrument read on the compensated machine
    applied_m: np.ndarray       # (N, 3) the correction the CNC had added
    version: np.ndarray         # (N,) the model version live at the CNC
    uncertainty_m: np.ndarray   # (N,) the instrument's U (k = 2)
    direction_rad: np.ndarray | None   # (N, 3) measured tool-direction error (R-test)
    direction_applied_rad: np.ndarray | None
    direction_uncertainty_rad: np.ndarray | None


def read_references(bag: Path) -> Readings:
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    rows = []
    for path in sorted(Path(bag).glob("*.mcap")):
        with open(path, "rb") as stream:
            reader = make_reader(stream, decoder_factories=[DecoderFactory()])
            for _, _, _, m in reader.iter_decoded_messages(topics=["/reference/tcp_error"]):
                stamp = m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec
                rows.append((stamp, (m.error.x, m.error.y, m.error.z),
                             (m.applied_correction.x, m.applied_correction.y,
                              m.applied_correction.z), m.compensation_model_version,
                             m.uncertainty, m.orientation_measured,
                             (m.orientation_error.x, m.orientation_error.y,
                              m.orientation_error.z),
                             (m.applied_orientation_correction.x,
                              m.applied_orientation_correction.y,
                              m.applied_orientation_correction.z),
                             m.orientation_uncertainty))
    rows.sort(key=lambda r: r[0])
    stamps = np.array([r[0] for r in rows], dtype=np.int64)
    oriented = bool(rows) and all(r[5] for r in rows)
    return Readings(
        time_s=(stamps - stamps[0]) / 1e9, stamp_ns=stamps,
        measured_m=np.array([r[1] for r in rows]), applied_m=np.array([r[2] for r in rows]),
        version=np.array([r[3] for r in rows]), uncertainty_m=np.array([r[4] for r in rows]),
        direction_rad=np.array([r[6] for r in rows]) if oriented else None,
        direction_applied_rad=np.array([r[7] for r in rows]) if oriented else None,
        direction_uncertainty_rad=np.array([r[8] for r in rows]) if oriented else None)


def rms(values: np.ndarray) -> np.ndarray:
    """Per-column root mean square of (N, 3) values."""
    return np.sqrt(np.mean(np.asarray(values) ** 2, axis=0))


#: The end state's length [s of data]: the demo's (core/workbench/closed_loop.py
#: END_WINDOW_S), written out here so that a change there shows as a test failure.
END_WINDOW_S = 30.0


def end_rows(readings: Readings, window_s: float = END_WINDOW_S) -> np.ndarray:
    """The readings of the run's last ``window_s`` seconds (the end state)."""
    return readings.time_s >= readings.time_s[-1] - window_s


def least_u_of_rms(instrument_u_k2: float, count: int) -> float:
    """The smallest expanded uncertainty (k = 2) an RMS of ``count`` readings can have with
    an instrument of ``instrument_u_k2``: its instrument part alone, 2 (U/2) / sqrt(N).
    ISO 14253-1 shows conformance only when RMS + U <= band, so RMS + this <= band is a
    necessary condition the demo's "within" must meet, whatever its sampling part."""
    return float(instrument_u_k2) / np.sqrt(count)


def first_live_s(readings: Readings, version: int) -> float | None:
    """Data time [s] of the first reading the CNC took with ``version`` or later applied."""
    at = np.flatnonzero(readings.version >= version)
    return float(readings.time_s[at[0]]) if at.size else None


def run_bundled_main_job(base: Path, scenario: str) -> tuple[int, Path, str]:
    """A bundled scenario's main job in lockstep into ``base/out``: (exit code, the output
    folder, what it printed)."""
    import contextlib
    import io

    from mt_accuracy_ros.commands.demo import run_demo
    from mt_accuracy_ros.nodes._scenario import BUNDLED

    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        code = run_demo(out_dir=str(base / "out"), lockstep=True,
                        scenario=str(BUNDLED / f"{scenario}.yaml"))
    return code, base / "out", printed.getvalue()


def iso_14253_state(rms: float, u_k2: float, band: float) -> str:
    """The decision rule written out here, apart from the package's: within when
    RMS + U <= band, outside when RMS - U > band, else undecided."""
    if rms + u_k2 <= band:
        return "within"
    return "outside" if rms - u_k2 > band else "undecided"


def assert_the_verdict_follows_the_figures(code: int, summary: dict) -> str:
    """The end state's verdict in ``summary.json`` is the one its own figures give by
    ISO 14253-1, component by component and overall; the job passes (exit 0, no failure)
    exactly when conformance is shown. Returns the overall state."""
    band = summary["instrument_band_um"]
    figures = summary["closed_loop"][-1]["with_compensation"]
    states = {f"e_{c}": iso_14253_state(figures[c]["rms_um"], figures[c]["u_k2_um"], band)
              for c in "xyz"}
    direction = summary.get("tool_direction")
    if direction:
        end = direction["phases"][-1]["with_compensation"]
        states.update({f"direction about {c}": iso_14253_state(
            end[c]["rms_um"], end[c]["u_k2_um"], direction["band_urad"]) for c in "xyz"})
    by_component = summary["end_state_conformance_by_component"]
    assert {k: by_component[k] for k in states} == states, (by_component, states)
    overall = ("within" if all(s == "within" for s in states.values()) else
               "outside" if "outside" in states.values() else "undecided")
    assert summary["end_state_conformance"] == overall
    assert summary["end_state_within_band"] is (overall == "within")
    assert (code == 0) is (overall == "within"), (code, overall, summary["failures"])
    assert bool(summary["failures"]) is (overall != "within"), summary["failures"]
    return overall
