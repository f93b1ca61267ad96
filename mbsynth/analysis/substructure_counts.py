"""Each substructure's share of a model, for ``mbsynth check``: its coordinates, the rows of
the constraints wholly inside it and its degrees of freedom at a state.

A substructure's coordinates are those of its parts and of the substructures it includes.
A constraint is wholly inside it when every coordinate the constraint involves
(``Constraint.indices``) is one of them; the ground is inside every substructure, so a joint
to ``world`` inside a file is that file's own. Its degrees of freedom are its coordinates
minus the rank of those rows (``equations.rank_report`` on its own blocks of M and A:
the rank rule and tolerance of the whole model's Result 3).
"""

import numpy as np

from ..core.equations import rank_report


def substructure_counts(system, M, A):
    """The tree of ``system.substructures`` as a list of dicts ``{name, file, coordinates,
    rows, degrees_of_freedom, children}`` (counts), with M and A evaluated at one state."""
    start, offset = {}, 0
    for part in system.parts:
        start[part.name] = range(offset, offset + len(part.coordinates))
        offset += len(part.coordinates)
    nodes, chain = [], [()] * system.n  # chain[i]: the nodes (by index) holding coordinate i, outermost first

    def walk(substructure, above):
        index = len(nodes)
        nodes.append({"substructure": substructure, "columns": [], "rows": []})
        path = above + (index,)
        for part in substructure.parts:
            for i in start[part]:
                chain[i] = path
        children = [walk(child, path) for child in substructure.children]
        nodes[index]["columns"] = [i for part in substructure.parts for i in start[part]] + [
            i for child in children for i in nodes[child]["columns"]]
        nodes[index]["children"] = children
        return index

    top = [walk(substructure, ()) for substructure in system.substructures]
    row = 0
    for constraint in system.constraints:
        k = len(constraint.row_names)
        for index in _common(chain[i] for i in constraint.indices):
            nodes[index]["rows"] += range(row, row + k)
        row += k
    M, A = np.asarray(M, dtype=float), np.asarray(A, dtype=float)

    def counts(index):
        node = nodes[index]
        columns, rows = np.array(node["columns"], dtype=int), np.array(node["rows"], dtype=int)
        rank = rank_report(M[np.ix_(columns, columns)], A[np.ix_(rows, columns)]).rank_A if len(rows) else 0
        return {"name": node["substructure"].name, "file": node["substructure"].file,
                "coordinates": len(columns), "rows": len(rows), "degrees_of_freedom": len(columns) - rank,
                "children": [counts(child) for child in node["children"]]}

    return [counts(index) for index in top]


def _common(chains):
    """The longest chain that starts every one of ``chains`` (none given: the empty chain)."""
    common = None
    for path in chains:
        if common is None:
            common = path
        else:
            k = 0
            while k < min(len(common), len(path)) and common[k] == path[k]:
                k += 1
            common = common[:k]
        if not common:
            return ()
    return common or ()
