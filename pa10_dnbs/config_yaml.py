"""Read one config file's YAML document strictly: every mistake is one ConfigError line naming the file.

- not UTF-8 text, or not valid YAML: ``FILE:LINE: not valid YAML: <problem>`` (one line, not PyYAML's several);
- a key given twice in one mapping (PyYAML keeps the last silently, so a whole section could vanish):
  ``FILE:LINE: key 'k' given twice in one mapping (first at line N)`` (two ``<<`` merge keys too);
- an integer of more than Python's 4300 digits, or nesting too deep for the parser: one line too;
- aliases that repeat more than ``MAX_ALIASED_NODES`` nodes (a "billion laughs" document: nine levels of anchors,
  each ten aliases of the one below, 600 bytes that a message's ``repr`` or ``str`` would expand to 10**9 strings
  and exhaust memory): one line ``FILE: refused: its aliases (*name) expand it to N nodes ...``, counted on the
  composed nodes before any object is built; ordinary anchors and aliases (``<<: *base``) read as before;
- ``1e-3``, ``1e3``, ``2.5e3`` are numbers (floats), as in YAML 1.2 and JSON: PyYAML's YAML 1.1 float rule
  wants a dot and a signed exponent (``1.0e-3``) and reads the others as strings. Every value the 1.1 rule
  reads is read exactly as before (the extra rule is tried after it), so existing files keep their values.
- ``1:30`` stays the string ``'1:30'``: YAML 1.1 reads it as a base-60 (sexagesimal) integer, 90, and ``1:30.5``
  as the float 90.5, a time-of-day a user never meant as a number (YAML 1.2 dropped the rule). The string is
  then refused by the key's own check, which names the key; ``!!int 1:30`` given explicitly is one line too.
"""
from __future__ import annotations

import re
from pathlib import Path

import yaml

from .config_error import ConfigError

# A number with an exponent that the YAML 1.1 float pattern misses: no dot or an unsigned exponent.
_EXPONENT_FLOAT = re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)[eE][-+]?[0-9]+$")


class DuplicateKeyError(yaml.constructor.ConstructorError):
    """A key given twice in one mapping."""


_INT, _FLOAT, _STR = "tag:yaml.org,2002:int", "tag:yaml.org,2002:float", "tag:yaml.org,2002:str"


#: the nodes aliases may add to a document (each alias counted as the nodes of its anchor, expanded): far above
#: any config, arm file or trajectory's own use of them, far below what exhausts memory when shown
MAX_ALIASED_NODES = 1_000_000


def expanded_nodes(root) -> tuple[int, int]:
    """(the nodes of the composed document ``root`` with every alias expanded, the nodes written): counted once per
    node (memoised), never built. An alias inside its own anchor (a document that holds itself) counts one."""
    size: dict[int, int] = {}
    open_nodes: set[int] = set()
    stack = [(root, False)]
    while stack:
        node, closing = stack.pop()
        children = node.value if isinstance(node, yaml.SequenceNode) else \
            [n for pair in node.value for n in pair] if isinstance(node, yaml.MappingNode) else ()
        if closing:
            size[id(node)] = 1 + sum(size.get(id(c), 1) for c in children)  # not yet counted: an ancestor's alias
            open_nodes.discard(id(node))
        elif id(node) not in size and id(node) not in open_nodes:
            open_nodes.add(id(node))
            stack.append((node, True))
            stack.extend((c, False) for c in children)
    return size[id(root)], len(size)


class BoundedSafeLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` that refuses a document whose aliases expand past MAX_ALIASED_NODES
    (:class:`AliasBombError`) before it is built (a file the user gives that is not a config: a bag's metadata)."""

    aliased = False   # set when the document holds an alias (only then are its nodes counted)

    def compose_node(self, parent, index):
        if self.check_event(yaml.AliasEvent):
            self.aliased = True
        return super().compose_node(parent, index)

    def get_single_data(self):
        node = self.get_single_node()
        if node is None:
            return None
        expanded, written = expanded_nodes(node) if self.aliased else (0, 0)
        if expanded - written > MAX_ALIASED_NODES:
            raise AliasBombError(f"refused: its aliases (*name) expand it to {expanded:.3g} nodes, from {written} "
                                 f"written (aliases may add at most {MAX_ALIASED_NODES}: a YAML alias bomb?)")
        return self.construct_document(node)


class StrictConfigLoader(BoundedSafeLoader):
    """:class:`BoundedSafeLoader` that refuses a key given twice in one mapping, reads ``1e-3`` as a float and leaves
    a sexagesimal ``1:30`` a string."""

    def resolve(self, kind, value, implicit):
        """YAML 1.1's tag for a plain scalar, except a base-60 int or float (the only ones with a ':'): str."""
        tag = super().resolve(kind, value, implicit)
        if kind is yaml.ScalarNode and tag in (_INT, _FLOAT) and ":" in value:
            return _STR
        return tag

    def _refuse_sexagesimal(self, node):
        if ":" in self.construct_scalar(node):
            raise yaml.constructor.ConstructorError(
                None, None, f"{node.value!r} is a base-60 (sexagesimal) number, not read: give it in decimal",
                node.start_mark)

    def construct_yaml_int(self, node):
        self._refuse_sexagesimal(node)
        return super().construct_yaml_int(node)

    def construct_yaml_float(self, node):
        self._refuse_sexagesimal(node)
        return super().construct_yaml_float(node)

    def construct_mapping(self, node, deep=False):
        if isinstance(node, yaml.MappingNode):
            first: dict = {}
            for key_node, _ in node.value:
                if key_node.tag == "tag:yaml.org,2002:merge":   # '<<': merged keys may be overridden, but
                    key = "<<"                                   # a second '<<' in one mapping is a duplicate
                else:
                    key = self.construct_object(key_node, deep=True)
                try:
                    seen = first.get(key)
                except TypeError:   # an unhashable key: the base constructor says so
                    continue
                if seen is not None:
                    raise DuplicateKeyError(
                        None, None, f"key {key!r} given twice in one mapping (first at line {seen.line + 1})",
                        key_node.start_mark)
                first[key] = key_node.start_mark
        return super().construct_mapping(node, deep=deep)


StrictConfigLoader.add_implicit_resolver(_FLOAT, _EXPONENT_FLOAT, list("-+0123456789."))
StrictConfigLoader.add_constructor(_INT, StrictConfigLoader.construct_yaml_int)
StrictConfigLoader.add_constructor(_FLOAT, StrictConfigLoader.construct_yaml_float)


class UnusableYamlError(yaml.YAMLError):
    """A document PyYAML parses but Python cannot hold: nesting too deep, an integer of too many digits."""

    def __init__(self, problem: str):
        super().__init__(problem)
        self.problem = problem


class AliasBombError(UnusableYamlError):
    """A document whose aliases expand past MAX_ALIASED_NODES nodes."""


def load_strict(text: str):
    """``text``'s YAML (or JSON) document read with :class:`StrictConfigLoader`; every fault a yaml.YAMLError
    (:class:`UnusableYamlError` for nesting too deep or an integer past Python's 4300-digit limit)."""
    try:
        return yaml.load(text, Loader=StrictConfigLoader)
    except RecursionError:
        raise UnusableYamlError("nested too deeply") from None
    except ValueError as exc:   # int('1' * 5000): Python's limit on the digits of an integer
        why = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise UnusableYamlError(f"a number out of range ({why})") from None


def yaml_error_line(path: Path, exc: yaml.YAMLError) -> str:
    """``FILE:LINE: not valid YAML: problem`` in one line (PyYAML's message spans several)."""
    mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
    where = f"{path}:{mark.line + 1}" if mark is not None else str(path)
    if isinstance(exc, (DuplicateKeyError, AliasBombError)):
        return f"{where}: {exc.problem}"
    problem = getattr(exc, "problem", None) or (str(exc).splitlines()[0] if str(exc) else type(exc).__name__)
    context = getattr(exc, "context", None)
    if context:
        problem = f"{context}, {problem}"
    return f"{where}: not valid YAML: {problem}"


def read_yaml(path: Path, error_class: type[Exception] = ConfigError, what: str = "config file"):
    """The YAML (or JSON) document of ``path`` (any type; the caller checks it), read strictly as UTF-8 with
    :class:`StrictConfigLoader`; every fault is one ``error_class`` line naming the file (``what``: the kind of
    file, in the message for a file that is not text). Any YAML 1.1 or JSON number is read, ``1e-05`` too."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise error_class(f"{path}: not a text {what} (not UTF-8: byte {exc.start})") from None
    except OSError as exc:
        raise error_class(f"{path}: cannot read: {exc.strerror or exc}") from None
    try:
        return load_strict(text)
    except yaml.YAMLError as exc:
        raise error_class(yaml_error_line(path, exc)) from None


def read_config_yaml(path: Path):
    """The YAML document of the config file ``path`` (any type; the caller checks it), read strictly."""
    return read_yaml(path, ConfigError, "config file")


def dumpable(obj):
    """``obj`` with its tuples as lists, recursively (dicts and lists walked): what ``yaml.safe_dump`` writes."""
    if isinstance(obj, dict):
        return {k: dumpable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [dumpable(v) for v in obj]
    return obj
