"""Contact and impacts in mbsynth and in MuJoCo on the same scenes: accuracy at matched
time and time at matched accuracy (issue 63).

    .venv/bin/python benchmarks/contact.py [--quick]

MuJoCo (``pip install mujoco``, the ``benchmark`` extras) is a peer here only; the package
never imports it. Each scene has a reference from an independent source, and each code a
sweep of its accuracy knob: mbsynth ``simulate`` (event-driven: impacts as velocity jumps,
analysis/impacts.py) over rtol = atol; MuJoCo ``mj_step`` (its default semi-implicit Euler,
stepped in C by ``mujoco.rollout``) over its timestep.

Scenes and references:

- **ball**: models/contact/bouncing_ball.yaml (m = 0.2, r = 0.05, dropped from h0 = 1,
  e = 0.5). Reference: the closed-form bounce times t_k and apex heights. Error: the
  largest |t_k − exact| over the first ``BOUNCES`` bounces (mbsynth: its impact events;
  MuJoCo: where the gap crosses zero, linear between steps); the apex error (the apex of
  the free flight through the mid-flight state, z + ż²/(2g)) beside it.
- **stop**: models/contact/pendulum_stop.yaml with e = 1: a rod released at −0.8 rad
  strikes the hinge's stop at 0.3 rad at t1 (elliptic integrals) and again every 2 t1.
  Error: the largest |t_k − exact| of the first ``STRIKES`` strikes (MuJoCo: a limited
  hinge, where the angle crosses the stop).
- **cradle**: Newton's cradle of three free balls on a line (no gravity, e = 1), the first
  striking the two at rest. Reference: the exchange of velocities (0, 0, v), which
  conserves momentum and energy. Error: the largest |v_i − exact| / v after the impacts.
- **standing**: solo12 (example-robot-data) standing on its four feet at rest, no joint
  torques: the contact forces at that instant. Reference: ``pinocchio.constraintDynamics``
  (a CONTACT_3D per foot). mbsynth: the held motion of (2.14) with the feet's gap and
  slip rows (what a run solves while the feet hold; no knob: one exact solve). MuJoCo:
  ``mj_forward`` with a small sphere at each foot touching the ground plane, elliptic
  friction cones (μ = 5, wide enough that no foot slips), its knob here the constraint
  impedance d of ``solimp`` (its soft contact's force error is about (1 − d)/d; the
  timestep does not enter a state at rest). Error: the largest force difference over the
  largest force.

MuJoCo's contact is soft: a constraint obeys the spring–damper a_ref = −b ġ − k g of its
``solref`` (here its direct form −k, −b) and impedance d (``solimp``); it cannot express
Newton's exact restitution. The closest it comes, used here: no friction rows (condim 1)
where there is no friction, d = ``IMPEDANCE``, a damping ratio ζ whose linear
spring–damper contact (released where its force falls to zero) rebounds at e
(``damping_ratio``; ζ ≈ 0 for e = 1), and a frequency ω = 1/√(timestep × ``STIFFENING``)
that stiffens as the timestep shrinks, so that the contact's duration π/ω falls towards
Newton's instant while the steps it spans grow (a contact fixed in steps, MuJoCo's
timeconst = k × timestep, keeps a restitution error of a few % from the step that ends
each contact, at any timestep; MuJoCo's floor of 2 steps gains energy: a 1 m drop
rebounds to 2 m). Each bounce keeps e only up to gravity's share during the contact.

Timing: the best of ``--repeat`` runs of ``simulate`` (the model loaded and its kernels
compiled by a first run, not timed) and of ``rollout`` (the model compiled, not timed).
Summary per scene: "accuracy at matched time" — the smallest error each code reaches
within the time budget both can meet (the larger of the two codes' fastest run times) —
and "time at matched accuracy" — the least time each needs for the error both can reach
(the larger of the two codes' smallest errors).

Writes benchmarks/contact_results.md (``--quick``: two settings per code, one repeat,
printed, no file).
"""

import argparse
import datetime
import os
import platform
import sys
import time
from pathlib import Path

import mujoco
import numpy as np
import pinocchio as pin
from mujoco import rollout
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.special import ellipk, ellipkinc

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

import mbsynth as mb  # noqa: E402
from mbsynth.core.solvers import kkt_acceleration  # noqa: E402
from mbsynth.model.reactions import multipliers  # noqa: E402
from mbsynth.model.unilateral import Gaps  # noqa: E402
from mbsynth.robots.twin import Twin  # noqa: E402
from mujoco_twin import mjcf  # noqa: E402

MODELS = HERE.parent / "models" / "contact"
G = 9.81
BOUNCES = 4  # bounces of the ball compared (its 4th apex is e^8 ≈ 4e-3 of the drop above the ground)
STRIKES = 3  # strikes of the pendulum on its stop compared
IMPEDANCE = 0.99  # MuJoCo's solimp d (dmin = dmax) in the dynamic scenes: stiff, below its 0.9999 cap
STIFFENING = 0.016  # s: MuJoCo's contact frequency ω = 1/√(timestep × this): 12 steps a contact at 1 ms, 125 at 10 μs
LEAST_DAMPING = 1e-9  # MuJoCo's damping ratio for e = 1 (it reads a zero damping as a malformed solref)
TOLERANCES = (1e-4, 1e-6, 1e-8, 1e-10, 1e-12)  # mbsynth rtol = atol
TIMESTEPS = (1e-3, 3e-4, 1e-4, 3e-5, 1e-5)  # MuJoCo
IMPEDANCES = (0.9, 0.99, 0.999, 0.9999)  # MuJoCo's solimp d in the standing scene
FLOOR = 1e-16  # an error below rounding is shown as this


def damping_ratio(e):
    """MuJoCo's dampratio ζ whose contact x'' = −2ζ x' − x (unit frequency; x < 0 the
    penetration) struck at unit speed leaves at speed e, released where its force
    −2ζ x' − x falls to zero or the penetration ends."""
    if e >= 1:
        return LEAST_DAMPING

    def rebound(zeta):
        ends = lambda _, y: -2 * zeta * y[1] - y[0]  # noqa: E731
        ends.terminal, ends.direction = True, -1
        leaves = lambda _, y: y[0]  # noqa: E731
        leaves.terminal, leaves.direction = True, 1
        run = solve_ivp(lambda _, y: [y[1], -2 * zeta * y[1] - y[0]], (0, 10), [0.0, -1.0], events=(ends, leaves),
                        rtol=1e-12, atol=1e-12, first_step=1e-6)
        return run.y[1, -1]

    return brentq(lambda z: rebound(z) - e, 1e-9, 0.999, xtol=1e-12)


def timed(call, repeat):
    """(the result of ``call()``, the least wall time of ``repeat`` calls)."""
    best, result = np.inf, None
    for _ in range(repeat):
        start = time.perf_counter()
        result = call()
        best = min(best, time.perf_counter() - start)
    return result, best


# ---- MuJoCo's runs

def mujoco_run(xml, qpos, qvel, t_end, timestep):
    """(times, qpos, qvel) of every step of MuJoCo's model ``xml`` from (qpos, qvel) to
    ``t_end`` and the wall time of its rollout (callable: run by ``timed``)."""
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    data.qpos[:], data.qvel[:] = qpos, qvel
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, data, state, spec)
    steps = int(round(t_end / timestep))

    def run():
        out = rollout.rollout(model, data, state[None], nstep=steps)[0][0]
        return out[:, 0], out[:, 1:1 + model.nq], out[:, 1 + model.nq:1 + model.nq + model.nv]
    return run


def _solref(timestep, e):
    """MuJoCo's ``solref`` in its direct form (−stiffness, −damping): a contact of natural
    frequency ω = 1/√(timestep × STIFFENING) and the damping ratio of restitution e. As the
    timestep shrinks, the contact's duration π/ω shrinks (towards Newton's instant) and the
    steps it spans, π/(ω × timestep), grow: a ω fixed in steps (MuJoCo's timeconst = k ×
    timestep) keeps a restitution error of a few % from the steps that end a contact."""
    omega = float(1 / np.sqrt(timestep * STIFFENING))
    return f"{-omega**2!r} {-2 * damping_ratio(e) * omega!r}"


def _soft(timestep, e, d=IMPEDANCE):
    return f'condim="1" solref="{_solref(timestep, e)}" solimp="{d} {d} 0.001"'


def ball_mjcf(timestep, m, r, e):
    """The ball on a slide joint along z above the plane z = 0."""
    return f"""<mujoco model="ball">
  <option timestep="{timestep!r}" gravity="0 0 {-G}"/>
  <default><geom {_soft(timestep, e)}/></default>
  <worldbody>
    <geom type="plane" size="0 0 1"/>
    <body><joint name="z" type="slide" axis="0 0 1"/><geom type="sphere" size="{r!r}" mass="{m!r}"/></body>
  </worldbody>
</mujoco>"""


def stop_mjcf(timestep, m, L, r, lo, hi, e):
    """The rod on a hinge about y at the world origin, its centre L/2 below, limited to [lo, hi]."""
    return f"""<mujoco model="stop">
  <compiler angle="radian"/>
  <option timestep="{timestep!r}" gravity="0 0 {-G}"/>
  <worldbody>
    <body>
      <joint name="hinge" type="hinge" axis="0 1 0" limited="true" range="{lo!r} {hi!r}"
             solreflimit="{_solref(timestep, e)}" solimplimit="{IMPEDANCE} {IMPEDANCE} 0.001"/>
      <inertial pos="0 0 {-L / 2!r}" mass="{m!r}" diaginertia="{m * L**2 / 12!r} {m * L**2 / 12!r} {m * r**2 / 2!r}"/>
    </body>
  </worldbody>
</mujoco>"""


def cradle_mjcf(timestep, m, r, x):
    """Balls of radius r on slide joints along x at positions ``x``, no gravity, e = 1."""
    balls = "\n".join(f'    <body pos="{xk!r} 0 0"><joint type="slide" axis="1 0 0"/>'
                      f'<geom type="sphere" size="{r!r}" mass="{m!r}"/></body>' for xk in x)
    return f"""<mujoco model="cradle">
  <option timestep="{timestep!r}" gravity="0 0 0"/>
  <default><geom {_soft(timestep, 1.0)}/></default>
  <worldbody>
{balls}
  </worldbody>
</mujoco>"""


# ---- the scenes

class Ball:
    name, knob = "ball", "bounce times"
    m, r, h0, e = 0.2, 0.05, 1.0, 0.5

    def __init__(self):
        t1 = np.sqrt(2 * (self.h0 - self.r) / G)
        v = G * t1 * self.e ** np.arange(BOUNCES)  # the speed at each impact
        self.times = t1 + np.concatenate([[0.0], np.cumsum(2 * self.e * v[:-1] / G)])
        self.apexes = self.r + (self.e * v) ** 2 / (2 * G)
        self.t_end = self.times[-1] + self.e * v[-1] / G  # the last apex compared
        self.system = mb.load(MODELS / "bouncing_ball.yaml")

    def _errors(self, bounces, t, z, zd):
        """(bounce time error, apex error) of a run's bounce times and states."""
        if len(bounces) < BOUNCES:
            return np.inf, np.inf
        ends = np.append(bounces[1:BOUNCES], t[-1])
        apexes = []
        for start, end in zip(bounces[:BOUNCES], ends):
            i = np.searchsorted(t, (start + end) / 2)
            apexes.append(z[i] + zd[i] ** 2 / (2 * G))
        return np.abs(bounces[:BOUNCES] - self.times).max(), np.abs(np.array(apexes) - self.apexes).max()

    def mbsynth(self, tol, repeat):
        run = lambda: mb.simulate(self.system, self.t_end, rtol=tol, atol=tol, dt=self.t_end / 2000)  # noqa: E731
        traj, wall = timed(run, repeat)
        bounces = np.array([ev.t for ev in traj.events if ev.kind == "impact"])
        return wall, *self._errors(bounces, traj.t, traj.q[:, 2], traj.qd[:, 2])

    def mujoco(self, timestep, repeat):
        run = mujoco_run(ball_mjcf(timestep, self.m, self.r, self.e), [self.h0], [0.0], self.t_end, timestep)
        (t, q, qd), wall = timed(run, repeat)
        t, z, zd = np.r_[0.0, t], np.r_[self.h0, q[:, 0]], np.r_[0.0, qd[:, 0]]
        return wall, *self._errors(_crossings(t, z - self.r, -1), t, z, zd)


class Stop:
    name, knob = "stop", "strike times"
    m, L, r, theta0, lo, hi = 1.2, 0.8, 0.02, -0.8, -1.5, 0.3

    def __init__(self):
        k, w = np.sin(-self.theta0 / 2), np.sqrt(3 * G / (2 * self.L))
        t1 = (ellipkinc(np.arcsin(np.sin(self.hi / 2) / k), k * k) + ellipk(k * k)) / w
        self.times = t1 * (1 + 2 * np.arange(STRIKES))
        self.t_end = self.times[-1] + t1
        self.system = mb.load(MODELS / "pendulum_stop.yaml", parameters={"e": 1.0})

    def mbsynth(self, tol, repeat):
        run = lambda: mb.simulate(self.system, self.t_end, rtol=tol, atol=tol)  # noqa: E731
        traj, wall = timed(run, repeat)
        strikes = np.array([ev.t for ev in traj.events if ev.kind == "impact"])
        return wall, _time_error(strikes, self.times), np.nan

    def mujoco(self, timestep, repeat):
        xml = stop_mjcf(timestep, self.m, self.L, self.r, self.lo, self.hi, 1.0)
        (t, q, _), wall = timed(mujoco_run(xml, [self.theta0], [0.0], self.t_end, timestep), repeat)
        t, angle = np.r_[0.0, t], np.r_[self.theta0, q[:, 0]]
        return wall, _time_error(_crossings(t, self.hi - angle, -1), self.times), np.nan


class Cradle:
    name, knob = "cradle", "velocities after"
    m, r, gap, speed, count, t_end = 0.3, 0.1, 0.05, 1.3, 3, 0.2

    def __init__(self):
        self.x = [0.0] + [self.gap + 2 * self.r * k for k in range(1, self.count)]
        balls = "\n".join(f"  b{k}: {{type: particle, mass: m, initial: {{position: [{self.x[k]!r}, 0, 0]"
                          + (f", velocity: [{self.speed!r}, 0, 0]" if k == 0 else "") + "}}"
                          for k in range(self.count))
        contacts = "\n".join(f"  - {{name: c{k}, type: spheres, between: [b{k}, b{k + 1}], radius: [r, r], "
                             f"restitution: 1}}" for k in range(self.count - 1))
        self.system = mb.loads(f"name: cradle\nparameters: {{m: {self.m}, r: {self.r}}}\nparts:\n{balls}\n"
                               f"contacts:\n{contacts}\n")
        self.exact = np.r_[np.zeros(self.count - 1), self.speed]

    def _errors(self, v):
        """(velocity error over v, energy error over the energy)."""
        return (np.abs(v - self.exact).max() / self.speed,
                abs((v**2).sum() - self.speed**2) / self.speed**2)

    def mbsynth(self, tol, repeat):
        traj, wall = timed(lambda: mb.simulate(self.system, self.t_end, rtol=tol, atol=tol), repeat)
        return wall, *self._errors(traj.qd[-1, 0::3])

    def mujoco(self, timestep, repeat):
        xml = cradle_mjcf(timestep, self.m, self.r, self.x)
        run = mujoco_run(xml, np.zeros(self.count), np.r_[self.speed, np.zeros(self.count - 1)], self.t_end, timestep)
        (_, _, qd), wall = timed(run, repeat)
        self.note = (f"MuJoCo's balls leave at ({', '.join(f'{v / self.speed:.3f}' for v in qd[-1])}) v at its "
                     f"timestep {timestep:g} s: its soft constraints set each contact's own acceleration, so the two "
                     f"balls at rest, touching, move as one body of mass 2m: the striker rebounds at −v/3 and the "
                     f"two leave at 2v/3, not (0, 0, 1) v.")
        return wall, *self._errors(qd[-1])


class Standing:
    name, knob = "standing", "contact forces"
    feet = ("FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT")
    joints = (0.0, 0.8, -1.6, 0.0, 0.8, -1.6, 0.0, -0.8, 1.6, 0.0, -0.8, 1.6)  # solo12 standing straight
    radius, mu = 1e-3, 5.0  # MuJoCo's foot spheres; its friction (no foot slips)

    def __init__(self):
        contacts = "\n".join(f"  - {{name: {f}, type: plane, child: solo_{f}.link, ground: h, friction: 1}}"
                             for f in self.feet)
        text = f"name: solo_standing\nparameters: {{h: -1.0}}\ngravity: [0, 0, {-G}]\nparts:\n" \
               f"  solo: {{type: robot, robot: solo12, floating: true}}\ncontacts:\n{contacts}\n"
        system = mb.loads(text)
        model = pin.buildModelFromUrdf(system.robots[0].description.path, pin.JointModelFreeFlyer())
        model.gravity.linear = np.array([0.0, 0.0, -G])
        data = model.createData()
        q = np.r_[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, self.joints]
        pin.framesForwardKinematics(model, data, q)
        ids = [model.getFrameId(f) for f in self.feet]
        heights = [data.oMf[i].translation[2] for i in ids]
        q[2] -= np.mean(heights)  # the feet on the ground z = 0
        pin.framesForwardKinematics(model, data, q)
        self.q, self.v, self.model, self.ids = q, np.zeros(model.nv), model, ids
        self.system = system = system.with_parameters(h=0.0)  # loaded with the ground below the robot
        twin = Twin(system)
        self.qm, self.qdm = twin.to_maximal(q, self.v)
        contacts = [pin.RigidConstraintModel(pin.ContactType.CONTACT_3D, model, model.frames[i].parentJoint,
                                             model.frames[i].placement, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
                    for i in ids]
        contact_data = [c.createData() for c in contacts]
        pin.initConstraintDynamics(model, data, contacts, contact_data)
        pin.constraintDynamics(model, data, q, self.v, np.zeros(model.nv), contacts, contact_data,
                               pin.ProximalSettings(1e-14, 1e-12, 100))
        self.exact = np.array(data.lambda_c).reshape(4, 3)
        self.feet_at = [data.oMf[i].translation.copy() for i in ids]
        self.spread = max(heights) - min(heights)

    def _error(self, forces):
        return np.abs(forces - self.exact).max() / np.abs(self.exact).max()

    def mbsynth(self, _tol, repeat):
        system, qm, qdm = self.system, self.qm, self.qdm
        kept = system.data()
        gaps = Gaps(system, kept.parameter_values)
        p = kept.parameter_values

        def solve():
            arrays = kept.evaluate(0.0, qm, qdm)
            A_gaps, b_gaps = gaps.rows(0.0, qm, qdm, p)
            slips = [gaps.slip_arrays(0.0, qm, qdm, p, i) for i in range(4)]
            A = np.vstack([arrays.A, A_gaps, *(T for T, _ in slips)])
            b = np.concatenate([arrays.b, b_gaps, *(b_slip for _, b_slip in slips)])
            motion = kkt_acceleration(arrays.M, arrays.Q, A, b, arrays.C)
            lam = multipliers(A, arrays.M @ motion.qdd - arrays.Q - arrays.C)[0]
            k = len(arrays.b)
            return np.column_stack([lam[k + 4:].reshape(4, 2), lam[k:k + 4]])  # (x, y, z) per foot

        for _ in range(3):  # its kernels compiled and chosen (compiled/grouped.py), not timed
            solve()
        forces, wall = timed(solve, max(repeat, 10))
        return wall, self._error(forces), np.nan

    def mujoco(self, d, repeat):
        model, data = self.model, self.model.createData()
        pin.forwardKinematics(model, data, self.q)
        text = mjcf(model).replace('<flag contact="disable"/>', "")
        text = text.replace("<option ", '<option cone="elliptic" tolerance="1e-14" iterations="200" ')
        for foot, at in zip(self.ids, self.feet_at):
            frame = model.frames[foot]
            body = data.oMi[frame.parentJoint]
            local = body.rotation.T @ (at + np.array([0, 0, self.radius]) - body.translation)
            line = f'<body name="{model.names[frame.parentJoint]}" '
            start = text.index(line)
            end = text.index("\n", text.index("<inertial", start))
            text = text[:end] + f'\n<geom type="sphere" size="{self.radius!r}" pos="{_numbers(local)}" ' \
                                f'mass="0" friction="{self.mu} 0 0" solimp="{d} {d} 0.001"/>' + text[end:]
        text = text.replace("<worldbody>", f'<worldbody>\n<geom type="plane" size="0 0 1" pos="0 0 {-1e-9}" '
                                           f'friction="{self.mu} 0 0" solimp="{d} {d} 0.001"/>')
        mj = mujoco.MjModel.from_xml_string(text)
        mjd = mujoco.MjData(mj)
        q = self.q.copy()
        q[3:7] = np.roll(q[3:7], 1)
        mjd.qpos[:], mjd.qvel[:] = q, 0.0

        def forward():
            mujoco.mj_forward(mj, mjd)
            found = np.zeros((4, 3))
            wrench = np.zeros(6)
            for i in range(mjd.ncon):
                contact = mjd.contact[i]
                mujoco.mj_contactForce(mj, mjd, i, wrench)
                force = contact.frame.reshape(3, 3).T @ wrench[:3]  # world axes, on geom2 (the foot)
                body = mj.geom_bodyid[contact.geom2]
                name = mujoco.mj_id2name(mj, mujoco.mjtObj.mjOBJ_BODY, body)
                k = [model.names[model.frames[f].parentJoint] for f in self.ids].index(name)
                found[k] += force
            return found, mjd.ncon

        (forces, count), wall = timed(forward, max(repeat, 10))
        return wall, (self._error(forces) if count == 4 else np.inf), np.nan


def _numbers(values):
    return " ".join(f"{x:.17g}" for x in values)


def _crossings(t, g, direction):
    """The times where g crosses zero going ``direction`` (−1: from above), linear between samples."""
    found = []
    for i in np.flatnonzero((g[:-1] > 0) & (g[1:] <= 0) if direction < 0 else (g[:-1] < 0) & (g[1:] >= 0)):
        found.append(t[i] + (t[i + 1] - t[i]) * g[i] / (g[i] - g[i + 1]))
    return np.array(found)


def _time_error(found, exact):
    return np.abs(found[:len(exact)] - exact).max() if len(found) >= len(exact) else np.inf


# ---- the sweeps and the summary

def sweep(scene, quick, repeat):
    """{code: [(setting, wall, error, second error)]} of a scene."""
    tolerances = TOLERANCES[1::3] if quick else TOLERANCES
    settings = (IMPEDANCES[::3] if quick else IMPEDANCES) if scene.name == "standing" else \
        (TIMESTEPS[:2] if quick else TIMESTEPS)
    if scene.name == "standing":
        tolerances = tolerances[:1]  # one exact solve: no knob
    else:
        scene.mbsynth(tolerances[0], 1)  # the kernels compiled, not timed
    rows = {"mbsynth": [(tol, *scene.mbsynth(tol, repeat)) for tol in tolerances],
            "MuJoCo": [(s, *scene.mujoco(s, repeat)) for s in settings]}
    return rows


def summary(rows):
    """(budget, {code: its least error within it}, target, {code: its least time to reach it})."""
    budget = max(min(wall for _, wall, *_ in runs) for runs in rows.values())
    at_time = {code: min(max(err, FLOOR) for _, wall, err, _ in runs if wall <= budget) for code, runs in rows.items()}
    target = max(min(max(err, FLOOR) for _, _, err, _ in runs) for runs in rows.values())
    at_error = {code: min(wall for _, wall, err, _ in runs if max(err, FLOOR) <= target) for code, runs in rows.items()}
    return budget, at_time, target, at_error


def report(results, repeat):
    lines = ["# Contact and impacts: mbsynth beside MuJoCo", "",
             "Written by `benchmarks/contact.py` (its docstring says what each scene, reference, error and",
             "knob is). Times are wall seconds, the best of "
             f"{repeat} runs, on one machine shared with other jobs (noisy).", "",
             f"- {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, {platform.processor() or platform.machine()}, "
             f"{os.cpu_count()} CPUs, Python {platform.python_version()}, mbsynth {mb.__version__}, "
             f"MuJoCo {mujoco.__version__}, Pinocchio {pin.__version__}", "",
             "MuJoCo's contact is soft (a spring–damper per constraint, `solref`/`solimp`): it cannot",
             "express Newton's exact restitution. The closest setting is used (the script's docstring):",
             f"impedance d = {IMPEDANCE}, the damping ratio of e's linear spring–damper contact, and a",
             f"frequency ω = 1/√(timestep × {STIFFENING} s) that stiffens with the timestep; its contacts",
             "last π/ω (28 ms at a 1 ms timestep, 1.3 ms at 10 μs), a duration Newton's law has not.", "",
             "## Summary", "",
             "| scene | reference | budget (s) | mbsynth error at it | MuJoCo error at it | target error | "
             "mbsynth time (s) | MuJoCo time (s) |",
             "|---|---|---|---|---|---|---|---|"]
    for scene, rows in results:
        budget, at_time, target, at_error = summary(rows)
        lines.append(f"| {scene.name} | {scene.knob} | {budget:.3g} | {at_time['mbsynth']:.2g} | "
                     f"{at_time['MuJoCo']:.2g} | {target:.2g} | {at_error['mbsynth']:.3g} | {at_error['MuJoCo']:.3g} |")
    lines += ["", "Budget: the larger of the two codes' fastest run times; each code's least error within it",
              "(accuracy at matched time). Target: the larger of the two codes' least errors; each code's",
              "least time to reach it (time at matched accuracy). An error below rounding shows as "
              f"{FLOOR:g}.", ""]
    for scene, rows in results:
        second = {"ball": "apex error (m)", "cradle": "energy error (rel.)"}.get(scene.name)
        knob = {"standing": "solimp d"}.get(scene.name, "timestep (s)")
        lines += [f"## {scene.name}: {scene.knob}", "",
                  "| code | setting | wall (s) | error |" + (f" {second} |" if second else ""),
                  "|---|---|---|---|" + ("---|" if second else "")]
        for code, runs in rows.items():
            for setting, wall, err, other in runs:
                label = ("exact solve" if scene.name == "standing" else f"rtol = atol = {setting:g}") \
                    if code == "mbsynth" else f"{knob} = {setting:g}"
                lines.append(f"| {code} | {label} | {wall:.3g} | {max(err, FLOOR):.2g} |"
                             + (f" {max(other, FLOOR):.2g} |" if second else ""))
        lines.append("")
        if getattr(scene, "note", None):
            lines += [scene.note, ""]
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="two settings per code, one repeat, printed")
    parser.add_argument("--repeat", type=int, default=3, help="runs timed per setting (the best kept)")
    parser.add_argument("--out", default=str(HERE / "contact_results.md"))
    args = parser.parse_args()
    repeat = 1 if args.quick else args.repeat
    results = []
    for scene in (Ball(), Stop(), Cradle(), Standing()):
        results.append((scene, sweep(scene, args.quick, repeat)))
        print(f"{scene.name}: done", flush=True)
    text = report(results, repeat)
    print(text)
    if not args.quick:
        Path(args.out).write_text(text + "\n")


if __name__ == "__main__":
    main()
