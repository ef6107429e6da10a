"""pa10_dnbs: decentralized neural backstepping control of a PA10-7CE arm."""

JOINT_NAMES = ("s1", "s2", "s3", "e1", "e2", "w1", "w2")
"""Joint names in chain order, as in ``urdf/pa10_7ce.urdf``."""

__version__ = "0.1.0"
