"""The N-four-bar of IFToMM A02 written as one cell file used N times (``count: N``), and
a model nesting that cell two deep: model files for the tests of ``mbsynth check`` and the
viewer on substructures. ``write_n_four_bar(folder)`` writes them and returns the top file."""

CELL = """\
name: four_bar_cell
parameters: {L: 1.0, m: 1.0, speed: 1.0}
world:
  frames:
    pivot: {}
parts:
  v: {type: planar_body, mass: m, inertia: m*L**2/12, frames: {bottom: {position: [0, -L/2, 0]}, top: {position: [0, L/2, 0]}}, initial: {position: [0, L/2], theta: 0, velocity: [speed/2, 0], angular_velocity: -speed/L}}
  h: {type: planar_body, mass: m, inertia: m*L**2/12, frames: {left: {position: [-L/2, 0, 0]}, right: {position: [L/2, 0, 0]}}, initial: {position: [L/2, L], theta: 0, velocity: [speed, 0]}}
joints:
  - {name: ground, type: revolute, parent: world.pivot, child: v.bottom}
  - {name: left, type: revolute, parent: v.top, child: h.left}
ports: {top: v.top, right: h.right}
"""

N_FOUR_BAR = """\
name: n_four_bar
parameters: {N: 2, L: 1.0, m: 1.0, g: 9.81, speed: 1.0}
gravity: [0, -g, 0]
world:
  frames:
    last: {position: [N*L, 0, 0]}
parts:
  cell: {type: model, file: four_bar_cell.yaml, count: N, parameters: {L: L, m: m, speed: speed}, placement: {position: [index*L, 0, 0]}}
  v: {type: planar_body, mass: m, inertia: m*L**2/12, frames: {bottom: {position: [0, -L/2, 0]}, top: {position: [0, L/2, 0]}}, initial: {position: [N*L, L/2], theta: 0, velocity: [speed/2, 0], angular_velocity: -speed/L}}
joints:
  - name: right
    for: {i: [0, N - 2]}
    type: revolute
    parent: cell[i + 1].top
    child: cell[i].right
  - {name: ground, type: revolute, parent: world.last, child: v.bottom}
  - {name: right_last, type: revolute, parent: v.top, child: "cell[N - 1].right"}
"""

# two cells joined by one revolute joint, used three times beside a single cell
PAIR = """\
name: pair
parameters: {L: 1.0}
parts:
  cell: {type: model, file: four_bar_cell.yaml, count: 2, parameters: {L: L}, placement: {position: [index*L, 0, 0]}}
joints:
  - {name: link, type: revolute, parent: "cell[1].top", child: "cell[0].right"}
"""

PAIRS = """\
name: pairs
parameters: {L: 1.0}
parts:
  pair: {type: model, file: pair.yaml, count: 3, parameters: {L: L}, placement: {position: [0, 3*index, 0]}}
  extra: {type: model, file: four_bar_cell.yaml}
"""


def write_n_four_bar(folder):
    """Write the cell, the N-four-bar, the pair and the pairs model into ``folder``; the
    N-four-bar's path."""
    for name, text in (("four_bar_cell.yaml", CELL), ("n_four_bar.yaml", N_FOUR_BAR), ("pair.yaml", PAIR),
                       ("pairs.yaml", PAIRS)):
        (folder / name).write_text(text)
    return folder / "n_four_bar.yaml"
