"""The arm a run controls: one object built once from its files (``urdf/<name>/``) and handed down."""
from .arm import Arm
from .arm_file import DEFAULT_ARM, ArmError, arm_file_path, load_arm, preset_names


__all__ = ["Arm", "ArmError", "DEFAULT_ARM", "arm_file_path", "load_arm", "preset_names"]
