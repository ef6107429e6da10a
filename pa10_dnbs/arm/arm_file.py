"""Read and validate an arm: ``--arm NAME`` (a folder of ``urdf/``), an arm file (``*.yaml``) or a bare URDF.

Every fault is an :class:`ArmError` (a ConfigError: the CLI prints its one line and exits 2) naming the
file and the key or joint: a URDF that does not parse, a joint named in the file that is not in the URDF,
a prismatic or floating joint among the actuated ones, a missing or zero effort limit with no override, a
moving link without inertia, a list of the wrong length, a fact without its source, a file that is not text; a
URDF that is not one tree of links and joints (pa10_dnbs.kinematics.urdf_tree: PyBullet would crash on some).
"""
from __future__ import annotations

import copyreg
import functools
import math
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from ..config_error import control_char, first_unknown, short, too_large
from ..config_yaml import read_yaml
from ..kinematics.urdf_chain import UrdfChain
from ..kinematics.urdf_tree import UrdfError
from ..kinematics.urdf_xml import urdf_root
from .arm import Arm
from .arm_path import ArmError, arm_file_path, existing_file, is_urdf, preset_names  # noqa: F401 (the API)
from .chain_select import actuated_joints
from .package_uri import is_package_uri, resolve_package_uri
from .placeholder_inertia import placeholder_inertias
from .plant_urdf import plant_urdf

DEFAULT_ARM = "pa10"
FACTS = ("torque_limit_nm", "rotor_inertia_kgm2", "viscous_nms_per_rad", "coulomb_nm")
KEYS = {"name", "description", "urdf", "urdf_install", "tip_link", "joints", "exclude_joints", "keep_gripper",
        "flange_link", "sources", "settings", *FACTS}


def load_arm(spec: str | Path = DEFAULT_ARM) -> Arm:
    """The arm ``spec`` names, read and validated once per file (later calls return the same object)."""
    return _load(str(arm_file_path(spec)))


@functools.lru_cache(maxsize=None)   # one Arm per file per process, however many files (a few kB each): a worker
def _load(path_text: str) -> Arm:  # unpickling settings gets the Arm the process holds (copyreg, below)
    path = Path(path_text)
    if is_urdf(path):   # a bare URDF: named *.urdf, or an XML document whose root is <robot>
        return _build(path, {"name": path.stem, "urdf": path.name,
                             "sources": {"urdf": str(path)}}, bare=True)
    raw = read_yaml(path, ArmError, "arm file")  # strict, as a config: a key given twice, 1e-3, one line per fault
    if not isinstance(raw, dict):
        raise ArmError(f"{path}: expected a mapping of arm facts")
    return _build(path, raw, bare=False)


def _not_utf8(exc: UnicodeDecodeError) -> str:
    """Why a URDF's bytes are refused: URDF readers (urdfdom, PyBullet) read UTF-8; a UTF-16 file (a BOM) is named
    as such, any other by its first byte that is not UTF-8."""
    head = exc.object[:2]
    if head in (b"\xff\xfe", b"\xfe\xff"):
        return "not a URDF as URDF readers take it: the file is UTF-16 text (save it as UTF-8)"
    return (f"not a URDF as URDF readers take it: byte {exc.start} (0x{exc.object[exc.start]:02x}) is not UTF-8 "
            "(a binary file, or text in another encoding: save it as UTF-8)")


def _build(path: Path, raw: dict, bare: bool) -> Arm:
    unknown = first_unknown(raw, KEYS)
    if unknown is not None:
        raise ArmError(f"{path}: {unknown}: unknown key (allowed: {', '.join(sorted(KEYS))})")
    for key in ("name", "urdf"):
        if not isinstance(raw.get(key), str) or not raw[key]:
            raise ArmError(f"{path}: {key}: expected a non-empty string")
    for key in ("name", "description"):   # printed in every table and report line: one line each
        value = raw.get(key, "")
        if not isinstance(value, str):
            raise ArmError(f"{path}: {key}: expected a text, got {short(value)}")
        # (around it, whitespace is dropped: YAML's folded > ends in a newline)
        if control := control_char(value.strip()):
            raise ArmError(f"{path}: {key}: holds a control character ({control!r}), which would split the lines "
                           "it is printed in")
    urdf = path if bare else existing_file(_urdf_path(path, raw), f"{path}: urdf")
    try:
        xml = urdf.read_text()
        chain = UrdfChain(xml)
        links = _links(xml)
    except UrdfError as exc:  # not one tree, or a malformed joint: the message names the joint or link
        raise ArmError(f"{urdf}: {exc}") from None
    except UnicodeDecodeError as exc:
        raise ArmError(f"{urdf}: {_not_utf8(exc)}") from None
    except OSError as exc:
        raise ArmError(f"{urdf}: cannot read: {exc.strerror or exc}") from None
    except (ET.ParseError, ValueError, AttributeError, TypeError) as exc:
        raise ArmError(f"{urdf}: the URDF does not parse: {exc}") from None
    names = _names(path, raw, "joints")
    exclude = _names(path, raw, "exclude_joints") or ()
    for key in ("tip_link", "flange_link"):
        _check_link_name(path, key, raw.get(key))
    keep_gripper = raw.get("keep_gripper", False)
    if not isinstance(keep_gripper, bool):
        raise ArmError(f"{path}: keep_gripper: expected true or false")
    try:
        actuated, locked = actuated_joints(chain, exclude=exclude, tip_link=raw.get("tip_link"), names=names,
                                           keep_gripper=keep_gripper)
    except ValueError as exc:
        raise ArmError(f"{path}: {exc}") from None
    joint_names = tuple(j.name for j in actuated)
    n = len(joint_names)
    for name in joint_names:
        why = _unfit_file_name(name)
        if why:
            raise ArmError(f"{urdf}: joint {name!r}: {why}: an actuated joint's name becomes a file name "
                           f"(<joint>.npz checkpoints); rename it in the URDF")
    for j in actuated:
        _check_inertia(urdf, links.get(j.child), j.child, j.name)
    for line in placeholder_inertias(chain, links, actuated[0].child):
        print(f"warning: {urdf}: {line}", file=sys.stderr)
    lower = np.array([j.lower for j in actuated], dtype=float)
    upper = np.array([j.upper for j in actuated], dtype=float)
    bad = [j.name for j in actuated if j.kind == "revolute" and not (math.isfinite(j.lower)
                                                                     and math.isfinite(j.upper) and j.lower < j.upper)]
    if bad:
        raise ArmError(f"{urdf}: joint {bad[0]!r}: a revolute joint needs <limit lower upper> with lower < upper")

    sources = {} if raw.get("sources") is None else raw["sources"]   # an empty list is not an empty mapping
    if not isinstance(sources, dict):
        raise ArmError(f"{path}: sources: expected a mapping of fact -> where its numbers came from")
    if not bare:
        for key in ("urdf",) + FACTS:
            source = sources.get(key)
            if key in raw and source is not None and not isinstance(source, str):
                raise ArmError(f"{path}: sources.{key}: must be a text (where the fact came from), got "
                               f"{short(source)}")
            if key in raw and not (isinstance(source, str) and source.strip()):
                raise ArmError(f"{path}: sources.{key}: missing (every fact needs its source)")
    if "torque_limit_nm" in raw:
        torque = _vector(path, "torque_limit_nm", raw["torque_limit_nm"], n, strict=True)
    else:
        efforts = [j.effort for j in actuated]
        bad = next(((j.name, e) for j, e in zip(actuated, efforts) if not (math.isfinite(e) and e > 0.0)), None)
        if bad:
            name, e = bad
            what = "no <limit effort>" if math.isnan(e) else f"effort {e:g}, not a finite limit > 0"
            raise ArmError(f"{urdf}: joint {name!r} has {what}: give torque_limit_nm in the arm file")
        torque = np.array(efforts, dtype=float)
        sources.setdefault("torque_limit_nm", "the URDF's <limit effort>")
    facts = {key: _vector(path, key, raw.get(key, 0.0), n, strict=False) for key in FACTS[1:]}
    for key in FACTS[1:]:
        sources.setdefault(key, "not given: zero")
    flange = raw.get("flange_link") or actuated[-1].child
    if flange not in links:
        raise ArmError(f"{path}: flange_link: no link {flange!r} in the URDF")
    _check_flange_moves(path, chain, flange, actuated)
    settings = {} if raw.get("settings") is None else raw["settings"]
    if not isinstance(settings, dict):
        raise ArmError(f"{path}: settings: expected a mapping (config keys of this arm)")
    try:
        cleaned, notes = plant_urdf(urdf)
    except ValueError as exc:
        raise ArmError(f"{urdf}: {exc}") from None
    for note in notes:
        print(note, file=sys.stderr)
    locked_at = tuple(float(min(max(0.0, j.lower), j.upper)) for j in locked)
    name = raw["name"] if not bare else path.stem
    return Arm(name=name, description=raw.get("description", name).strip() or name, file=path, urdf=urdf,
               joint_names=joint_names, locked_joints=tuple(j.name for j in locked), locked_position_rad=locked_at,
               lower_rad=lower, upper_rad=upper, torque_limit_nm=torque, flange_link=flange,
               rotor_inertia_kgm2=facts["rotor_inertia_kgm2"], viscous_nms_per_rad=facts["viscous_nms_per_rad"],
               coulomb_nm=facts["coulomb_nm"], sources=dict(sources), settings=settings, chain=chain,
               plant_urdf=cleaned)


def _urdf_path(path: Path, raw: dict) -> Path:
    """The file an arm file's ``urdf`` names: relative to the arm file, or a ``package://`` URI (package_uri.py;
    ``urdf_install`` says how to install the package when it is not)."""
    hint = raw.get("urdf_install")
    if hint is not None and not (isinstance(hint, str) and hint.strip()):
        raise ArmError(f"{path}: urdf_install: expected a non-empty string (how to install the urdf's package)")
    if not is_package_uri(raw["urdf"]):
        return path.parent / raw["urdf"]   # resolved by existing_file (a loop or a name too long: one line)
    try:
        return resolve_package_uri(raw["urdf"], hint)
    except ValueError as exc:  # PackageNotFound too
        raise ArmError(f"{path}: urdf: {exc}") from None


def _names(path: Path, raw: dict, key: str) -> tuple[str, ...] | None:
    value = raw.get(key)
    if value is None:
        return None
    if not isinstance(value, list) or not all(isinstance(v, str) and v for v in value):
        raise ArmError(f"{path}: {key}: expected a list of joint names")
    if key == "joints":   # each actuated once (a repeat in exclude_joints locks the joint all the same)
        twice = [v for i, v in enumerate(value) if v in value[:i]]
        if twice:
            raise ArmError(f"{path}: {key}: {twice[0]!r} is given twice (each actuated joint once, in chain order)")
    return tuple(value)


def _check_link_name(path: Path, key: str, value) -> None:
    """``tip_link`` / ``flange_link``: absent (None) or a link's name, a string; a number (YAML reads an unquoted
    ``2`` as one) is told to be quoted."""
    if value is None or isinstance(value, str):
        return
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        raise ArmError(f'{path}: {key}: expected a link name (a string), got the number {value!r}: quote it '
                       f'({key}: "{value}") if the URDF has a link named so')
    kind = {list: "a list", dict: "a mapping", bool: "a boolean"}.get(type(value), type(value).__name__)
    raise ArmError(f"{path}: {key}: expected a link name (a string), got {kind}: {short(value)}")


def _check_flange_moves(path: Path, chain: UrdfChain, flange: str, actuated) -> None:
    """``flange`` (the link that carries a payload) lies after an actuated joint: the root link, or a link fixed
    to it, carries nothing the joints lift (the plant found no such link when a payload was put there)."""
    parent_joint = {j.child: j for j in chain.joints}
    names = {j.name for j in actuated}
    link = flange
    while link in parent_joint:
        if parent_joint[link].name in names:
            return
        link = parent_joint[link].parent
    where = ("the URDF's root link" if flange == chain.root_link else
             f"fixed to the root link {chain.root_link!r} (no actuated joint moves it)")
    raise ArmError(f"{path}: flange_link: {flange!r} is {where}: the flange must be a link the actuated "
                   f"joints carry (the tip is {actuated[-1].child!r})")


MAX_FILE_NAME_BYTES = 200   # a joint's name in UTF-8: "<joint>.npz.tmp.npz" within the usual 255-byte limit


def _unfit_file_name(name: str) -> str | None:
    """Why the joint name ``name`` cannot be a file's name (``<name>.npz``), or None when it can."""
    for char, called in (("/", "'/'"), ("\0", "a NUL character")):
        if char in name:
            return f"it holds {called}"
    if control := control_char(name):
        return f"it holds a control character ({control!r}), which would split a file's name and a message's line"
    if name in (".", ".."):
        return f"{name!r} names a folder"
    size = len(name.encode("utf-8", "surrogatepass"))
    if size > MAX_FILE_NAME_BYTES:
        return f"{size} bytes long in UTF-8, more than {MAX_FILE_NAME_BYTES}"
    return None


def _vector(path: Path, key: str, value, n: int, strict: bool) -> np.ndarray:
    """``value`` as (n,) floats: a list of n numbers or one number for every joint; > 0 (strict) or >= 0."""
    items = value if isinstance(value, list) else [value] * n
    if len(items) != n:
        raise ArmError(f"{path}: {key}: expected {n} values (one per actuated joint), got {len(items)}")
    out = []
    for i, v in enumerate(items):
        if isinstance(v, int) and not isinstance(v, bool) and abs(v) > sys.float_info.max:
            raise ArmError(f"{path}: {key}[{i}]: {too_large(v)}")
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise ArmError(f"{path}: {key}[{i}]: expected a finite number, got {short(v)}")
        if (v <= 0.0) if strict else (v < 0.0):
            raise ArmError(f"{path}: {key}[{i}]: must be {'> 0' if strict else '>= 0'}, got {short(v)}")
        out.append(float(v))
    return np.array(out)


def _links(xml: str) -> dict[str, ET.Element | None]:
    """Link name -> its <inertial> element (None when it has none)."""
    return {el.get("name"): el.find("inertial") for el in urdf_root(xml).findall("link")}


def _check_inertia(urdf: Path, inertial, link: str, joint: str) -> None:
    """The link an actuated joint moves needs a mass > 0 and a positive definite inertia tensor."""
    if inertial is None:
        raise ArmError(f"{urdf}: link {link!r} (moved by {joint!r}) has no <inertial>")
    mass_el, inertia_el = inertial.find("mass"), inertial.find("inertia")
    try:
        mass = float(mass_el.get("value"))
        i = {k: float(inertia_el.get(k, 0.0)) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
    except (AttributeError, TypeError, ValueError):
        raise ArmError(f"{urdf}: link {link!r}: <inertial> needs <mass value> and <inertia>") from None
    tensor = np.array([[i["ixx"], i["ixy"], i["ixz"]], [i["ixy"], i["iyy"], i["iyz"]], [i["ixz"], i["iyz"], i["izz"]]])
    if not (mass > 0.0 and np.all(np.isfinite(tensor)) and np.all(np.linalg.eigvalsh(tensor) > 0.0)):
        raise ArmError(f"{urdf}: link {link!r} (moved by {joint!r}): mass {mass:g} kg and inertia must be > 0")


def _pickled_as_its_file(arm: Arm):
    """An Arm is pickled as its file: a worker process reads it once there (``load_arm`` keeps one per file)."""
    return load_arm, (str(arm.file),)


copyreg.pickle(Arm, _pickled_as_its_file)
