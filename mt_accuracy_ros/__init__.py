"""mt_accuracy_ros: live accuracy monitor and volumetric compensation for CNC machine tools.

Layout (docs/architecture.md has the picture)
---------------------------------------------
core/       ROS-free numerics (numpy/scipy only), by domain: inputs, scales, kinematics,
            thermal, effects, compensation, rotary, workbench, fleet. Never imports
            rclpy or sim/.
sim/        the virtual machine tool (ROS-free); only its own nodes import it.
io/         bags, CSV surveys and logs, the CNC's OPC UA server: files and wires into
            arrays in SI units.
nodes/      thin rclpy nodes: convert -> call core -> publish.
report/     every HTML report (templates/report.html.j2).
cli.py      the ``mt-accuracy`` command, assembled from commands/ (each module's
            ``add_parser`` and handler: demo.py the main job, check.py the workbench,
            processes.py nodes as processes, ...).
"""
__version__ = "0.1.0"
