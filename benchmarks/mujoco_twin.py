"""A Pinocchio model as a MuJoCo model, for benchmarks/end_to_end.py.

``MujocoTwin(model)`` writes the MJCF of a Pinocchio model whose joints are revolute
about x, y or z (JointModelRX/RY/RZ) below a fixed or free-flyer root: one body per joint
at the joint's placement, its inertia Pinocchio's (mass, centre of mass, rotational
inertia there: ``fullinertia``), a hinge about the joint's axis (a ``freejoint`` for the
root), Pinocchio's gravity, no geometry (so no contacts), no limits, damping or armature.
MuJoCo then computes the same forward dynamics (``mj_forward``'s qacc against ``pin.aba``:
``check``). Its state differs: quaternions scalar-first, the free joint's linear velocity
in world axes (Pinocchio's in the body's), angular in the body's as Pinocchio's
(``state``); ``rhs`` is f(t, (qpos, qvel)) = (q̇pos, qacc) for scipy's solve_ivp.
"""

import mujoco
import numpy as np
import pinocchio as pin

AXES = {"JointModelRX": "1 0 0", "JointModelRY": "0 1 0", "JointModelRZ": "0 0 1"}


class MujocoTwin:
    """MuJoCo's model of a Pinocchio ``model`` (module docstring)."""

    def __init__(self, model):
        self.pinocchio = model
        self.free = model.njoints > 1 and model.joints[1].shortname() == "JointModelFreeFlyer"
        self.model = mujoco.MjModel.from_xml_string(mjcf(model))
        self.data = mujoco.MjData(self.model)
        names = [mujoco.mj_id2name(self.model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(self.model.njnt)]
        if names != [f"j{i}" for i in range(1, model.njoints)]:
            raise ValueError("MuJoCo ordered the joints differently from Pinocchio")
        self.nq, self.nv = self.model.nq, self.model.nv

    def state(self, q, v):
        """MuJoCo's (qpos, qvel) as one vector from Pinocchio's (q, v)."""
        q, v = np.array(q, dtype=float), np.array(v, dtype=float)
        if self.free:
            R = pin.Quaternion(q[6], *q[3:6]).toRotationMatrix()
            q[3:7] = np.roll(q[3:7], 1)  # (x, y, z, w) -> (w, x, y, z)
            v[:3] = R @ v[:3]
        return np.concatenate([q, v])

    def configuration(self, qpos):
        """Pinocchio's q from MuJoCo's qpos."""
        q = np.array(qpos, dtype=float)
        if self.free:
            q[3:7] = np.roll(q[3:7], -1)
        return q

    def acceleration(self, qpos, qvel):
        """MuJoCo's forward dynamics, qacc."""
        self.data.qpos[:], self.data.qvel[:] = qpos, qvel
        mujoco.mj_forward(self.model, self.data)
        return self.data.qacc

    def rhs(self):
        """f(t, (qpos, qvel)) = (q̇pos, qacc): for a free joint ẋ = its world velocity and
        u̇ = ½ u ⊗ (0, ω) with ω in the body's axes."""
        model, data, nq = self.model, self.data, self.nq
        if not self.free:
            def f(_, y):
                data.qpos[:], data.qvel[:] = y[:nq], y[nq:]
                mujoco.mj_forward(model, data)
                return np.concatenate([y[nq:], data.qacc])
            return f

        def f(_, y):
            data.qpos[:], data.qvel[:] = y[:nq], y[nq:]
            mujoco.mj_forward(model, data)
            w, xyz, omega = y[3], y[4:7], y[nq + 3:nq + 6]
            rate = np.concatenate([[-0.5 * xyz @ omega], 0.5 * (w * omega + np.cross(xyz, omega))])
            return np.concatenate([y[nq:nq + 3], rate, y[nq + 6:], data.qacc])
        return f

    def check(self, rng):
        """The largest difference of MuJoCo's qacc from ``pin.aba`` (Pinocchio's velocity
        axes) at a random state, relative to the largest acceleration."""
        model = self.pinocchio
        q = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
        v = rng.uniform(-1, 1, model.nv)
        expected = pin.aba(model, model.createData(), q, v, np.zeros(model.nv))
        y = self.state(q, v)
        got = np.array(self.acceleration(y[:self.nq], y[self.nq:]))
        if self.free:  # MuJoCo's linear acceleration: d/dt of the world velocity R v
            R = pin.Quaternion(q[6], *q[3:6]).toRotationMatrix()
            got[:3] = R.T @ got[:3] - np.cross(v[3:6], v[:3])
        return float(np.abs(got - expected).max() / np.abs(expected).max())


def mjcf(model):
    """The MJCF text of a Pinocchio ``model`` (module docstring)."""
    children = {i: [] for i in range(model.njoints)}
    for i in range(1, model.njoints):
        children[model.parents[i]].append(i)
    g = model.gravity.linear

    def body(i, indent):
        kind = model.joints[i].shortname()
        if kind == "JointModelFreeFlyer" and i == 1:
            joint = '<freejoint name="j1"/>'
        elif kind in AXES:
            joint = f'<joint name="j{i}" type="hinge" axis="{AXES[kind]}" limited="false"/>'
        else:
            raise ValueError(f"joint {model.names[i]}: {kind} is not revolute about x, y or z")
        placement, inertia = model.jointPlacements[i], model.inertias[i]
        I = inertia.inertia
        full = " ".join(f"{x:.17g}" for x in (I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]))
        pad = " " * indent
        lines = [f'{pad}<body name="{model.names[i]}" pos="{_numbers(placement.translation)}" '
                 f'quat="{_numbers(_quaternion(placement.rotation))}">',
                 f'{pad}  <inertial pos="{_numbers(inertia.lever)}" mass="{inertia.mass:.17g}" fullinertia="{full}"/>',
                 f"{pad}  {joint}"]
        for child in children[i]:
            lines += body(child, indent + 2)
        return lines + [f"{pad}</body>"]

    lines = ['<mujoco model="twin">', '  <compiler angle="radian"/>',
             f'  <option gravity="{_numbers(g)}"><flag contact="disable"/></option>', "  <worldbody>"]
    for child in children[0]:
        lines += body(child, 4)
    return "\n".join(lines + ["  </worldbody>", "</mujoco>"]) + "\n"


def _quaternion(R):
    """(w, x, y, z) of a rotation matrix."""
    u = pin.Quaternion(R)
    return np.array([u.w, u.x, u.y, u.z])


def _numbers(values):
    return " ".join(f"{x:.17g}" for x in values)
