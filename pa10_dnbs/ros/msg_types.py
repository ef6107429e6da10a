"""Message classes by ROS type name ("pkg/msg/Type"), for raw subscriptions and publishers."""
from __future__ import annotations

import importlib


def message_class(type_name: str):
    """The rclpy message class of ``type_name``; LookupError when its Python package is not installed."""
    try:
        pkg, kind, name = type_name.split("/")
    except ValueError:
        raise LookupError(f"{type_name!r} is not a ROS type name (pkg/msg/Type)") from None
    try:
        return getattr(importlib.import_module(f"{pkg}.{kind}"), name)
    except (ImportError, AttributeError):
        raise LookupError(f"{type_name}: no Python message package installed for it") from None
