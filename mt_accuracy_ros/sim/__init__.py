"""The virtual machine tool: ROS-free simulation of scales, temperatures and errors."""
