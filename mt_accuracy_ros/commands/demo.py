"""The main job on the virtual machine tool: the whole graph, recorded, and a report.

1. The virtual machine's installation calibration is simulated (laser, every
   20 mm) and written as the machine description the model starts from.
2. Separate processes: encoder and temperature publishers (the scenario
   ``demo``: warm-up, a Y guideway deterioration at 50 s, a column thermal drift
   and an X ball-screw pitch error the model does not hold), the yaw/systematic
   estimator, the compensation broadcaster, the model monitor and the recorder
   (MCAP). The virtual machine is a CNC that applies the broadcast compensation
   (``compensation_input``: real-time offset by default, or tables), so its
   reference instrument measures the compensated machine: the loop is closed.
3. This process runs the user, a node (:class:`..nodes.demo_user.DemoUser`) that
   listens like any ROS tool and acts: when the monitor names a missing effect, it
   asks the monitor to add it (its ``change_model`` service, answered once the
   version is made) and watches the machine's error fall. :func:`run_demo` starts the
   graph, spins it and summarises.
4. At the end: a printed summary - the TCP error per component without
   compensation, with the starting model's, after each model change, after the
   deterioration, and at the end of the run, each with its k = 2 uncertainty -
   ``report.html``, ``summary.json`` and the final model (``model.yaml``; the
   starting one is ``model_start.yaml``).
"""
from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np
import yaml


def _prepare(out: Path, scenario_name: str) -> Path:
    from ..nodes._scenario import resolve_scenario
    from ..sim.instruments import calibrate_machine
    from ..sim.machine_tool import simulate

    scenario = resolve_scenario(scenario_name)
    calibration = calibrate_machine(simulate(scenario, start_index=0, stop_index=1))
    (out / "machine_calibrated.yaml").write_text(yaml.safe_dump(calibration, sort_keys=False))
    model = out / "model_start.yaml"
    start = {"machine": "machine_calibrated.yaml", "effects": {"geometric": {}}}
    if scenario.work_offset:
        # The reference instrument is zeroed at the work offset, where the part is touched
        # off: the model's position errors are referred to it (the compensation never
        # moves the datum). What the calibration knows there is said with it.
        start["datum"] = dict(scenario.work_offset)
        start["datum_uncertainty_m"] = [float(v) for v in _datum_uncertainty(
            calibration, scenario.work_offset)]
    model.write_text(yaml.safe_dump(start, sort_keys=False))
    return model


#: The calibration's stated uncertainties (k = 2) beyond the laser's: a linear table
#: point's set-up and averaging (0.1 um) and a ball-bar squareness (1 urad).
CALIBRATION_LINEAR_FLOOR_M = 0.1e-6
CALIBRATION_SQUARENESS_RAD = 1.0e-6


def _datum_uncertainty(calibration: dict, datum: dict) -> list[float]:
    """(3,) [m] U (k = 2) of the calibrated model's error at the datum: the laser's
    stated accuracies (XM60, Kidani Table 3.3: 0.5 ppm of the travel from the axis' low
    end, (0.5 + 0.1 M) urad at M = 1 m) at each table there, carried to the tool."""
    from ..core.compensation.datum import calibration_uncertainty_at
    from ..core.kinematics.machine import machine_from_dict
    from ..sim.instruments import xm60_angular_accuracy_rad, xm60_linear_accuracy_m

    machine = machine_from_dict(calibration, "the calibration")

    def table(name: str, position: float) -> float:
        if name[1] in "ABC":
            return float(xm60_angular_accuracy_rad(0.0, 1.0))
        low = machine.axes[name[2]].stroke[0]
        return float(xm60_linear_accuracy_m(position - low)) + CALIBRATION_LINEAR_FLOOR_M

    return calibration_uncertainty_at(machine, datum, table, CALIBRATION_SQUARENESS_RAD).tolist()


#: The CNC's controller at rate 1: interpolation cycle, fixed input delay, staleness
#: limit [s of data]. The delay covers the graph's stamp-to-arrival latency at the
#: demo's batch period (docs/benchmarks.md). At ``rate_factor`` r the delay and the
#: limit are r times these in data time - the same in wall time, which is what the
#: host's processes keep (:func:`paced`).
CONTROLLER = {"controller_cycle_s": 0.001, "compensation_delay_s": 0.02,
              "max_compensation_age_s": 0.5}
#: A model reaching the machine less than this before the run's end [s of data] came
#: too late for the end state to show it.
LATE_MODEL_S = 20.0
#: Wall seconds the demo waits for every node to be up before starting the machine.
GRAPH_READY_TIMEOUT_S = 60.0
#: Wall seconds between the start stamp being set and the machine's sample 0.
START_LEAD_S = 1.0
#: Niceness of the compensation path's nodes (CNC, estimator, broadcaster): the CPU
#: first while the monitor searches or the host is loaded (nodes/_priority.py).
PATH_NICENESS = -15
#: Scale batch period of the demo's machine at rate 1 [s]: 100 batches a second, as a
#: CNC's position stream comes (times the rate in data time, :func:`paced`).
BATCH_PERIOD_S = 0.01


def paced(rate_factor: float) -> dict:
    """The machine's batch period and the controller's delays at ``rate_factor`` [s of
    data]: the same wall-clock cadence and deadlines at every rate (at rate 3 the graph
    has a third of the wall time per data second, so its data-time latency triples)."""
    scale = max(1.0, float(rate_factor))
    return {"batch_period_s": BATCH_PERIOD_S * scale,
            "controller_cycle_s": CONTROLLER["controller_cycle_s"],
            "compensation_delay_s": CONTROLLER["compensation_delay_s"] * scale,
            "max_compensation_age_s": CONTROLLER["max_compensation_age_s"] * scale}
#: The reference instrument's reading period [s]: not a divisor of the program's
#: 5.85 s cycle, so that the readings land on new positions every cycle (at 0.5 s
#: they would revisit 24 positions, too few to resolve a 10 mm screw pitch).
REFERENCE_PERIOD_S = 0.37


#: The monitor checks the model every this many reference readings (11.1 s of data).
MONITOR_CHECK_EVERY = 30


#: The lockstep participants and what each must have handled before the machine
#: streams on (nodes/_lockstep.py): with them every node sees the same data in the same
#: order and every decision falls at the same data time, whatever the host's speed.
LOCKSTEP_NODES = ["yaw_estimator:scales", "compensation_broadcaster:compensation",
                  "model_monitor:reference", "temperature_publisher:temperatures",
                  "demo_user:checks"]


#: Subscriptions the machine holds its streams for, so that the bag holds the run from
#: its first sample: scales go to the estimator, broadcaster and recorder; temperatures
#: also to the monitor.
SCALES_CONSUMERS = 3
TEMPERATURE_CONSUMERS = 4
#: Wall seconds between the run's progress lines.
PROGRESS_EVERY_S = 5.0


def run_demo(out_dir: str = "demo_output", rate_factor: float = 1.0,
             scenario: str = "demo", compensation_mode: str = "hybrid",
             path_niceness: int = PATH_NICENESS, lockstep: bool = False) -> int:
    """The main job; with ``lockstep`` the machine streams in data time, each batch once
    every node of the loop has caught up, so the outcome is the same on any host
    (``rate_factor`` then plays no part: the run goes as fast as the graph can).

    Starts the graph (the nodes' processes and the user, :class:`..nodes.demo_user.
    DemoUser`, in this one), spins it until the machine has streamed its scenario and
    the monitor has judged every reading, then summarises (printed, ``summary.json``,
    ``report.html``). Returns the exit code: 1 when the job failed (:func:`demo_failures`).
    """
    import rclpy
    from rclpy.parameter import Parameter

    from ..nodes._common import node_executor
    from ..nodes._scenario import resolve_scenario
    from ..nodes.demo_user import DemoUser

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    bag = out / "bag"
    if bag.exists():
        import shutil

        shutil.rmtree(bag)
    started = time.monotonic()
    chosen = resolve_scenario(scenario)
    print(f"mt_accuracy_ros demo - virtual {chosen.machine.name}, scenario '{scenario}' "
          f"({chosen.description}); the CNC applies the compensation ({compensation_mode}); "
          f"{chosen.duration_s:.0f} s of data " + (
              "in lockstep (data time: every node keeps up, the host's speed changes only "
              "the wall time)" if lockstep else f"at {rate_factor:g}x"), flush=True)
    if lockstep:
        rate_factor = 1.0   # the controller's real-time delays, in data time
    model = _prepare(out, scenario)
    five_axis = any(spec.is_rotary for spec in chosen.machine.axes.values())
    nodes, encoder = _start_nodes(model, bag, scenario, compensation_mode, rate_factor,
                                  path_niceness, lockstep, five_axis)
    rclpy.init()
    # The user asks the monitor through its change_model service: answered once the
    # effects are fitted and live, with the version made.
    user = DemoUser(parameter_overrides=[
        Parameter("rate_factor", value=float(rate_factor)),
        Parameter("lockstep", value=bool(lockstep))])
    # The user's own executor for the whole run: rclpy.spin_once(user) would add and
    # remove it at every call (the wait set rebuilt each time), and rclpy's global executor
    # outlives a context - in a process that ran rclpy before (a test worker) it woke
    # only on its timeout, and the lockstep machine went 7 times slower.
    executor = node_executor(user)
    console = _Console(user, started)
    try:
        # The corrections go to the CNC (when it takes them in real time) and the recorder:
        # the run counts them from the bag.
        _drive(user, executor, encoder, lockstep, console,
               1 + (compensation_mode in ("realtime", "hybrid")))
    finally:
        dead_nodes = _stop_graph(encoder, nodes, console)
        executor.shutdown()
        user.destroy_node()
        rclpy.try_shutdown()
    summary, story = _conclude(out, user, scenario, compensation_mode, five_axis, lockstep,
                               time.monotonic() - started, dead_nodes)
    return _print_summary(out, summary, story, rate_factor)


def _start_nodes(model: Path, bag: Path, scenario: str, compensation_mode: str,
                 rate_factor: float, path_niceness: int, lockstep: bool,
                 five_axis: bool) -> tuple[list, object]:
    """Start the graph's processes: the recorder, the estimator, the broadcaster, the
    monitor, the thermometers and (its streams held until the run's start stamp is set)
    the virtual machine. Returns (the others, the machine) as
    :class:`.processes.NodeProcess`."""
    from .processes import start_node

    calibrated_machine = (model.parent / "machine_calibrated.yaml").resolve()
    # The machine's clock starts once every node is up (:func:`_drive`): started at a
    # fixed moment, a node still importing would meet a backlog of seconds of data, every
    # correction of it stale on arrival.
    machine = {"scenario": scenario, "start_stamp_ns": -1, "rate_factor": rate_factor}
    path = {"niceness": int(path_niceness)}
    step = {"lockstep": True} if lockstep else {}
    # A lockstep run's pacing reports (several per batch) are run control, not data: the
    # bag holds what a real-time run's holds.
    recording = {"exclude_topics": ["/lockstep", "/lockstep/stream"]} if lockstep else {}
    nodes = [start_node("recorder", {"output": str(bag), "discovery_period_s": 0.2,
                                     **recording}, quiet=True),
             # The estimator reads the virtual machine's own strokes and scale distances:
             # with another machine's its yaw (Kidani eq. 2.13, over the scales' distance D) and
             # its profile's grid were another machine's, and the profile that replaced
             # the calibration after the baseline held a constant beyond that grid.
             start_node("yaw_estimator", {"machine": str(calibrated_machine),
                                          "baseline_after_s": 40.0, **path, **step}, quiet=True),
             start_node("compensation_broadcaster", {"model": str(model), **path, **step},
                        quiet=True),
             # 300 readings = the whole run; a check every 30 readings (each names
             # effects from ~150 candidates, ~1-2 s of CPU) leaves the CPU to the loop.
             # A five-axis machine has more ways to be out of place (each rotary axis'
             # location and runout, besides the structure's drift): up to 5 at once.
             # The monitor renews the added effects' numbers by itself once more
             # readings predict better (auto_refit): a drift named over the first 2 K
             # of warming is refitted over the whole warm-up.
             start_node("model_monitor", {"model": str(model), "window": 300,
                                          "check_every": MONITOR_CHECK_EVERY, "auto_refit": True,
                                          "max_effects": 5 if five_axis else 3, **step},
                        quiet=True),
             start_node("temperature_publisher",
                        {**machine, "min_subscribers": TEMPERATURE_CONSUMERS, **step},
                        quiet=True)]
    if lockstep:
        step["lockstep_nodes"] = LOCKSTEP_NODES
    encoder = start_node("encoder_publisher", {
        **machine, "min_subscribers": SCALES_CONSUMERS, "compensation_input": compensation_mode,
        "reference_period_s": REFERENCE_PERIOD_S, **paced(rate_factor), **path, **step},
        quiet=True)
    return nodes, encoder


class _Console:
    """The run's progress line, every :data:`PROGRESS_EVERY_S` of wall time: feedback
    while it runs (data time, the model live at the machine, checks, stale count)."""

    def __init__(self, user, started: float) -> None:
        self.user = user
        self.started = started
        self.next = time.monotonic() + PROGRESS_EVERY_S

    def tick(self) -> None:
        from ..nodes.demo_user import progress_line

        if time.monotonic() < self.next:
            return
        self.next += PROGRESS_EVERY_S
        user = self.user
        print(progress_line(time.monotonic() - self.started, user.references, user.models,
                            len(user.checks), user.delivery.get(
                                "/encoder_publisher:compensation", {})), flush=True)


def _drive(user, executor, encoder, lockstep: bool, console: _Console,
           compensation_consumers: int) -> None:
    """Start the machine once the graph is up; spin until it has streamed its scenario,
    then until the monitor has judged every reading - the user looking after each
    wake-up."""
    from .model_tools import set_remote_parameter

    def graph_ready() -> bool:
        return user.sees_graph_ready(SCALES_CONSUMERS, TEMPERATURE_CONSUMERS,
                                     compensation_consumers)

    ready_by = time.monotonic() + GRAPH_READY_TIMEOUT_S
    while not graph_ready() and time.monotonic() < ready_by:
        executor.spin_once(timeout_sec=0.05)
        console.tick()
    if not graph_ready():
        print(f"  WARNING the graph was not complete after {GRAPH_READY_TIMEOUT_S:.0f} s; "
              "starting the machine anyway", flush=True)
    start_ns = time.time_ns() + int(START_LEAD_S * 1e9)
    user.start(start_ns)
    for publisher in ("/encoder_publisher", "/temperature_publisher"):
        # The same stamp twice changes nothing: asked again while unanswered.
        ok, reason = set_remote_parameter(user, publisher, "start_stamp_ns", start_ns,
                                          resend_after_s=2.0, executor=executor)
        if not ok:
            raise RuntimeError(f"could not start {publisher}: {reason}")
    # Lockstep has no pace to keep: bounded only so that a hung graph still ends.
    deadline = time.monotonic() + (1800.0 if lockstep else 90.0 / user.rate_factor + 60.0)
    while time.monotonic() < deadline and encoder.popen.poll() is None:
        _wake(user, executor, console)
    # Drain: a monitor that fell behind on a loaded host still judges every reading
    # before the graph stops, so how many checks the run gets does not depend on the
    # host's speed (bounded; its delivery counters come once a second).
    settle = time.monotonic() + 2.0
    drain = time.monotonic() + 60.0
    while time.monotonic() < settle or (not user.monitor_done() and time.monotonic() < drain):
        _wake(user, executor, console)


def _wake(user, executor, console: _Console) -> None:
    """One wake-up of the run: the graph's callbacks, the progress line, the user's look."""
    from ..nodes.demo_user import action_line

    executor.spin_once(timeout_sec=0.05)
    console.tick()
    action = user.act()
    if action is not None:
        print(action_line(action), flush=True)


def _stop_graph(encoder, nodes: list, console: _Console | None = None) -> list[str]:
    """Stop every process of the graph; returns the nodes that died during the run. The
    progress line goes on meanwhile (a loaded host's recorder may take a while)."""
    # A node that died during the run (killed, crashed) is named: its absence explains
    # frozen profiles or a silent monitor, and the run cannot be called a success.
    # (The virtual machine's publishers end by themselves, with 0, when the scenario
    # is over: a clean end, not a death.)
    dead_nodes = [f"{p.name} (exit {_exit_text(p.popen.returncode)})"
                  for p in [encoder, *nodes] if p.popen.poll() not in (None, 0)]
    encoder.stop()
    for process in nodes:
        # The recorder may still be writing a backlog on a loaded host: time to close
        # its file rather than a kill that leaves it unreadable.
        process.stop(timeout_s=60.0 if process.name == "recorder" else 10.0,
                     while_waiting=None if console is None else console.tick)
    return dead_nodes


def _conclude(out: Path, user, scenario: str, compensation_mode: str, five_axis: bool,
              lockstep: bool, wall_s: float, dead_nodes: list[str]) -> tuple[dict, dict]:
    """The run's story and summary from what the user heard and the bag recorded (the
    final model saved as ``model.yaml``). Returns (summary, story)."""
    from .check_timing import check_timeliness

    bag = out / "bag"
    losses = delivery_losses(user.delivery)
    warnings = warning_lines(user.node_warnings)
    references, orientations = user.references, user.orientations
    # The headline is computed from the record - the bag the report is made from - so
    # that the summary and the report tell one story, reading for reading.
    try:
        recorded = _recorded_references(bag, user.start_ns)
    except Exception as exc:  # noqa: BLE001 - an unreadable bag: the listener's readings stand
        losses.append(f"the bag's reference readings could not be read ({type(exc).__name__}: "
                      f"{exc}): the headline is this listener's")
        recorded = ([], [])
    if recorded[0]:
        if len(recorded[0]) != len(references):
            losses.append(f"the bag holds {len(recorded[0])} reference readings, this listener "
                          f"received {len(references)}: the headline is the bag's")
        references, orientations = recorded
    if user.models:
        # The saved model is the final one, every effect added with its parameters.
        (out / "model.yaml").write_text(user.models[-1][1].model_yaml)
    story = loop_story(references, user.models, user.alarms,
                       compensation_mode=compensation_mode,
                       orientations=orientations if any(o is not None for o in orientations)
                       else None, five_axis=five_axis)
    # A reading without a tool direction on a five-axis machine: a warning everywhere.
    warnings += story.get("warnings", [])
    print("  the run is over; writing the report", flush=True)
    # In lockstep the machine waits for every check: only a paced run can be late.
    timing = None if lockstep else check_timeliness(
        [t for t, _ in user.checks], user.check_arrivals,
        MONITOR_CHECK_EVERY * REFERENCE_PERIOD_S)
    if timing is not None:
        timing["search_wall_s"] = [round(w, 3) for w, _ in user.searches]
        timing["search_cpu_s"] = [round(c, 3) for _, c in user.searches]
    try:
        compensation = _recorded_compensation(bag)
    except Exception as exc:  # noqa: BLE001 - an unreadable bag: said, none counted
        losses.append(f"the bag's compensation messages could not be read "
                      f"({type(exc).__name__}: {exc}): none are counted")
        compensation = []
    summary = _summarise(out, user.checks, user.alarms, user.actions, compensation,
                         wall_s, references, losses, story, user.delivery, scenario,
                         [text for _, text in user.model_alarms], start_ns=user.start_ns,
                         dead_nodes=dead_nodes, check_timing=timing, warnings=warnings)
    return summary, story


def _print_summary(out: Path, summary: dict, story: dict, rate_factor: float) -> int:
    """Print the run's outcome; returns the exit code (1 when the job failed)."""
    from .check_timing import timeliness_line

    # The headline first: what the instrument measured on the compensated machine.
    for line in story["lines"]:
        print(line)
    for key, value in summary.items():
        if not isinstance(value, (list, dict)):
            print(f"  {key:42s} {value:.4g}" if isinstance(value, float) else
                  f"  {key:42s} {value}")
    print(f"  {'path_scheduling':42s} " + ("; ".join(
        f"{node}: {text}" for node, text in summary["path_scheduling"].items()) or "unknown"))
    for line in summary["warnings"]:
        # Overload is loud: a graph that could not keep up says so; so is every node's
        # warning and a reading the verdict could not use.
        print(f"  WARNING {line}")
    for text in summary["model_alarms"]:
        print(f"  ALARM {text}")
    if "check_timing" in summary:
        print("  " + timeliness_line(summary["check_timing"], rate_factor))
    print(f"  report: {out / 'report.html'}   bag: {out / 'bag'}   final model: "
          f"{out / 'model.yaml'}")
    failures = summary["failures"]
    for failure in failures:
        print(f"  FAILED: {failure}")
    return 1 if failures else 0


def late_warning(summary: dict) -> str:
    """The warning line when more than :data:`LATE_WARNING_SHARE` of the corrections
    arrived too late to apply ("" otherwise)."""
    stale, messages = summary["compensation_stale"], max(summary["compensation_messages"], 1)
    if stale <= LATE_WARNING_SHARE * messages:
        return ""
    window = summary["stale_between_s"]
    return (f"{stale} of {messages} corrections ({stale / messages:.1%}) arrived too late to "
            f"apply (warning above {LATE_WARNING_SHARE:.0%}): the real-time path missed its "
            "deadline on this host" + (
                f", between {window[0]:.1f} s and {window[1]:.1f} s of data (the oldest "
                f"{summary['worst_stale_age_ms']:.0f} ms late)" if window else ""))


#: Share of corrections arriving too late to apply above which the demo warns.
LATE_WARNING_SHARE = 0.01


def _recorded_references(bag: Path, start_ns: int) -> tuple[list[tuple], list[tuple]]:
    """The reference readings of the bag as the demo's listener holds them: (data time
    [s], measured (3,), applied (3,), version, uncertainty) and, where the tool's
    direction was measured, (measured (3,), applied (3,), uncertainty) [rad] (None for a
    reading without one)."""
    from ..io.bag_reader import decode, read_messages
    from ..nodes.demo_user import reference_entry

    references, orientations = [], []
    for m in (decode(m) for m in read_messages(bag, ["/reference/tcp_error"])):
        reading, orientation = reference_entry(m, start_ns)
        references.append(reading)
        orientations.append(orientation)
    return references, orientations


def _recorded_compensation(bag: Path) -> list[tuple[int, float]]:
    """The bag's compensation messages: (stamp [ns], the model's TCP error norm [m]) each.

    Read after the run rather than heard one by one (100 a second) by the user in this
    process: the recorder was subscribed before the machine streamed (the graph's
    readiness), so the bag holds every message a listener would have had.
    """
    from ..io.bag_reader import decode, read_messages
    from ..nodes._common import stamp_to_nanoseconds

    return [(stamp_to_nanoseconds(m.header.stamp),
             float(np.linalg.norm([m.error.x, m.error.y, m.error.z])))
            for m in (decode(m) for m in read_messages(bag, ["/compensation"]))]


def _exit_text(code: int | None) -> str:
    if code is None:
        return "running"
    return f"signal {-code}" if code < 0 else str(code)


def hear_warnings(node_warnings: dict[str, list[str]], status_name: str,
                  values: dict[str, str]) -> None:
    """Keep the warnings a ``<node>: delivery`` status carries, once each, in order: the
    demo user's rule (:func:`..nodes.demo_user.hear_warnings`)."""
    from ..nodes.demo_user import hear_warnings as hear

    hear(node_warnings, status_name, values)


def warning_lines(node_warnings: dict[str, list[str]]) -> list[str]:
    """The nodes' warnings as the summary's lines: '<node>: <warning>'."""
    return [f"{node.lstrip('/')}: {text}" for node, texts in sorted(node_warnings.items())
            for text in texts]


def _conformance_of(story: dict):
    """The story's overall end state (a story without one: undecided, nothing shown)."""
    from ..core.workbench.conformance import Conformance

    return Conformance(story.get("end_state_conformance", "undecided"))


def demo_failures(summary: dict, story: dict) -> list[str]:
    """Why the main job did not do its job (empty when it did): the command exits
    non-zero with these, whatever the host's speed."""
    out = []
    if summary.get("dead_nodes"):
        out.append(f"node(s) died during the run: {', '.join(summary['dead_nodes'])}")
    if not summary.get("model_checks"):
        out.append("the model monitor published no check")
    if not summary.get("bag_messages"):
        out.append("nothing was recorded")
    if summary.get("compensation_input", "hybrid") != "off" and \
            not summary.get("compensation_applied"):
        out.append("the loop never closed: the CNC applied no real-time correction "
                   f"({summary.get('compensation_stale', 0)} arrived too late to apply)")
    state = _conformance_of(story)
    if state.value != "within":
        unshown = [v["sentence"] for v in story.get("end_state_verdicts", [])
                   if v["conformance"] != "within"]
        why = (f"the end state's conformance to the instrument's band is not shown: it is "
               f"{state.value} (ISO 14253-1: RMS + U must not exceed the band)"
               + (": " + "; ".join(unshown) if unshown else ""))
        messages = int(summary.get("compensation_messages") or 0)
        stale = int(summary.get("compensation_stale") or 0)
        live_at, run_s = summary.get("added_version_live_at_s", -1), summary.get("run_data_s")
        if run_s and (live_at is None or live_at > run_s - LATE_MODEL_S):
            # On a loaded host the diagnosis and the gates fall behind the data, and the
            # model the user added arrives after the run's last phase.
            why += ("; the model the user added reached the machine "
                    + ("only after the run" if live_at is None else f"at {live_at:.0f} s of "
                       f"{run_s:.0f} s") + ": the monitor's diagnosis or the gates fell behind "
                    "the data (a loaded machine?)")
        if messages and stale > 0.1 * messages:
            # The machine then runs on corrections held from seconds before: the
            # host, not the model, is what failed.
            why += (f"; {stale} of {messages} corrections arrived too late to apply "
                    f"({100.0 * stale / messages:.0f} %): this host did not keep the "
                    "real-time path's deadline (a loaded machine?), the CNC held old ones")
        out.append(why)
    return out


def delivery_losses(delivery: dict[str, dict[str, str]]) -> list[str]:
    """Plain sentences for every stream a node lost or refused messages of.

    ``delivery`` maps a node to its latest ``<stream>.<counter>`` values
    (the ``<node>: delivery`` diagnostics).
    """
    lines = []
    for node, values in sorted(delivery.items()):
        if node.endswith(":compensation"):
            continue  # the controller's own status, not a stream
        streams = sorted({key.rsplit(".", 1)[0] for key in values if "." in key})
        for stream in streams:
            processed = int(values.get(f"{stream}.processed", "0"))
            lost = int(values.get(f"{stream}.lost", "0"))
            refused = int(values.get(f"{stream}.refused", "0"))
            if lost or refused:
                unit = "samples" if stream == "scales" else "messages"
                share = 100.0 * lost / max(1, lost + processed)
                lines.append(f"{node} lost {lost} of {lost + processed} {unit} of '{stream}' "
                             f"({share:.0f} %) and refused {refused} messages: it could not "
                             "keep up or the input was bad; the results above miss them")
    return lines


LABEL_WIDTH = 58


def table_row(label: str, cells: list[str], width: int = 20) -> str:
    """One aligned row of the printed phase table: a label that does not fit its column
    goes on a line of its own, so it never runs into the numbers."""
    numbers = "".join(f"{cell:>{width}s}" for cell in cells)
    if len(label) > LABEL_WIDTH - 2:
        return f"  {label}\n  {'':{LABEL_WIDTH}s}{numbers}"
    return f"  {label:{LABEL_WIDTH}s}{numbers}"


def loop_story(references, models, alarms, *, compensation_mode: str,
               orientations=None, five_axis: bool = False) -> dict:
    """The closed loop told in numbers: the machine's TCP error per phase of the run.

    ``references``: (data time [s], measured (3,), applied (3,), model version,
    uncertainty k = 2 [m]) per reading; ``models``: (time, ModelVersion);
    ``alarms``: (time [s], axis). A model version's phase starts at the first
    reading the CNC took with its compensation applied. ``orientations``
    (five-axis: one (measured (3,), applied (3,), uncertainty) [rad] per
    reading, None for one without) adds the tool-direction error per phase; on a
    ``five_axis`` machine the direction is judged too, and readings without one are a
    warning (``warnings``), never a silent fall-back to the tip alone.

    The end state is judged by ISO 14253-1 (:mod:`..core.workbench.conformance`):
    ``end_state_conformance`` "within" (conformance shown for every component),
    "outside" or "undecided"; ``end_state_within_band`` is True only when "within".
    """
    from ..core.workbench.closed_loop import COMPONENTS, loop_phases
    from ..core.workbench.conformance import Conformance, overall
    from ..core.workbench.statistics import format_with_uncertainty

    if len(references) < 10:
        return {"phases": [], "lines": ["  too few reference readings to tell the loop's story"],
                "end_state_within_band": False, "end_state_conformance": "undecided",
                "end_state_verdicts": [], "warnings": []}
    time_s = np.array([r[0] for r in references])
    order = np.argsort(time_s, kind="stable")
    time_s = time_s[order]
    measured = np.array([references[i][1] for i in order])
    applied = np.array([references[i][2] for i in order])
    versions = np.array([references[i][3] for i in order])
    band = float(np.median([r[4] for r in references]))
    reasons = {int(m.version): m.reason for _, m in models}
    events = []
    live = sorted({int(v) for v in versions if v > 0})
    for k, version in enumerate(live):
        first = float(time_s[np.argmax(versions == version)])
        label = f"starting model's compensation (v{version})" if k == 0 else \
            f"v{version}: {reasons.get(version, 'model change')}"
        events.append((first, label))
    if versions[0] == 0:
        events.insert(0, (float(time_s[0]), "before the first compensation arrived"))
    for when, axis in alarms:
        events.append((float(when), f"after the {axis.upper()} deterioration alarm"))
    phases = loop_phases(time_s, measured, applied, events, band)
    header = f"  {'TCP error at the reference points, RMS [um]':58s}" + "".join(
        f"{'e_' + c:>20s}" for c in COMPONENTS)
    lines = [f"  closed loop: the CNC applies the compensation ({compensation_mode}); the "
             f"reference instrument (U = {band * 1e6:.1f} um, k = 2) measures the machine", header]

    def row(label: str, figures) -> str:
        return table_row(label, [format_with_uncertainty(f.rms * 1e6, f.rms_u_k2 * 1e6, "")
                                 .replace(" (k = 2)", "").strip() for f in figures])

    whole = phases[0]
    lines.append(row(f"without compensation (whole run, {whole.count} readings)", whole.without))
    for phase in phases[1:]:
        span = f" [{phase.start_s:.0f}-{phase.end_s:.0f} s]"
        lines.append(row(f"{phase.label}{span}", phase.with_compensation))
    end = phases[-1]
    verdicts = end.verdicts(band)
    lines.append(f"  end of the run (last {end.end_s - end.start_s:.0f} s, {end.count} readings): "
                 "compensated TCP error against the instrument's band (ISO 14253-1: within "
                 "only when RMS + U <= band)")
    lines += [f"    {v.sentence()}" for v in verdicts]
    warnings: list[str] = []
    result_orientation = None
    if orientations is not None or five_axis:
        result_orientation, direction_verdicts = _direction_story(
            time_s, order, orientations, events, row, lines, warnings)
        # The five-axis end state is judged on both: the tool's tip and its direction.
        verdicts += direction_verdicts
    state = overall(v.state for v in verdicts)
    if result_orientation is not None and not result_orientation["end_verdicts"]:
        state = overall([state, Conformance.UNDECIDED])   # no direction: nothing shown
    lines.append(f"  end state: {_state_words(state)}")
    _datum_line(time_s, measured, end, band, lines)
    for when, axis in alarms:
        after = [p for p in phases if p.label.startswith(f"after the {axis.upper()}")]
        if after:
            lines.append(f"  the {axis.upper()} guideway deterioration was detected at "
                         f"{when:.1f} s; its measured yaw change enters the compensation "
                         "through the live profile (p2 = p1 - delta e); " + (
                             "absorbed: the end state is back within the band (conformance "
                             "shown)" if state is Conformance.WITHIN else
                             f"not shown absorbed by the end of the run (end state {state.value})"))
    return {"phases": [p.as_dict() for p in phases], "lines": lines,
            "end_state_within_band": state is Conformance.WITHIN,
            "end_state_conformance": state.value,
            "end_state_verdicts": [v.as_dict() for v in verdicts],
            "band_um": band * 1e6, "compensation_mode": compensation_mode,
            "orientation": result_orientation, "warnings": warnings}


def _state_words(state) -> str:
    """The overall end state in words (ISO 14253-1)."""
    from ..core.workbench.conformance import Conformance

    return {Conformance.WITHIN: "within the band - conformance shown for every component "
                                "(ISO 14253-1)",
            Conformance.OUTSIDE: "OUTSIDE the band - nonconformance shown for a component "
                                 "(ISO 14253-1): something the model lacks remains",
            Conformance.UNDECIDED: "UNDECIDED - conformance not shown for every component, "
                                   "nonconformance for none (ISO 14253-1): the uncertainty "
                                   "straddles the band"}[state]


def _direction_story(time_s, order, orientations, events, row, lines: list[str],
                     warnings: list[str]) -> tuple[dict, list]:
    """The tool-direction table and its end-state verdicts (five-axis), judged on the
    readings that carry a direction; a reading without one is a warning, never a silent
    fall-back to the tip alone. ``orientations``: one (measured, applied, U) [rad] or None
    per reading, in the readings' order (None: no reading has one)."""
    from ..core.workbench.closed_loop import COMPONENTS, loop_phases

    given = [orientations[i] if orientations is not None else None for i in order]
    has = np.array([o is not None for o in given], dtype=bool)
    if not has.all():
        warnings.append(f"{int((~has).sum())} of {has.size} reference readings carry no tool "
                        "direction: the direction is judged on the "
                        f"{int(has.sum())} that do" + (
                            "; with none, it is not judged and the end state's conformance "
                            "is not shown" if not has.any() else ""))
    if has.sum() < 10:
        return {"phases": [], "band_urad": float("nan"), "end_within_band": False,
                "end_conformance": "undecided", "end_verdicts": []}, []
    turned = np.array([o[0] for o in given if o is not None])
    turn = np.array([o[1] for o in given if o is not None])
    band_rad = float(np.median([o[2] for o in given if o is not None]))
    tilt = loop_phases(time_s[has], turned, turn, events, band_rad)
    lines.append(f"  {'tool direction error at the same readings, RMS [urad]':58s}"
                 + "".join(f"{'about ' + c:>20s}" for c in COMPONENTS))
    lines.append(row("without compensation (whole run)", tilt[0].without))
    for phase in tilt[1:]:
        lines.append(row(f"{phase.label} [{phase.start_s:.0f}-{phase.end_s:.0f} s]",
                         phase.with_compensation))
    end_tilt = tilt[-1]
    verdicts = end_tilt.verdicts(band_rad, unit="µrad", prefix="direction about ")
    lines.append(f"  end of the run (last {end_tilt.end_s - end_tilt.start_s:.0f} s): tool "
                 "direction error against the R-test's band (ISO 14253-1)")
    lines += [f"    {v.sentence()}" for v in verdicts]
    state = end_tilt.conformance(band_rad)
    return {"phases": [p.as_dict() for p in tilt], "band_urad": band_rad * 1e6,
            "end_within_band": state.value == "within", "end_conformance": state.value,
            "end_verdicts": [v.as_dict() for v in verdicts]}, verdicts


def _datum_line(time_s, measured, end, band: float, lines: list[str]) -> None:
    """The end state about its mean, judged against the band: an R-test or probe is zeroed
    on the part, so a constant offset of the whole end state is a datum (what a
    work-offset touch-off takes out); its spread is not."""
    from ..core.workbench.closed_loop import COMPONENTS
    from ..core.workbench.conformance import judge, overall
    from ..core.workbench.statistics import rms_with_uncertainty

    in_end = (time_s >= end.start_s) & (time_s <= end.end_s)
    if np.count_nonzero(in_end) < 3:
        return
    mean = measured[in_end].mean(axis=0)
    verdicts = []
    for j, c in enumerate(COMPONENTS):
        f = rms_with_uncertainty(measured[in_end, j] - mean[j], band, seed=70 + j)
        verdicts.append(judge(f"e_{c}", f.rms * 1e6, f.rms_u_k2 * 1e6, band * 1e6, "µm"))
    lines.append("  end state about its mean (the datum a work-offset touch-off takes out: "
                 + ", ".join(f"{m * 1e6:+.2f}" for m in mean) + " um): spread "
                 + "; ".join(f"{v.name} {v.rms:.2f} ± {v.u_k2:.2f} um" for v in verdicts)
                 + f" - {_BAND_WORDS[overall(v.state for v in verdicts).value]} (ISO 14253-1)")


#: An overall state as the printed lines say it of the band.
_BAND_WORDS = {"within": "within the band", "outside": "outside the band",
               "undecided": "undecided against the band"}


def rotary_location_identified(model_path: Path, machine) -> str:
    """What the final model says of where the rotary axes really are (ISO 230-7): each
    location error with its k = 2 uncertainty, and why the zero-angle errors are not
    among them ("" on a machine without rotary axes or without such an effect)."""
    import yaml

    rotary = [a for a in machine.axis_order if machine.axes[a].is_rotary]
    if not rotary or not model_path.is_file():
        return ""
    effects = (yaml.safe_load(model_path.read_text()) or {}).get("effects", {}) or {}
    parts = []
    for name, entry in effects.items():
        if not (isinstance(entry, dict) and entry.get("family") == "rotary_location"):
            continue
        values, spread = entry.get("coefficients", {}), entry.get("uncertainties", {})
        for error, value in values.items():
            offset = error[1] in "XYZ"
            scale, unit = (1e6, "um") if offset else (1e6, "urad")
            parts.append(f"{error} {value * scale:+.1f} ± {2 * spread.get(error, 0.0) * scale:.1f}"
                         f" {unit}")
    if not parts:
        return ""
    zeros = ", ".join(f"E{a}0{a}" for a in rotary)
    return (f"rotary axes' location errors identified (ISO 230-7, U k = 2): {'; '.join(parts)}"
            f"; not identifiable: {zeros} (zero-angle errors: taken out by the set-up at "
            f"{', '.join(f'{a} = {np.degrees(machine.setup_angle(a)):g} deg' for a in rotary)}"
            "; an outer axis' zero error shows as the tilt of the axis it carries)")


def table_tilts(machine, effects: list[str]) -> list[str]:
    """The named effects that tilt an axis carrying the workpiece, each with what it is
    (e.g. 'angular:EBX (the X table's pitch)')."""
    out = []
    for name in effects:
        family, _, variant = str(name).partition(":")
        if family not in ("angular", "angular_periodic", "angular_arm") or len(variant) != 3:
            continue
        axis = variant[2]
        if axis not in machine.workpiece_branch or machine.axes[axis].is_rotary:
            continue
        about = "XYZ"["ABC".index(variant[1])]
        kind = "roll" if about == axis else ("yaw" if about == "Z" else "pitch")
        if axis == "Z":
            kind = "roll" if about == "Z" else "tilt"
        out.append(f"{name} (the {axis} table's {kind})")
    return out


def _pooled_rms_um(phase: dict | None, kind: str) -> float:
    """[um] The per-component RMS of a phase of the loop table, pooled over x, y, z (NaN
    without the phase): one way everywhere."""
    return float(np.sqrt(np.mean([phase[kind][c]["rms_um"] ** 2 for c in "xyz"]))) \
        if phase else float("nan")


def _summarise(out: Path, checks, alarms, actions, compensation, wall_s: float,
               references, losses: list[str], story: dict, delivery: dict,
               scenario: str = "demo", model_alarms: list[str] | None = None,
               start_ns: int = 0, dead_nodes: list[str] | None = None,
               check_timing: dict | None = None, warnings: list[str] | None = None) -> dict:
    """The run's figures (``summary.json``, written with the report): see
    :func:`_close_summary`."""
    from ..io.bag_reader import bag_info
    from ..nodes._scenario import resolve_scenario

    info = bag_info(out / "bag")
    before = [c.rmse for t, c in checks if not actions or t < actions[0]["time_s"]]
    # The checks right after the change (before anything else happens to the machine).
    after = [c.rmse for t, c in checks if actions and t > actions[0]["time_s"]][:2]
    end = story["phases"][-1] if story["phases"] else None
    whole = story["phases"][0] if story["phases"] else None
    controller = delivery.get("/encoder_publisher:compensation", {})
    pooled = _pooled_rms_um
    mode = story.get("compensation_mode", "hybrid")
    closed = mode == "off" or int(controller.get("applied", 0)) > 0 or \
        (mode == "table" and int(controller.get("tables_applied", 1)) > 0)
    summary = {
        # The headline is the instrument's measurement of the machine (the loop table).
        "headline": "measured by the reference instrument on the compensated machine"
        if closed else "measured by the reference instrument; the loop did NOT close (the "
        "CNC applied no real-time correction): 'compensated' is the machine with only what "
        "reached it",
        "loop_closed": bool(closed),
        "tcp_error_uncompensated_rms_um": pooled(whole, "without_compensation"),
        "tcp_error_compensated_rms_um": pooled(whole, "with_compensation"),
        "tcp_error_end_state_rms_um": pooled(end, "with_compensation"),
        # ISO 14253-1: "within" only when RMS + U <= band for every component (and the
        # tool's direction on a five-axis machine); the old key is True only then.
        "end_state_conformance": _conformance_of(story).value,
        "end_state_verdict": _state_words(_conformance_of(story)),
        "end_state_conformance_by_component": {
            v["name"]: v["conformance"] for v in story.get("end_state_verdicts", [])},
        "end_state_verdicts": [v["sentence"] for v in story.get("end_state_verdicts", [])],
        "end_state_within_band": _conformance_of(story).value == "within",
        "compensation_input": story.get("compensation_mode", "hybrid"),
        "instrument_band_um": story.get("band_um", float("nan")),
        "model_checks": len(checks),
        # A second, labelled figure: the monitor's offline residual (reference - model).
        "offline_residual_rmse_before_um": float(np.mean(before[-3:]) * 1e6) if before
        else float("nan"),
        "missing_effect_found": actions[0]["added"] if actions else "",
        "missing_effects_found": actions[0]["effects"] if actions else [],
        "table_tilts_named": table_tilts(resolve_scenario(scenario).machine,
                                         actions[0]["effects"]) if actions else [],
        "rotary_location_identified": rotary_location_identified(
            out / "model.yaml", resolve_scenario(scenario).machine),
        "where_the_residual_lived": actions[0]["where"] if actions else "",
        "effect_added_accepted": bool(actions and actions[0]["accepted"]),
        "offline_residual_rmse_after_um": float(np.mean(after) * 1e6) if after
        else float("nan"),
        "offline_residual_rmse_end_um": checks[-1][1].rmse * 1e6 if checks else float("nan"),
        "deterioration_alarm_axis": ",".join(a[1] for a in alarms),
        "deterioration_alarm_at_s": alarms[0][0] if alarms else float("nan"),
        "compensation_messages": len(compensation),
        "compensation_applied": int(controller.get("applied", 0)),
        "compensation_stale": int(controller.get("stale", 0)),
        # Corrections the CNC never received (a gap in ``sequence``): it subscribes best
        # effort, so a correction lost in transport is skipped, not waited for.
        "compensation_lost": int(delivery.get("/encoder_publisher", {}).get(
            "compensation.lost", "0")),
        "compensation_latency_p99_ms": float(controller.get("latency_p99_ms", "nan")),
        # When the path missed its deadline (data time) and by how much.
        "stale_between_s": [round((int(controller[key]) - start_ns) / 1e9, 2)
                            for key in ("first_stale_stamp_ns", "last_stale_stamp_ns")]
        if int(controller.get("first_stale_stamp_ns", -1)) >= 0 else [],
        "worst_stale_age_ms": float(controller.get("worst_stale_age_ms", 0.0)),
        # What each node on the compensation path ran at (its niceness, or why not).
        "path_scheduling": {node.lstrip("/"): values["scheduling"]
                            for node, values in sorted(delivery.items())
                            if "scheduling" in values},
        "max_model_tcp_error_um": max((e for _, e in compensation), default=0.0) * 1e6,
        "bag_messages": int(info["message_count"]),
        "bag_topics": len(info["topics"]),
        "wall_time_s": wall_s,
        "final_diagnosis": checks[-1][1].diagnosis if checks else "",
        "stream_losses": "; ".join(losses) or "none: every node processed every sample",
        "closed_loop": story["phases"],
        "model_alarms": list(model_alarms or []),
        "tool_direction": story.get("orientation"),
    }
    if actions and actions[0]["accepted"]:
        # When the user's model reached the machine (data time of the first reading it
        # compensated): a monitor or gate that fell behind the data makes it late.
        summary["added_version_live_at_s"] = next(
            (round(t, 1) for t, _, _, version, _ in references
             if t > actions[0]["time_s"] and version > 1), None)
        summary["run_data_s"] = float(resolve_scenario(scenario).duration_s)
    # Everything the command prints as a warning or a failure is in the summary and the
    # report too: the dead nodes, a late real-time path, every loss.
    summary["dead_nodes"] = list(dead_nodes or [])
    if check_timing is not None:
        summary["checks_late"] = check_timing["late"]
        summary["check_latency_max_s"] = check_timing["latency_max_s"]
        summary["check_timing"] = check_timing
    return _close_summary(out, summary, story, checks, actions, alarms, losses, scenario,
                          warnings or [])


def _close_summary(out: Path, summary: dict, story: dict, checks, actions, alarms,
                   losses: list[str], scenario: str, warnings: list[str]) -> dict:
    """The summary's warnings and failures, the report (a failure without a readable bag),
    and ``summary.json``; returns the summary."""
    from ..core.errors import BagError

    late = late_warning(summary)
    if late:
        losses.append(late)
    summary["warnings"] = list(losses) + list(warnings)
    summary["failures"] = demo_failures(summary, story)
    try:
        report = _write_report(out, checks, actions, alarms, losses, story, scenario,
                               summary["dead_nodes"], summary["failures"], warnings)
        summary["report"] = report.as_dict()
    except BagError as exc:
        # The run's numbers stand; without a readable bag there is no report, and the
        # run cannot pass as complete.
        summary["failures"].append(f"no report: {exc}")
        summary["report"] = None
    (out / "summary.json").write_text(json.dumps(summary, indent=2, default=float))
    return summary


def _write_report(out: Path, checks, actions, alarms, losses: list[str], story: dict,
                  scenario: str = "demo", dead_nodes: list[str] | None = None,
                  failures: list[str] | None = None, warnings: list[str] | None = None):
    """The bag's full report, with the run as the demo's user saw it live."""
    from .check import check_bag
    from ..core.errors import MtAccuracyError
    from ..report import Section, pyplot, save_figure, write_bag_report

    plt = pyplot()
    fig, ax = plt.subplots(figsize=(10, 3.6))
    if checks:
        t = np.array([c[0] for c in checks])
        ax.plot(t, [c[1].rmse * 1e6 for c in checks], "k.-", label="residual RMSE (live checks)")
        ax.plot(t, [c[1].band * 1e6 for c in checks], "g--", label="instrument band (k = 2)")
    for action in actions:
        ax.axvline(action["time_s"], color="tab:red", label=f"user added {action['added']}")
    for when, axis in alarms:
        ax.axvline(when, color="tab:orange", ls=":", label=f"deterioration alarm, {axis}")
    ax.set(xlabel="time since start [s]", ylabel="µm")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    figure = save_figure(fig, out, "report_run", "The model monitor's checks as the user saw "
                         "them, at wall-clock time x rate (behind the data when the graph "
                         "lags): the residual RMSE, the effect the user added, the alarm.")
    from ..nodes._scenario import resolve_scenario

    chosen = resolve_scenario(scenario)
    run = Section("The run", figures=[figure], paragraphs=[
        f"The virtual {chosen.machine.name} ran the scenario '{scenario}' "
        f"({chosen.description}) through the live graph, every node its own process."])
    for action in actions:
        said = "accepted" if action["accepted"] else "refused: " + action["reason"]
        run.paragraphs.append(f"At {action['time_s']:.1f} s the user added {action['added']} "
                              f"({said}).")
        tilts = table_tilts(chosen.machine, action.get("effects", []))
        if tilts:
            run.paragraphs.append(
                "Tilts of the axes that carry the workpiece named: " + "; ".join(tilts) +
                ". Each moves the part under the tool by the tilt times the arm from the "
                "table to the machining point, which changes with the other axes.")
    located = rotary_location_identified(out / "model.yaml", chosen.machine)
    if located:
        run.paragraphs.append(located[0].upper() + located[1:] + ".")
    for when, axis in alarms:
        run.paragraphs.append(f"At {when:.1f} s the {axis} axis raised its deterioration alarm.")
    run.paragraphs.append("Delivery: " + ("; ".join(losses) if losses else
                                          "every node processed every sample and message."))
    for warning in warnings or []:
        run.paragraphs.append(f"WARNING: {warning}")
    run.paragraphs.append(f"End state: {_state_words(_conformance_of(story))}")
    run.paragraphs += [verdict["sentence"] + "." for verdict in
                       story.get("end_state_verdicts", [])]
    if dead_nodes:
        run.paragraphs.append("Node(s) died during the run: " + ", ".join(dead_nodes) + ".")
    for failure in failures or []:
        run.paragraphs.append(f"FAILED: {failure}")
    try:
        # The workbench judges the model that was live at the end (model.yaml, its
        # versions and coefficients as the graph made them), not an offline re-fit.
        final = out / "model.yaml"
        result = check_bag(out / "bag", str(final if final.is_file() else
                                           out / "model_start.yaml"), [], 0, "", 0.05)
    except MtAccuracyError as exc:
        run.paragraphs.append(f"The workbench could not judge this bag: {exc}")
        result = None
    return write_bag_report(out / "report.html", out / "bag", result,
                            title="mt_accuracy_ros - main job report",
                            subtitle="The virtual machine tool through the live graph, recorded "
                                     "and judged against its reference instrument.",
                            extra_sections=[run])


# ------------------------------------------------------------------ the command line
#: The main job's scenario on each bundled machine.
DEMO_SCENARIOS = {"kidani_hmc": "demo", "khan_chen_rpppr": "demo_5axis", "vmc": "demo_vmc",
                  "trunnion_ac": "demo_trunnion"}
#: Its default rate [sim s per wall s] (real time, on every machine).
DEMO_RATE = 1.0
#: Niceness a process may be given (Linux).
NICENESS_RANGE = (-20, 19)


def validate_demo(args) -> None:
    """A positive rate (not in lockstep), a niceness Linux allows, the output directory."""
    from ..core.inputs.options import in_range, not_applicable
    from ..io.output_paths import Output, check_outputs

    in_range("--rate", args.rate, low=0, low_open=True, unit="sim s per wall s")
    if args.lockstep and args.rate is not None:
        raise not_applicable("--rate", "a demo in real time", "--lockstep (it streams in "
                             "data time, at the pace of the slowest node)")
    in_range("--niceness", args.niceness, low=NICENESS_RANGE[0], high=NICENESS_RANGE[1],
             what="an integer")
    check_outputs([Output("--out", args.out, "directory")])


def demo_command(args) -> int:
    """Run the main job on the chosen machine (its demo scenario unless one is given)."""
    rate = args.rate if args.rate is not None else DEMO_RATE
    return run_demo(out_dir=args.out, rate_factor=rate,
                    scenario=args.scenario or DEMO_SCENARIOS[args.machine],
                    compensation_mode=args.compensation, path_niceness=args.niceness,
                    lockstep=args.lockstep)


def add_parser(commands) -> None:
    """``demo`` on the subcommands ``commands``."""
    demo = commands.add_parser("demo", help="run the main job on the virtual machine tool")
    demo.add_argument("--out", default="demo_output", help="output directory")
    demo.add_argument("--rate", type=float, default=None,
                      help="sim seconds per wall second (the 90 s scenario takes 90/rate s; "
                           "default 1: real time, 10 ms scale batches and a 20 ms controller "
                           "delay; at rate r both are r times longer in data time)")
    demo.add_argument("--scenario", default=None,
                      help="bundled scenario or path (default: the machine's demo scenario)")
    demo.add_argument("--machine", default="kidani_hmc", choices=sorted(DEMO_SCENARIOS),
                      help="the virtual machine: the 3-axis HMC (scenario 'demo'), a 3-axis "
                           "VMC with the work on X and Y tables (scenario 'demo_vmc'), Khan "
                           "& Chen's 5-axis RPPPR grinder (scenario 'demo_5axis') or a 5-axis "
                           "trunnion VMC (scenario 'demo_trunnion')")
    demo.add_argument("--compensation", default="hybrid",
                      choices=["hybrid", "realtime", "table", "off"],
                      help="how the virtual CNC takes the compensation: tables + real-time "
                           "offset (hybrid, default), real-time offset only, tables only, or off")
    demo.add_argument("--niceness", type=int, default=-15,
                      help="niceness of the compensation path's nodes (CNC, estimator, "
                           "broadcaster; default -15: the CPU first when the host is loaded; "
                           "0 = as started). Without the right to it they warn and run as is")
    demo.add_argument("--lockstep", action="store_true",
                      help="stream in data time: the machine sends each batch once every node "
                           "of the loop has caught up, so the outcome is the same on any host "
                           "(the tests run so); not with --rate")
    demo.set_defaults(handler=demo_command, validate=validate_demo)
