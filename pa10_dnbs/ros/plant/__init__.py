"""The plant node: the ROS 2 wrapper that steps an arm model (``pa10_dnbs/plant/``) and serves its joints
(node.py; its endpoints, lockstep and realtime loops, statistics, counters and tick timing beside it)."""
