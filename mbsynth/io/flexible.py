"""Reading a flexible body (``type: flexible_body``): its FE model from the beam
generator (``beam:``) or from files (``fe:``, relative to the model file), its reduction,
damping, centrifugal stiffening (beams), frames at FE nodes and initial state (sections in
schema.py). Every error of the
FE layer is reported at the key that caused it, with the model file and line."""

import numpy as np

from ..core.errors import ModelError
from ..model.parts import EulerFlexibleBody, FlexibleBody
from ..model.parts.flexible_body import coordinates, modal_damping, rayleigh_damping
from ..model.parts.flexible_euler_body import coordinates as angle_coordinates
from .parts import read_body_initial, read_geometry, read_rotation, read_sequence
from .source import LineDict

BEAM_NUMBERS = ("length", "area", "Iy", "Iz", "J", "E", "density", "G", "nu", "shear_factor")
AMPLITUDES = ("amplitudes", "amplitude_rates")


def read_flexible_body(builder, name, spec, path):
    builder.section(spec, path, "flexible_body")
    fe, stress_stiffness = _read_fe(builder, spec, path)
    reduction = _read_reduction(builder, fe, spec.get("reduction"), path + ("reduction",))
    r = reduction.size
    damping = _read_damping(builder, reduction, spec.get("damping"), path + ("damping",))
    stiffening = _read_stiffening(builder, reduction, stress_stiffness, spec.get("stiffening", False),
                                  path + ("stiffening",))
    frames = _read_frames(builder, fe, reduction.interface, spec.get("frames"), path + ("frames",))
    sequence = read_sequence(builder, spec, path)
    euler = sequence != "quaternion"
    initial = _read_initial(builder, spec.get("initial"), path + ("initial",), r, sequence if euler else None)
    names = angle_coordinates(sequence, r) if euler else coordinates(r)
    q, qd = builder.part_symbols(name, names)
    geometry = read_geometry(builder, spec.get("geometry"), path + ("geometry",))
    options = dict(frames=frames, damping=damping, geometry=geometry, initial=initial, stiffening=stiffening)
    if euler:
        return _fe_layer(builder, path, EulerFlexibleBody, name, sequence, q, qd, reduction, builder.gravity,
                         builder.parameter_symbols, **options)
    return _fe_layer(builder, path, FlexibleBody, name, q, qd, reduction, builder.gravity,
                     builder.parameter_symbols, **options)


def _read_fe(builder, spec, path):
    """(the FE model of ``beam:`` or ``fe:`` (exactly one), its stress stiffness u ↦ K_G or
    None: files carry no element data)."""
    from ..model.flexible.beam import beam, number_problem, stress_stiffness  # scipy: only for flexible bodies
    from ..model.flexible.files import read_fe
    from ..model.flexible.matrices import check_dofs_per_node

    given = [k for k in ("beam", "fe") if k in spec]
    if len(given) != 1:
        builder.fail(path, f"a flexible body needs exactly one of beam (the beam generator) and fe (FE matrix "
                           f"files); got {', '.join(given) or 'neither'}")
    key = given[0]
    node = builder.section(spec[key], path + (key,), f"flexible_{key}")
    where = path + (key,)
    if key == "beam":
        numbers = {k: builder.fixed_value(builder.constant(node[k], where + (k,)), where + (k,)) for k in BEAM_NUMBERS
                   if k in node}
        for k, value in numbers.items():
            if number_problem(k, value):
                builder.fail(where + (k,), number_problem(k, value))
        elements = node["elements"]
        if not isinstance(elements, int) or isinstance(elements, bool):
            builder.fail(where + ("elements",), f"elements must be a positive integer, got {elements!r}")
        vectors = {k: builder.numbers(node[k], where + (k,), 3) for k in ("axis", "up") if k in node}
        length = numbers.pop("length")
        fe = _fe_layer(builder, where, beam, length, elements, **numbers, **vectors,
                       theory=node.get("theory", "euler_bernoulli"), mass=node.get("mass", "consistent"))
        return fe, stress_stiffness(length, elements, **numbers, **vectors)
    files = {k: str(_file(builder, node[k], where + (k,))) for k in ("bundle", "mass", "stiffness", "nodes") if k in node}
    if ("bundle" in files) == any(k in files for k in ("mass", "stiffness", "nodes")) or \
            ("bundle" not in files and len(files) != 3):
        builder.fail(where, "give either bundle (one .npz) or all three of mass, stiffness and nodes")
    dofs = node.get("dofs_per_node")
    if dofs is not None:
        dofs = _fe_layer(builder, where + ("dofs_per_node",), check_dofs_per_node, dofs)
    if "bundle" in files:
        return _fe_layer(builder, where + ("bundle",), read_fe, files["bundle"], dofs_per_node=dofs), None
    return _fe_layer(builder, where, read_fe, **files, dofs_per_node=dofs), None


def _fe_layer(builder, path, function, *args, **kwargs):
    """``function(*args, **kwargs)`` of the FE layer, its ModelError reported at ``path``."""
    try:
        return function(*args, **kwargs)
    except ModelError as err:
        builder.fail(path, str(err))


def _file(builder, text, path):
    if not isinstance(text, str) or not text:
        builder.fail(path, f"expected a file name, got {text!r}")
    file = builder.doc.folder / text
    if file.is_dir():
        builder.fail(path, f"{text!r} is a folder ({file}), not a file")
    if not file.is_file():
        builder.fail(path, f"file {text!r} not found (looked for {file})")
    return file


def _read_reduction(builder, fe, node, path):
    """Craig–Bampton with its reference node held at the frame, or free-interface modes
    without rigid ones; refused where it leaves no elastic coordinate, or where holding the
    reference node does not fix the frame (translation-only nodes)."""
    from ..model.flexible.reduction import craig_bampton, free_interface

    node = builder.section(node, path, "flexible_reduction")
    method = node["method"]
    if not isinstance(method, str) or method not in METHODS:
        builder.fail(path + ("method",), f"method must be craig_bampton or free_interface, got {method!r}")
    interface = node.get("interface", [])
    if not isinstance(interface, list) or not all(_is_count(j) for j in interface):
        builder.fail(path + ("interface",), f"interface must be a list of node indices, got {interface!r}")
    chosen = [k for k in ("modes", "max_frequency") if k in node]
    if len(chosen) != 1:
        builder.fail(path, f"choose the modes by exactly one of modes (a count) and max_frequency (Hz); got "
                           f"{', '.join(chosen) or 'neither'}")
    count = node.get("modes")
    if count is not None and not _is_count(count):
        builder.fail(path + ("modes",), f"modes must be a count (an integer ≥ 0), got {count!r}")
    where = path + ("max_frequency",)
    limit = builder.fixed_value(builder.constant(node["max_frequency"], where), where) if "max_frequency" in node else None
    if limit is not None and not limit >= 0:
        builder.fail(where, f"max_frequency must be ≥ 0 Hz, got {limit!r}")
    if method == "craig_bampton":
        if fe.dofs_per_node != 6:
            builder.fail(path + ("method",), TRANSLATION_ONLY.format(fe.dofs_per_node))
        if not interface:
            builder.fail(path + ("interface",), "Craig–Bampton needs at least one interface node")
        reference = node.get("reference", interface[0])
        if not _is_count(reference) or reference not in interface:
            builder.fail(path + ("reference",), f"the reference node {reference!r} (held at the part's frame) "
                                                f"must be one of the interface nodes {interface}")
        reduction = _fe_layer(builder, path, craig_bampton, fe, interface, count=count, max_frequency=limit)
        reduction = _fe_layer(builder, path, reduction.hold, reference)
    else:
        if "reference" in node:
            builder.fail(path + ("reference",), "free-interface modes hold no node at the frame: reference is "
                                                "for craig_bampton")
        reduction = _fe_layer(builder, path, free_interface, fe, interface, count=count, max_frequency=limit,
                              rigid=False)
    if reduction.size == 0:
        if count is not None:
            builder.fail(path + ("modes",), f"modes: 0 {RIGID}" + (" (or add interface nodes)" if method ==
                                                                   "craig_bampton" else ""))
        first = _first_mode(fe, method, interface)
        builder.fail(where, f"max_frequency {limit:g} Hz is below the first {METHODS[method]} mode"
                            + (f", {first:.6g} Hz" if first is not None else "") + f": it {RIGID}")
    return reduction


METHODS = {"craig_bampton": "fixed-interface", "free_interface": "free"}  # method -> the modes it keeps
RIGID = ("leaves the reduction no elastic coordinate: the part would be rigid (a rigid_body); choose at least one "
         "mode")
TRANSLATION_ONLY = ("Craig–Bampton holds its reference node at the part's frame, which fixes the frame's rotation "
                    "only for a node with rotations (6 DOFs); these nodes have {} (translations): the rotation about "
                    "the reference node would stay in the reduced coordinates, the frame's own rotation twice. Use "
                    "method: free_interface (its elastic modes leave every rigid motion to the frame)")


def _is_count(value):
    """An integer ≥ 0 written as one (a bool is not: YAML's true is Python's 1)."""
    return isinstance(value, int) and not isinstance(value, bool) and value >= 0


def _first_mode(fe, method, interface):
    """The lowest mode (Hz) the reduction ``method`` would keep, or None where it has none."""
    from ..model.flexible.reduction import craig_bampton, free_interface

    try:
        reduction = (craig_bampton(fe, interface, count=1) if method == "craig_bampton"
                     else free_interface(fe, interface, count=1, rigid=False))
    except ModelError:
        return None
    return reduction.frequencies[0] / (2 * np.pi) if len(reduction.frequencies) else None


def _read_stiffening(builder, reduction, stress_stiffness, value, path):
    """``stiffening: true``: the centrifugal stiffening of a spinning beam (stiffening.py)."""
    from ..model.flexible.stiffening import centrifugal_stiffening

    if not isinstance(value, bool):
        builder.fail(path, f"stiffening must be true or false, got {value!r}")
    if not value:
        return None
    if stress_stiffness is None:
        builder.fail(path, "centrifugal stiffening needs the FE model's member forces: it is available for "
                           "beam: parts (FE files carry no element data)")
    return _fe_layer(builder, path, centrifugal_stiffening, reduction, stress_stiffness)


def _read_damping(builder, reduction, node, path):
    if node is None:
        return None
    node = builder.section(node, path, "flexible_damping")
    if len(node) != 1:
        builder.fail(path, f"give exactly one of rayleigh and modal; got {', '.join(node) or 'neither'}")
    if "rayleigh" in node:
        alpha, beta = builder.numbers(node["rayleigh"], path + ("rayleigh",), 2)
        if alpha < 0 or beta < 0:
            builder.fail(path + ("rayleigh",), f"α and β must be ≥ 0, got {alpha}, {beta}")
        return rayleigh_damping(reduction, alpha, beta)
    ratio = builder.fixed_value(builder.constant(node["modal"], path + ("modal",)), path + ("modal",))
    if ratio < 0:
        builder.fail(path + ("modal",), f"the damping ratio must be ≥ 0, got {ratio}")
    return modal_damping(reduction, ratio)


def _read_frames(builder, fe, interface, node, path):
    """{name: (FE node, rotation, geometry)} of ``frames:`` (a ``line`` may run to another of
    them or to an interface node's frame)."""
    node = builder.mapping(node, path, set(node) if isinstance(node, dict) else set())
    frames = {}
    for name, spec in node.items():
        fpath = path + (name,)
        builder.identifier(name, fpath, "frame name")
        spec = builder.section(spec, fpath, "flexible_frame")
        at = spec["node"]
        if not isinstance(at, int) or isinstance(at, bool) or not 0 <= at < len(fe.nodes):
            builder.fail(fpath + ("node",), f"node must be one of the FE model's nodes, 0 to {len(fe.nodes) - 1}; "
                                            f"got {at!r}")
        names = (set(node) | {f"node_{j}" for j in interface}) - {name}
        frames[name] = (at, read_rotation(builder, spec, fpath),
                        read_geometry(builder, spec.get("geometry"), fpath + ("geometry",), names))
    return frames


def _read_initial(builder, node, path, modes, sequence=None):
    """The frame's pose and rates (as a rigid body's, for the frame's origin; the angles of
    ``sequence`` where it turns by angles) and the modal amplitudes and their rates (lists
    of the reduction's size)."""
    node = builder.section(node, path, "initial_flexible_body")
    rigid = LineDict({k: v for k, v in node.items() if k not in AMPLITUDES})
    values = read_body_initial(builder, rigid, path, planar=False, sequence=sequence)
    for key, suffix in zip(AMPLITUDES, ("", "_dot")):
        if key in node:
            if not isinstance(node[key], list) or len(node[key]) != modes:
                builder.fail(path + (key,), f"{key}: a list of {modes} numbers, one per coordinate eta1..eta{modes} "
                                            "of the reduction")
            values.update({f"eta{k + 1}{suffix}": v for k, v in enumerate(builder.numbers(node[key], path + (key,), modes))})
    return values

