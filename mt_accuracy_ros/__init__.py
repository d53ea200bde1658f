"""mt_accuracy_ros: live accuracy monitor and volumetric compensation for CNC machine tools.

Layout
------
core/   ROS-free numerics (numpy/scipy only): dual-scale yaw, kNN systematic error,
        kinematic and thermal models. Never imports rclpy.
sim/    the virtual machine tool (ROS-free).
io/     MCAP bag reading and writing (ROS-free where possible).
nodes/  thin rclpy nodes: convert -> call core -> publish.
cli.py  the ``mt-accuracy`` command.
"""
__version__ = "0.1.0"
