"""The real robot: the measured state in, ros2_control commands out."""
