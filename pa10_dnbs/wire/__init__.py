"""The wire format without ROS: topic names, JointState CDR, stamp <-> step arithmetic, runs rebuilt from messages."""
