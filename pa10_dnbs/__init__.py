"""pa10_dnbs: decentralized neural backstepping control of robot arms (the PA10-7CE by default; any serial
arm from its URDF, pa10_dnbs.arm)."""

__version__ = "0.1.0"
