"""ROS-free numerical core. Only numpy and scipy; importable without rclpy."""
