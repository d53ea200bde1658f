"""The main job on the virtual machine tool: the whole graph, recorded, and a report.

1. The virtual machine's installation calibration is simulated (laser, every
   20 mm) and written as the machine description the model starts from.
2. Separate processes: encoder and temperature publishers (the scenario
   ``demo``: warm-up, a Y guideway deterioration at 50 s, a column thermal drift
   the model does not hold), the yaw/systematic estimator, the compensation
   broadcaster, the model monitor and the recorder (MCAP).
3. This process listens like any ROS tool and acts as the user: when the
   monitor names a missing effect, it asks the monitor to add it (the
   ``add_effects`` parameter) and watches the error fall.
4. At the end: a printed summary and ``report.html`` + ``summary.json``.
"""
from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np
import yaml


def _prepare(out: Path, scenario_name: str) -> Path:
    from .nodes._scenario import resolve_scenario
    from .sim.instruments import calibrate_machine
    from .sim.machine_tool import simulate

    scenario = resolve_scenario(scenario_name)
    calibration = calibrate_machine(simulate(scenario, start_index=0, stop_index=1))
    (out / "machine_calibrated.yaml").write_text(yaml.safe_dump(calibration, sort_keys=False))
    model = out / "model.yaml"
    model.write_text(yaml.safe_dump({"machine": "machine_calibrated.yaml",
                                     "effects": {"geometric": {}}}, sort_keys=False))
    return model


def _set_parameter(node, target: str, name: str, value) -> tuple[bool, str]:
    """Set a parameter of another node through its set_parameters service."""
    import rclpy
    from rcl_interfaces.srv import SetParameters
    from rclpy.parameter import Parameter

    client = node.create_client(SetParameters, f"{target}/set_parameters")
    if not client.wait_for_service(timeout_sec=10.0):
        return False, f"{target}/set_parameters not available"
    request = SetParameters.Request(parameters=[Parameter(name, value=value).to_parameter_msg()])
    future = client.call_async(request)
    deadline = time.monotonic() + 30.0
    while not future.done() and time.monotonic() < deadline:
        rclpy.spin_once(node, timeout_sec=0.05)
    node.destroy_client(client)
    if not future.done():
        return False, "no answer"
    result = future.result().results[0]
    return bool(result.successful), str(result.reason)


def run_demo(out_dir: str = "demo_output", rate_factor: float = 2.0,
             scenario: str = "demo") -> int:
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from mt_accuracy_msgs.msg import (ModelCheck, ReferenceMeasurement, SystematicProfile,
                                      VolumetricCompensation)

    from .nodes._common import RESULT_QOS, stamp_to_nanoseconds
    from .nodes.compensation_broadcaster import COMPENSATION_QOS
    from .processes import start_node

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    bag = out / "bag"
    if bag.exists():
        import shutil

        shutil.rmtree(bag)
    started = time.monotonic()
    model = _prepare(out, scenario)
    start_ns = time.time_ns() + 4_000_000_000
    machine = {"scenario": scenario, "start_stamp_ns": start_ns, "rate_factor": rate_factor}
    # The machine holds its streams until every consumer - the recorder first of all -
    # is subscribed, so the bag holds the run from its first sample: scales go to the
    # estimator, broadcaster and recorder; temperatures also to the monitor.
    scales_consumers, temperature_consumers = 3, 4
    nodes = [start_node("recorder", {"output": str(bag), "discovery_period_s": 0.2}, quiet=True),
             start_node("yaw_estimator", {"baseline_after_s": 40.0}, quiet=True),
             start_node("compensation_broadcaster", {"model": str(model)}, quiet=True),
             start_node("model_monitor", {"model": str(model)}, quiet=True),
             start_node("temperature_publisher",
                        {**machine, "min_subscribers": temperature_consumers}, quiet=True)]
    encoder = start_node("encoder_publisher", {**machine, "min_subscribers": scales_consumers},
                         quiet=True)
    rclpy.init()
    listener = rclpy.create_node("demo_user")
    checks: list[tuple[float, ModelCheck]] = []
    alarms: list[tuple[float, str]] = []
    compensation: list[tuple[int, float]] = []
    actions: list[dict] = []

    def now_s() -> float:
        return (time.time_ns() - start_ns) / 1e9 * rate_factor

    def on_profile(message: SystematicProfile) -> None:
        if message.deterioration and not any(a[1] == message.axis for a in alarms):
            alarms.append((now_s(), message.axis))

    listener.create_subscription(ModelCheck, "model_check", lambda m: checks.append((now_s(), m)),
                                 RESULT_QOS)
    for axis in ("x", "y", "z"):
        listener.create_subscription(SystematicProfile, f"systematic/{axis}", on_profile,
                                     RESULT_QOS)
    listener.create_subscription(VolumetricCompensation, "compensation", lambda m: compensation.append(
        (stamp_to_nanoseconds(m.header.stamp), float(np.linalg.norm([m.error.x, m.error.y,
                                                                   m.error.z])))),
        COMPENSATION_QOS)
    delivery: dict[str, dict[str, str]] = {}  # node -> latest delivery counters

    def on_diagnostics(message: DiagnosticArray) -> None:
        for status in message.status:
            if status.name.endswith(": delivery"):
                delivery[status.name.split(":")[0]] = {v.key: v.value for v in status.values}

    listener.create_subscription(DiagnosticArray, "/diagnostics", on_diagnostics, 50)
    references: list[np.ndarray] = []
    listener.create_subscription(ReferenceMeasurement, "reference/tcp_error", lambda m: references.append(
        np.array([m.error.x, m.error.y, m.error.z])), RESULT_QOS)
    try:
        deadline = time.monotonic() + 90.0 / rate_factor + 60.0
        while time.monotonic() < deadline and encoder.popen.poll() is None:
            rclpy.spin_once(listener, timeout_sec=0.05)
            latest = checks[-1][1] if checks else None
            # The user looks once the machine has warmed for a while (35 s of the run).
            if latest is not None and not actions and latest.ranking and checks[-1][0] > 35 \
                    and "most likely missing" in latest.diagnosis:
                effect = latest.ranking[0].effect
                ok, reason = _set_parameter(listener, "/model_monitor", "add_effects", [effect])
                actions.append({"time_s": now_s(), "added": effect, "accepted": ok,
                                "reason": reason, "rmse_before_m": latest.rmse})
        settle = time.monotonic() + 2.0
        while time.monotonic() < settle:
            rclpy.spin_once(listener, timeout_sec=0.05)
    finally:
        encoder.stop()
        for process in nodes:
            process.stop()
        listener.destroy_node()
        rclpy.try_shutdown()
    losses = delivery_losses(delivery)
    summary = _summarise(out, checks, alarms, actions, compensation, time.monotonic() - started,
                         references, losses)
    print("mt_accuracy_ros demo - virtual HMC, scenario 'demo' (warm-up, Y guideway "
          "deterioration at 50 s, column drift missing from the model)")
    for key, value in summary.items():
        if not isinstance(value, (list, dict)):
            print(f"  {key:42s} {value:.4g}" if isinstance(value, float) else
                  f"  {key:42s} {value}")
    for line in losses:
        # Overload is loud: a graph that could not keep up says so.
        print(f"  WARNING {line}")
    print(f"  report: {out / 'report.html'}   bag: {bag}")
    return 0 if checks and summary["bag_messages"] > 0 else 1


def delivery_losses(delivery: dict[str, dict[str, str]]) -> list[str]:
    """Plain sentences for every stream a node lost or refused messages of.

    ``delivery`` maps a node to its latest ``<stream>.<counter>`` values
    (the ``<node>: delivery`` diagnostics).
    """
    lines = []
    for node, values in sorted(delivery.items()):
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


def _summarise(out: Path, checks, alarms, actions, compensation, wall_s: float,
               references, losses: list[str]) -> dict:
    from .io.bag_reader import bag_info

    info = bag_info(out / "bag")
    before = [c.rmse for t, c in checks if not actions or t < actions[0]["time_s"]]
    # The checks right after the change (before anything else happens to the machine).
    after = [c.rmse for t, c in checks if actions and t > actions[0]["time_s"]][:2]
    raw = np.array(references) if references else np.zeros((0, 3))
    raw = raw - raw.mean(axis=0) if raw.size else raw
    summary = {
        "tcp_error_uncompensated_rms_um": float(np.sqrt(np.mean(raw ** 2)) * 1e6) if raw.size
        else float("nan"),
        "model_checks": len(checks),
        "residual_rmse_before_um": float(np.mean(before[-3:]) * 1e6) if before else float("nan"),
        "missing_effect_found": actions[0]["added"] if actions else "",
        "effect_added_accepted": bool(actions and actions[0]["accepted"]),
        "residual_rmse_after_um": float(np.mean(after) * 1e6) if after else float("nan"),
        "deterioration_alarm_axis": ",".join(a[1] for a in alarms),
        "deterioration_alarm_at_s": alarms[0][0] if alarms else float("nan"),
        "compensation_messages": len(compensation),
        "max_model_tcp_error_um": max((e for _, e in compensation), default=0.0) * 1e6,
        "bag_messages": int(info["message_count"]),
        "bag_topics": len(info["topics"]),
        "wall_time_s": wall_s,
        "final_diagnosis": checks[-1][1].diagnosis if checks else "",
        "stream_losses": "; ".join(losses) or "none: every node processed every sample",
    }
    report = _write_report(out, checks, actions, alarms, losses)
    summary["report"] = report.as_dict()
    (out / "summary.json").write_text(json.dumps(summary, indent=2, default=float))
    return summary


def _write_report(out: Path, checks, actions, alarms, losses: list[str]):
    """The bag's full report, with the run as the demo's user saw it live."""
    from .check import check_bag
    from .core.errors import MtAccuracyError
    from .report import Section, pyplot, save_figure, write_bag_report

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
    run = Section("The run", figures=[figure], paragraphs=[
        "The virtual machining centre ran the demo scenario (X and Y moving, a warm-up, the Y "
        "guideway deteriorating at 50 s, a column thermal drift the starting model lacks) "
        "through the live graph, every node its own process."])
    for action in actions:
        run.paragraphs.append(f"At {action['time_s']:.1f} s the user added {action['added']} "
                              f"({'accepted' if action['accepted'] else 'refused: ' + action['reason']}).")
    for when, axis in alarms:
        run.paragraphs.append(f"At {when:.1f} s the {axis} axis raised its deterioration alarm.")
    run.paragraphs.append("Delivery: " + ("; ".join(losses) if losses else
                                          "every node processed every sample and message."))
    try:
        result = check_bag(out / "bag", str(out / "model.yaml"), [a["added"] for a in actions
                                                                    if a["accepted"]], 0, "", 0.1)
    except MtAccuracyError as exc:
        run.paragraphs.append(f"The workbench could not judge this bag: {exc}")
        result = None
    return write_bag_report(out / "report.html", out / "bag", result,
                            title="mt_accuracy_ros - main job report",
                            subtitle="The virtual machine tool through the live graph, recorded "
                                     "and judged against its reference instrument.",
                            extra_sections=[run])
