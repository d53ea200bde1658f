"""Bag I/O: rosbag2-compatible MCAP writing and reading (no ROS graph needed)."""
