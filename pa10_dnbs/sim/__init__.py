"""In-process closed-loop simulation (no ROS)."""
