"""The arm a run controls: one object built once from its files (``urdf/<name>/``) and handed down."""
from .arm import Arm
from .arm_file import DEFAULT_ARM, ArmError, arm_file_path, load_arm, preset_names


def arm_of(cfg: dict) -> Arm:
    """The arm of a validated config (``cfg['arm']`` holds its file's path; read once per process)."""
    return load_arm(cfg["arm"])


__all__ = ["Arm", "ArmError", "DEFAULT_ARM", "arm_file_path", "arm_of", "load_arm", "preset_names"]
