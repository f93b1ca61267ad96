"""Model files as parts of other model files: ``type: model`` entries and ``ports:``.

    parts:
      left_leg:
        type: model
        file: leg.yaml                  # relative to this file
        parameters: {L: 0.4, m: m_leg}  # the child's parameters, as expressions of this file's
        placement: {position: [0, 0.2, 0], rpy: [0, 0, pi/2]}
      cell: {type: model, file: cell.yaml, count: N, placement: {position: [index*L, 0, 0]}}

Everything the included file declares (parts, joints, constraints, forces, outputs,
initial values, parameters) joins the model under its entry's name as a prefix: part
``thigh`` becomes ``left_leg.thigh``, its coordinate ``left_leg.thigh.x``, the parameter
``L`` ``left_leg.L``; ``count: N`` makes copies ``cell[0]`` … ``cell[N-1]`` (``index`` is
their number in ``parameters`` and ``placement``). The file's ``ports: {hip: pelvis.hip}``
names frames the including file joins to as ``left_leg.hip``. The paper's sub-systems (parts)
(section 2): each file is a system with its own equation of motion, and the composite is
one again, so it may be included in turn.

This module reads the entries (``read_includes``: before any part is built, so that every
parameter is known); ``io/joints.py`` reads the ports with the other frames (``read_ports``).
The loader's builders do the rest, one per file copy, each reading its file under its prefix
(``Scoped`` gives a builder its file's view of the model's names).
"""

import difflib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import sympy as sp

from ..core.errors import ModelError
from ..symbolic.cache import placeholder
from .parts import read_rotation
from .placement import Placement
from .source import read_document

INDEX = placeholder("index")  # a copy's number in its entry's parameters, read once for all copies
COUNT_MAX = 100_000  # copies of one entry: a bound on a mistaken count, far above any machine's parts


@dataclass
class Include:
    """One copy of an included file: its ``prefix`` in the model's names (``left_leg.``),
    ``relative`` placement in the including file's axes and ``placement`` in the world's,
    the ``parameters`` its entry gives ({the file's name: expression in full names}), the
    including ``parent`` builder, the entry's ``path`` there, and the ``chain`` of
    (file, line) entries that led to it."""

    prefix: str
    relative: Placement
    placement: Placement
    parameters: dict
    parent: object
    path: tuple
    chain: tuple


def read_includes(builder):
    """[(entry name, [child builders, one per copy])] of the file's ``type: model``
    entries, each child's parameters read (and its own included files, depth first)."""
    node = builder.root.get("parts")
    children = []
    for name, spec in (node.items() if isinstance(node, dict) else ()):
        if isinstance(spec, dict) and spec.get("type") == "model":
            children.append((name, _read_entry(builder, name, spec, ("parts", name))))
    return children


def _read_entry(builder, name, spec, path):
    builder.section(spec, path, "model_part")
    doc = _child_document(builder, spec, path)
    given = _given_parameters(builder, doc, spec, path + ("parameters",))
    count = _count(builder, spec, path)
    line = builder.doc.line_of(path)
    children = []
    with builder.extra_names({"index": INDEX} if count is not None else {}):  # read once, for every copy
        forms = {key: builder.expression(text, path + ("parameters", key), builder.param_symbols)
                 for key, text in given.items()}
    for index in range(count if count is not None else 1):
        local = f"{name}[{index}]" if count is not None else name
        names = {"index": sp.Integer(index)} if count is not None else {}
        with builder.extra_names(names):
            parameters = {key: builder.checked(form.xreplace({INDEX: sp.Integer(index)}), given[key],
                                               path + ("parameters", key)) for key, form in forms.items()}
            relative = _placement(builder, spec.get("placement"), path + ("placement",))
        include = Include(builder.prefix + local + ".", relative, builder.placement.then(relative), parameters,
                          builder, path, builder.chain + ((builder.doc.name, line),))
        child = type(builder)(doc, builder.assembly, include)
        child.plan()
        children.append(child)
    return children


def _given_parameters(builder, doc, spec, path):
    """The entry's ``parameters:``, each a parameter the included file declares."""
    declared = doc.root.get("parameters") if isinstance(doc.root.get("parameters"), dict) else {}
    node = spec.get("parameters")
    given = builder.mapping(node, path, set(node) if isinstance(node, dict) else set())
    for key in given:
        if key not in declared:
            close = difflib.get_close_matches(str(key), sorted(map(str, declared)), n=1)
            hint = f" (did you mean '{close[0]}'?)" if close else ""
            builder.fail(path + (key,), f"'{key}' is not a parameter of {doc.name}{hint}; it declares: "
                                        f"{', '.join(map(str, declared)) or 'none'}")
    return given


def _child_document(builder, spec, path):
    """The Document of the entry's ``file`` (read once per model), refused when the file
    includes itself through the chain that led here."""
    text = spec["file"]
    if not isinstance(text, str) or not text.strip():
        builder.fail(path + ("file",), f"expected a model file name, got {text!r}")
    file = (builder.doc.folder / text).resolve()
    if file.is_dir():
        builder.fail(path + ("file",), f"'{text}' is a folder, not a model file ({file})")
    if not file.is_file():
        builder.fail(path + ("file",), f"no such model file '{text}' (looked for {file})")
    files = [Path(str(name)).resolve() for name, _ in builder.chain] + [Path(str(builder.doc.name)).resolve()]
    if file in files:
        chain = " → ".join(f"{name}:{line}" for name, line in builder.chain + ((builder.doc.name,
                                                                                builder.doc.line_of(path)),))
        builder.fail(path + ("file",), f"'{text}' includes itself: {chain} → {file}")
    documents = builder.assembly.documents
    if file not in documents:
        try:
            documents[file] = read_document(file)
        except ModelError as err:  # the file's own line, then the entries that led to it
            entry = builder.prefix + path[-1]
            chain = builder.chain + ((builder.doc.name, builder.doc.line_of(path)),)
            raise ModelError(f"{err}{included_from(entry, chain)}") from None
    return documents[file]


def included_from(name, chain):
    """The note an error inside an included file ends with: `` (in 'NAME', included from
    FILE:LINE, …)``, the including entries from the nearest to the model file's."""
    return f" (in '{name}', included from {', '.join(f'{file}:{line}' for file, line in reversed(chain))})"


def _count(builder, spec, path):
    """The entry's number of copies, or None for one copy named by the entry alone."""
    if "count" not in spec:
        return None
    value = builder.fixed_value(builder.constant(spec["count"], path + ("count",)), path + ("count",))
    if value != int(value) or value < 1:
        builder.fail(path + ("count",), f"count must be a whole number ≥ 1, got {value:g}")
    if value > COUNT_MAX:
        builder.fail(path + ("count",), f"count {value:g} is more than {COUNT_MAX} copies")
    if "index" in builder.param_symbols:
        builder.fail(path + ("count",), "the file has a parameter 'index', the name each copy's number has in "
                                        "the entry's parameters and placement: rename the parameter")
    return int(value)


def _placement(builder, node, path):
    """The entry's ``placement:`` (a position and at most one of rpy, axis, quaternion)
    as a Placement; its turn is built in at load (its parameters become fixed ones)."""
    if node is None:
        return Placement()
    node = builder.section(node, path, "placement")
    position = builder.constants(node.get("position", [0, 0, 0]), path + ("position",), 3)
    return Placement(read_rotation(builder, node, path), position)


class Scoped(Mapping):
    """The names of ``names`` that start with ``prefix``, under the rest of their name:
    an included file's view of the model's names (with ``t``, time)."""

    def __init__(self, names, prefix):
        self.names, self.prefix = names, prefix

    def __getitem__(self, name):
        if name == "t":
            return self.names["t"]
        return self.names[self.prefix + name]

    def __contains__(self, name):
        return name == "t" or self.prefix + name in self.names

    def __iter__(self):
        size = len(self.prefix)
        return (name[size:] for name in self.names if name.startswith(self.prefix))

    def __len__(self):
        return sum(1 for _ in self)
