"""YAML documents that remember where every key came from.

``read_document(path)`` parses a model file with PyYAML's safe loader (no tags,
no code) into ordinary dicts and lists that also carry line numbers, so that a
mistake found later can be reported as ``file:line: at key.path: message``.
"""

from pathlib import Path

import yaml

from ..errors import ModelError


class LineDict(dict):
    """A mapping with ``line`` (its own) and ``key_lines`` (one per key), 1-based."""

    line = 0
    key_lines: dict


class LineList(list):
    """A sequence with ``line`` (its own) and ``item_lines`` (one per item), 1-based."""

    line = 0
    item_lines: list


class _Loader(yaml.SafeLoader):
    pass


def _construct_mapping(loader, node):
    loader.flatten_mapping(node)
    mapping = LineDict()
    mapping.line = node.start_mark.line + 1
    mapping.key_lines = {}
    for key_node, value_node in node.value:
        key = loader.construct_object(key_node, deep=True)
        line = key_node.start_mark.line + 1
        if not isinstance(key, (str, int, float)):
            raise ModelError(f"{loader.name}:{line}: mapping keys must be plain names, got {key!r}")
        if key in mapping:
            raise ModelError(f"{loader.name}:{line}: duplicate key '{key}' "
                             f"(first given on line {mapping.key_lines[key]})")
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
    """A parsed model file: ``root`` (a LineDict) and ``error(path, message)``."""

    def __init__(self, name, text):
        self.name = str(name)
        self.text = text
        loader = _Loader(text)
        loader.name = self.name
        try:
            root = loader.get_single_data()
        except yaml.MarkedYAMLError as err:
            mark = err.problem_mark or err.context_mark
            line = f":{mark.line + 1}" if mark else ""
            raise ModelError(f"{self.name}{line}: not valid YAML: {err.problem or err.context}") from None
        except yaml.YAMLError as err:
            raise ModelError(f"{self.name}: not valid YAML: {err}") from None
        finally:
            loader.dispose()
        if not isinstance(root, LineDict):
            raise ModelError(f"{self.name}:1: a model file must be a mapping of keys "
                             f"(name, parameters, subsystems, ...), got {type(root).__name__}")
        self.root = root

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
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ModelError(f"{path}: no such model file") from None
    except (OSError, UnicodeDecodeError) as err:
        raise ModelError(f"{path}: cannot read model file: {err}") from None
    return Document(path, text)
