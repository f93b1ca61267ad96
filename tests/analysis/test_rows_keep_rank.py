"""Models whose rows keep their rank along every motion (singular_watch.rows_keep_rank): a
tree of joints of the rank-keeping kinds on quaternion parts. Their runs have no singular
position to watch for: the claim is checked against the singular values of the equilibrated
A along a moving run (numpy's SVD), and the run without the watch against the run with it."""

import numpy as np
import pytest

import mbsynth as mb
from mbsynth.analysis import continuous
from mbsynth.analysis.singular_watch import RANK_KEEPING_KINDS, SingularWatch, rows_keep_rank
from mbsynth.core.tolerances import NEAR_SINGULAR
from tests.model.flexible.test_flexible_pendulum import pendulum_yaml

# a chain hung from the world by one joint of each rank-keeping kind, joint frames turned
# away from the parts' axes so that no row lines up with a coordinate
CHAIN = """
name: every_kind
gravity: [0, 0, -9.81]
parts:
{parts}
joints:
  - {{name: j1, type: revolute, parent: world, child: b1.top}}
  - {{name: j2, type: prismatic, parent: b1.tip, child: b2.top}}
  - {{name: j3, type: cylindrical, parent: b2.tip, child: b3.top}}
  - {{name: j4, type: spherical, parent: b3.tip, child: b4.top}}
  - {{name: j5, type: universal, parent: b4.tip, child: b5.top}}
  - {{name: j6, type: {last}, parent: b5.tip, child: b6.top{length}}}
"""
PART = """  b{k}:
    type: rigid_body
    mass: {mass}
    inertia: [0.02, 0.03, 0.01]
    frames:
      top: {{position: [0, 0, 0.2], axis: [0.3, 0.4, 0.866]}}
      tip: {{position: [0.05, 0, -0.2], axis: [0.6, 0, 0.8]}}
    initial: {{position: [0, 0, {z}]}}"""


def chain(last="fixed", length=""):
    parts = "\n".join(PART.format(k=k, mass=0.5 + 0.1 * k, z=-0.4 * k) for k in range(1, 7))
    return mb.loads(CHAIN.format(parts=parts, last=last, length=length), name="every_kind")


def test_the_chain_has_every_rank_keeping_kind():
    """The chain's joints are of every kind of RANK_KEEPING_KINDS (the evidence below covers them all)."""
    used = {con.joint_kind for con in chain().constraints if hasattr(con, "joint_kind")}
    assert used == set(RANK_KEEPING_KINDS)


def test_trees_of_rank_keeping_joints_on_quaternion_parts_keep_rank():
    assert rows_keep_rank(chain())
    assert rows_keep_rank(mb.loads(pendulum_yaml(4)))
    assert rows_keep_rank(mb.from_robot("ur5"))


@pytest.mark.parametrize("model", ["models/mechanisms/bricard.yaml", "models/mechanisms/four_bar.yaml",
                                   "models/mechanisms/double_pendulum_rods.yaml", "models/joints/cart_pole_servo.yaml",
                                   "models/contact/pendulum_stop.yaml", "models/flexible/spin_up_beam.yaml"])
def test_loops_other_rows_and_parts_and_limits_are_not_claimed(model):
    """A loop (Bricard's spatial one; the four-bar's of planar parts), distance rows (a rod's
    length), a servo row, a joint with limits, a part turned by angles: no claim."""
    assert not rows_keep_rank(mb.load(model))


def test_a_distance_joint_in_the_chain_is_not_claimed():
    assert not rows_keep_rank(chain("distance", ", length: 0.3"))


def test_the_chains_rows_keep_full_rank_along_a_moving_run():
    """The every-kind chain released with every joint moving: at each of its output rows the
    equilibrated A has full row rank, its smallest singular value far above NEAR_SINGULAR of
    its largest (numpy's SVD: the watch's own measure)."""
    system = chain()
    q, qd = system.initial_state()
    qd = qd + 0.8 * np.cos(np.arange(qd.size))
    traj = mb.simulate(system, 1.0, dt=0.02, qd0=qd)
    data = system.data()
    watch = SingularWatch(data, 0.0, traj.q[0], traj.qd[0])
    assert watch.rank == len(system.constraint_names)
    ratios = [watch._measure(t, q, qd) for t, q, qd in zip(traj.t, traj.q, traj.qd)]
    assert min(ratios) > 1e3 * NEAR_SINGULAR, min(ratios)


def test_a_run_that_keeps_rank_ends_where_the_watched_run_ends(monkeypatch):
    """The flexible pendulum (projected by extra_projection.py, which a watch follows) runs
    with no watch; with one forced on it ends at the same state, bit for bit."""
    system = mb.loads(pendulum_yaml(4))
    made = []
    original = SingularWatch.__init__

    def counted(self, *args):
        made.append(1)
        original(self, *args)
    monkeypatch.setattr(SingularWatch, "__init__", counted)
    alone = mb.simulate(system, 0.3, rtol=1e-8, atol=1e-8)
    assert not made
    keeping = continuous.ContinuousIntegration.__init__

    def watching(self, *args):  # the watch forced on, the drift target (integration.drift_target) kept
        keeping(self, *args)
        self.keeps_rank = False
    monkeypatch.setattr(continuous.ContinuousIntegration, "__init__", watching)
    watched = mb.simulate(system, 0.3, rtol=1e-8, atol=1e-8)
    assert made
    assert alone.q[-1].tobytes() == watched.q[-1].tobytes() and alone.qd[-1].tobytes() == watched.qd[-1].tobytes()
