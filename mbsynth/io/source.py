"""YAML documents that remember where every key came from.

``read_document(path)`` parses a model file with PyYAML's safe loader (no tags,
no code) into ordinary dicts and lists that also carry line numbers, so that a
mistake found later can be reported as ``file:line: at key.path: message``.

Hostile files are refused with a line too: text that is not UTF-8 or holds control
characters, nesting deeper than ``MAX_DEPTH``, more than ``MAX_NODES`` nodes once every
alias is expanded (a "billion laughs" file: each alias repeats its anchor), and scalars
that cannot be read (an integer of thousands of digits, a date that does not exist).
"""

import re
from pathlib import Path

import yaml

from ..core.errors import ModelError
from .old_keys import renamed

LINE_BREAK = re.compile("\r\n|[\r\n\x85\u2028\u2029]")  # YAML's line breaks
MAX_DEPTH = 64  # levels of nested mappings and lists
MAX_NODES = 100_000  # nodes of a document with every alias expanded


class LineDict(dict):
    """A mapping with ``line`` (its own) and ``key_lines`` (one per key), 1-based.

    Hashable by identity, like LineList: a model reader may ask ``value in KINDS`` of
    any value it finds (a mapping or list is no name, and the answer is simply no)."""

    line = 0
    key_lines: dict
    __hash__ = object.__hash__


class LineList(list):
    """A sequence with ``line`` (its own) and ``item_lines`` (one per item), 1-based."""

    line = 0
    item_lines: list
    __hash__ = object.__hash__


try:  # libyaml's scanner and parser (C) under PyYAML's composer and safe constructor: the same
    from yaml.cyaml import CParser  # documents, events and marks, the events in C

    class _Base(yaml.composer.Composer, CParser, yaml.constructor.SafeConstructor, yaml.resolver.Resolver):
        def __init__(self, text):
            CParser.__init__(self, text)
            yaml.constructor.SafeConstructor.__init__(self)
            yaml.resolver.Resolver.__init__(self)
            yaml.composer.Composer.__init__(self)
except ImportError:  # PyYAML built without libyaml
    _Base = yaml.SafeLoader


class _Loader(_Base):
    """A safe loader that bounds the nesting depth and the expanded size of a document."""

    def __init__(self, text, name):
        super().__init__(text)
        self.name = name
        self.depth = 0
        self.sizes = {}  # id(node) -> its number of nodes with aliases expanded

    def compose_node(self, parent, index):
        alias = self.check_event(yaml.AliasEvent)
        line = self.peek_event().start_mark.line + 1
        if self.depth >= MAX_DEPTH:
            raise ModelError(f"{self.name}:{line}: nested more than {MAX_DEPTH} levels deep")
        self.depth += 1
        node = super().compose_node(parent, index)
        self.depth -= 1
        if not alias:
            children = (node.value if isinstance(node, yaml.SequenceNode) else
                        [x for pair in node.value for x in pair] if isinstance(node, yaml.MappingNode) else [])
            self.sizes[id(node)] = 1 + sum(self.sizes.get(id(child), 1) for child in children)
        if self.sizes.get(id(node), 1) > MAX_NODES:
            raise ModelError(f"{self.name}:{line}: more than {MAX_NODES} values once the aliases (*name) "
                             "are expanded; refusing a file that repeats its anchors this much")
        return node

    def construct_object(self, node, deep=False):
        try:
            return super().construct_object(node, deep)
        except ModelError:
            raise
        except (ValueError, OverflowError) as err:  # int("9" * 5000), date 2001-02-30
            value = str(node.value)
            value = value if len(value) <= 40 else value[:37] + "..."
            raise ModelError(f"{self.name}:{node.start_mark.line + 1}: cannot read the value "
                             f"{value!r}: {err}") from None


def _construct_mapping(loader, node):
    """A LineDict; a key given twice is an error, except that a key of the mapping itself
    overrides one merged in with ``<<: *anchor`` (merged pairs come first, YAML's rule)."""
    own = sum(key_node.tag != "tag:yaml.org,2002:merge" for key_node, _ in node.value)
    loader.flatten_mapping(node)
    merged = len(node.value) - own
    mapping = LineDict()
    mapping.line = node.start_mark.line + 1
    mapping.key_lines = {}
    own_keys = set()
    for i, (key_node, value_node) in enumerate(node.value):
        key = loader.construct_object(key_node, deep=True)
        line = key_node.start_mark.line + 1
        if not isinstance(key, (str, int, float)):
            raise ModelError(f"{loader.name}:{line}: mapping keys must be plain names, got {key!r}")
        if key in own_keys:
            raise ModelError(f"{loader.name}:{line}: duplicate key '{key}' "
                             f"(first given on line {mapping.key_lines[key]})")
        if i >= merged:
            own_keys.add(key)
        mapping[key] = loader.construct_object(value_node, deep=True)
        mapping.key_lines[key] = line
    return mapping


def _construct_sequence(loader, node):
    sequence = LineList(loader.construct_object(child, deep=True) for child in node.value)
    sequence.line = node.start_mark.line + 1
    sequence.item_lines = [child.start_mark.line + 1 for child in node.value]
    return sequence


_Loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)
_Loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_SEQUENCE_TAG, _construct_sequence)


class Document:
    """A parsed model file: ``root`` (a LineDict) and ``error(path, message)``; ``folder``:
    where file names in it are relative to (the model file's folder; default the working
    folder)."""

    def __init__(self, name, text, folder=None):
        self.name = str(name)
        self.text = text
        self.folder = Path.cwd() if folder is None else Path(folder).resolve()
        loader = None
        try:
            loader = _Loader(text, self.name)
            root = loader.get_single_data()
        except yaml.reader.ReaderError as err:
            line = min(text.count("\n", 0, err.position) + 1, len(LINE_BREAK.findall(text)) + 1)
            raise ModelError(f"{self.name}:{line}: not valid YAML: character U+{err.character:04X} is not "
                             "allowed in a model file (binary data?)") from None
        except yaml.MarkedYAMLError as err:
            mark = err.problem_mark or err.context_mark
            line = f":{min(mark.line + 1, len(LINE_BREAK.findall(text)) + 1)}" if mark else ""  # libyaml marks the
            # end of a stream that ends in a line break on the line after it
            if "maximum nesting depth" in str(err.problem):  # libyaml's own bound, met before MAX_DEPTH is counted
                raise ModelError(f"{self.name}{line}: nested more than {MAX_DEPTH} levels deep") from None
            raise ModelError(f"{self.name}{line}: not valid YAML: {err.problem or err.context}") from None
        except yaml.YAMLError as err:
            raise ModelError(f"{self.name}: not valid YAML: {err}") from None
        finally:
            if loader is not None:
                loader.dispose()
        if not isinstance(root, LineDict):
            raise ModelError(f"{self.name}:1: a model file must be a mapping of keys "
                             f"(name, parameters, parts, ...), got {type(root).__name__}")
        self.root = renamed(root, self.name)

    def line_of(self, path):
        """The line of the deepest key or item of ``path`` that exists."""
        node, line = self.root, self.root.line
        for key in path:
            if isinstance(node, LineDict) and key in node:
                line, node = node.key_lines[key], node[key]
            elif isinstance(node, LineList) and isinstance(key, int) and 0 <= key < len(node):
                line, node = node.item_lines[key], node[key]
            else:
                break
        return line

    def error(self, path, message):
        """A ModelError reading ``file:line: at a.b.c: message``."""
        where = ".".join(f"[{k}]" if isinstance(k, int) else str(k) for k in path).replace(".[", "[")
        at = f" at {where}:" if where else ""
        return ModelError(f"{self.name}:{self.line_of(path)}:{at} {message}")


def read_document(path):
    """Read and parse the model file at ``path``."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise ModelError(f"{path}: no such model file") from None
    except IsADirectoryError:
        raise ModelError(f"{path}: is a folder, not a model file") from None
    except OSError as err:
        raise ModelError(f"{path}: cannot read model file: {err.strerror or err}") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as err:
        line = data.count(b"\n", 0, err.start) + 1
        raise ModelError(f"{path}:{line}: not UTF-8 text (byte {data[err.start]:#04x}); "
                         "a model file is YAML") from None
    return Document(path, text, folder=path.resolve().parent)
