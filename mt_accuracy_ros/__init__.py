"""mt_accuracy_ros: live accuracy monitor and volumetric compensation for CNC machine tools.

Layout (docs/architecture.md has the picture)
---------------------------------------------
core/       ROS-free numerics (numpy/scipy only), by domain: scales, kinematics,
            thermal, compensation, workbench. Never imports rclpy.
sim/        the virtual machine tool (ROS-free); only its own nodes import it.
io/         MCAP bag reading and writing, message-field conversions.
nodes/      thin rclpy nodes: convert -> call core -> publish.
report.py   every HTML report (templates/report.html.j2).
cli.py      the ``mt-accuracy`` command; commands/ what it runs (demo.py the main job,
            check.py the workbench, processes.py nodes as processes, ...).
"""
__version__ = "0.1.0"
