"""ROS 2 node graph: thin nodes around the numeric core and the plant."""
