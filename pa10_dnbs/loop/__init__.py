"""Loop logic without ROS: the plant's effort gate and one joint's control loop."""
