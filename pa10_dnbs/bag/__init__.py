"""rosbag2 bags in MCAP: writing, reading with clear errors, /tf for Foxglove, analysis (no rclpy here)."""
