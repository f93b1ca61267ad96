"""Campbell diagrams: the frequencies of a spinning model's steady motion against its spin
rate, each mode followed across the sweep, and where they meet the engine orders kΩ.

At each value Ω of the swept parameter (the spin rate, rad/s) the model's initial state,
which follows the parameter (``initial: {blade.angle_z_dot: Omega}``), is linearized as a
steady motion (modes.py, ``steady=True``). Modes are followed from one value to the next
by their shapes: the assignment (scipy's ``linear_sum_assignment``, deterministic) that
maximizes the summed modal assurance criterion MAC(a, b) = |aᴴb|² / (|a|²|b|²) between the
previous value's shapes and the new ones, so branches keep their identity where their
frequencies cross or veer. A crossing of branch j with the k-th order line f = kΩ/2π is
where f_j(Ω) − kΩ/2π changes sign between two values, at the zero of the straight line
between them: a resonance of that mode with a k-per-revolution excitation.
"""

from dataclasses import dataclass

import numpy as np
import scipy.optimize

from ..core.errors import ModelError, NoEquilibrium
from ..model.data import workspace
from .modes import modes


@dataclass(frozen=True)
class Crossing:
    """Branch ``branch`` (0-based) meets the order ``order`` line at the spin rate ``rate``
    (rad/s), at ``frequency`` = order · rate / 2π (Hz)."""

    branch: int
    order: int
    rate: float
    frequency: float


@dataclass(frozen=True)
class Campbell:
    """``frequencies`` (Hz) and ``damping_ratios`` (values × branches; NaN where a branch has
    no mode at a value) of the model's modes at each ``values`` of ``parameter``, the order
    lines 1 … ``orders`` and their ``crossings``."""

    system_name: str
    parameter: str
    values: np.ndarray
    frequencies: np.ndarray
    damping_ratios: np.ndarray
    orders: int
    crossings: tuple


def campbell(model, parameter, values, orders=4):
    """The ``Campbell`` diagram of ``model`` (a System, a Data; its parameter left as it was)
    over the spin rates ``values`` (rad/s) of its parameter ``parameter``. ModelError for an unknown parameter, fewer than
    two values, or a value at which the model does not move steadily (the value named)."""
    data = workspace(model)
    system = data.model
    if parameter not in system.parameters:
        raise ModelError(f"model '{system.name}': --campbell sweeps a parameter; '{parameter}' is none of its "
                         f"parameters ({', '.join(system.parameters) or 'none'})")
    values = np.asarray(values, dtype=float)
    if values.size < 2 or not np.all(np.isfinite(values)) or not np.all(np.diff(values) > 0):
        raise ModelError(f"model '{system.name}': --campbell needs at least two increasing finite values of "
                         f"{parameter}, got {values.tolist()}")
    branches, shapes = [], None  # branches[j]: list of (value index, Mode)
    kept = data.parameters[parameter]
    try:
        for i, value in enumerate(values):
            data.set_parameters({parameter: float(value)})
            try:
                found = modes(data, steady=True).modes
            except NoEquilibrium as err:
                raise ModelError(f"at {parameter} = {value:g}: {err}") from None
            shapes = _follow(branches, shapes, [m for m in found if m.kind != "free"], i)
    finally:
        data.set_parameters({parameter: kept})  # the model's (or the Data's) value, as it was
    frequencies = np.full((values.size, len(branches)), np.nan)
    damping = np.full_like(frequencies, np.nan)
    for j, branch in enumerate(branches):
        for i, mode in branch:
            frequencies[i, j], damping[i, j] = mode.frequency, mode.damping_ratio
    return Campbell(system.name, parameter, values, frequencies, damping, int(orders),
                    tuple(_crossings(values, frequencies, orders)))


def _follow(branches, shapes, found, i):
    """Append the modes ``found`` at value ``i`` to the ``branches`` whose last shapes
    (``shapes``: {branch: shape}) they match best (module docstring); a mode matched to none
    starts a branch. Returns the shapes to match next."""
    if shapes is None:
        shapes = {}
    order = list(shapes)
    assigned = {}
    if order and found:
        old = np.array([shapes[j] for j in order])
        new = np.array([m.shape for m in found])
        mac = np.abs(old.conj() @ new.T) ** 2 / np.outer(np.sum(np.abs(old) ** 2, 1), np.sum(np.abs(new) ** 2, 1))
        rows, cols = scipy.optimize.linear_sum_assignment(-mac)
        assigned = {int(c): order[int(r)] for r, c in zip(rows, cols)}
    for c, mode in enumerate(found):
        if c not in assigned:
            assigned[c] = len(branches)
            branches.append([])
        branches[assigned[c]].append((i, mode))
    return {assigned[c]: mode.shape for c, mode in enumerate(found)}


def _crossings(values, frequencies, orders):
    """The Crossing of each branch with each order line (module docstring), by rate."""
    found = []
    for k in range(1, int(orders) + 1):
        line = k * values / (2 * np.pi)
        for j in range(frequencies.shape[1]):
            gap = frequencies[:, j] - line
            for i in range(values.size - 1):
                a, b = gap[i], gap[i + 1]
                if not (np.isfinite(a) and np.isfinite(b)) or a * b > 0 or (a == 0 and i > 0) or a == b:
                    continue
                rate = values[i] + (values[i + 1] - values[i]) * a / (a - b)
                found.append(Crossing(j, k, float(rate), float(k * rate / (2 * np.pi))))
    return sorted(found, key=lambda c: (c.rate, c.order, c.branch))


def to_dict(result):
    """The JSON form of a Campbell result."""
    def listed(array):
        return [[None if np.isnan(x) else float(x) for x in row] for row in array]
    return {"model": result.system_name, "parameter": result.parameter, "values": result.values.tolist(),
            "frequencies_hz": listed(result.frequencies), "damping_ratios": listed(result.damping_ratios),
            "orders": result.orders,
            "crossings": [{"branch": c.branch + 1, "order": c.order, "rate": c.rate, "frequency_hz": c.frequency}
                          for c in result.crossings]}


def format_campbell(result):
    """The table: one row per value, one column per branch (Hz), then the crossings."""
    head = f"{result.parameter + ' [rad/s]':>16}" + "".join(f"{f'mode {j + 1} [Hz]':>15}"
                                                           for j in range(result.frequencies.shape[1]))
    rows = [f"{v:>16.6g}" + "".join(f"{'-' if np.isnan(f) else f'{f:.6g}':>15}" for f in row)
            for v, row in zip(result.values, result.frequencies)]
    lines = [f"Campbell diagram of {result.system_name}: modes about the steady motion against {result.parameter}",
             head, *rows]
    if result.crossings:
        lines.append(f"crossings with the order lines 1P … {result.orders}P (f = k {result.parameter}/2π):")
        lines += [f"  mode {c.branch + 1} meets {c.order}P at {result.parameter} = {c.rate:.6g} rad/s "
                  f"({c.frequency:.6g} Hz)" for c in result.crossings]
    else:
        lines.append(f"no mode meets the order lines 1P … {result.orders}P in this range")
    return "\n".join(lines)


def figure(result, top=None):
    """The diagram as a matplotlib figure: the branches, the order lines (labelled kP), the
    crossings circled; the frequency axis up to ``top`` (Hz; default: the highest frequency)."""
    import matplotlib.pyplot as plt

    drawing, axes = plt.subplots(figsize=(7, 5))
    x = result.values
    if top is None:
        top = 1.05 * np.nanmax(result.frequencies) if result.frequencies.size else 1.0
    for j in range(result.frequencies.shape[1]):
        axes.plot(x, result.frequencies[:, j], "o-", markersize=3, label=f"mode {j + 1}")
    for k in range(1, result.orders + 1):
        axes.plot(x, k * x / (2 * np.pi), "--", color="grey", linewidth=0.8)
        end = min(x[-1], 0.95 * 2 * np.pi * top / k)
        axes.annotate(f"{k}P", (end, k * end / (2 * np.pi)), color="grey", fontsize=8)
    if result.crossings:
        axes.plot([c.rate for c in result.crossings], [c.frequency for c in result.crossings], "o", markersize=9,
                  markerfacecolor="none", markeredgecolor="red", label="crossings")
    axes.set_ylim(0, top)
    axes.set_xlim(x[0], x[-1])
    axes.set_xlabel(f"{result.parameter} [rad/s]")
    axes.set_ylabel("frequency [Hz]")
    axes.set_title(f"Campbell diagram: {result.system_name}")
    axes.legend(fontsize=8)
    drawing.tight_layout()
    return drawing


def plot(result, path):
    """``figure(result)`` written to ``path`` (matplotlib's Agg; the format from the file's
    suffix), whole or not at all."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..core.files import write_atomically

    drawing = figure(result)
    suffix = str(path).rsplit(".", 1)[-1].lower()
    write_atomically(path, lambda temporary: drawing.savefig(temporary, format=suffix, dpi=120))
    plt.close(drawing)
