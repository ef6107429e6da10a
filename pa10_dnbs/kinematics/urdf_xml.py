"""A URDF's XML element tree, read as URDF parsers read it.

urdfdom (ROS) and PyBullet read URDFs with TinyXML, which knows no namespaces: old Gazebo URDFs carry tags such as
``<sensor:camera>`` or ``<controller:gazebo_ros_camera>`` whose prefix the file never declares, and load there.
Python's XML parser refuses them ("unbound prefix"); :func:`urdf_root` then declares each such prefix on the
``<robot>`` element (namespace ``urn:pa10-dnbs:undeclared:<prefix>``, on the same line, so later line numbers hold)
and reads it again; so too a prefix declared only on some inner element and used outside it. The URDF's own
elements (link, joint, inertial, ...) carry no prefix and are read as written.
"""
from __future__ import annotations

import re
import xml.etree.ElementTree as ET

UNDECLARED = "urn:pa10-dnbs:undeclared:"
_NAME = r"[A-Za-z_][\w.-]*"
_USED = re.compile(rf"</?({_NAME}):{_NAME}|\s({_NAME}):{_NAME}\s*=")   # prefixed tags and attributes
_DECLARED = re.compile(rf"xmlns:({_NAME})\s*=")
_ROBOT = re.compile(r"<robot(?=[\s/>])")   # the root's tag, not <robot:x> or <robot-x>
_START_TAG = re.compile(r"[^>]*")           # the rest of a start tag (its attributes), up to its '>'


def urdf_root(data: str | bytes) -> ET.Element:
    """The root element of the XML text ``data``; prefixes used but never declared are declared (see the module).
    Raises ET.ParseError for XML that is not well-formed otherwise (its line as in ``data``)."""
    try:
        return ET.fromstring(data)
    except ET.ParseError as exc:
        if "unbound prefix" not in str(exc):
            raise
    text = data if isinstance(data, str) else data.decode("utf-8", errors="surrogateescape")
    used = {p for m in _USED.finditer(text) for p in m.groups() if p}
    root = _ROBOT.search(text)
    on_root = set(_DECLARED.findall(_START_TAG.match(text, root.end()).group(0))) if root else set()
    # a prefix declared only on some inner element is unbound elsewhere: declared on the root too (the inner
    # declaration still holds inside its element)
    missing = sorted(used - on_root - {"xml", "xmlns"})
    declared = "".join(f' xmlns:{p}="{UNDECLARED}{p}"' for p in missing)
    fixed = text[:root.end()] + declared + text[root.end():] if root else text
    return ET.fromstring(fixed if isinstance(data, str) else fixed.encode("utf-8", errors="surrogateescape"))
