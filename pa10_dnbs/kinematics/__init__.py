"""Forward kinematics from the URDF (numpy and the standard library only)."""
