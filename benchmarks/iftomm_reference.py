"""Independent references for the benchmark problems of issue 18 (no mbsynth inside).

Used by ``benchmarks/iftomm.py`` and ``tests/test_benchmark_problems.py``:

- ``pendulum_exact``: the simple pendulum (IFToMM A01, any scale) released from rest,
  in closed form with Jacobi's elliptic functions.
- ``n_four_bar_yaml``: the N-four-bar mechanism (IFToMM A02) as model text, for any N;
  ``n_four_bar_reference``: its exact one-degree-of-freedom motion (all vertical bars
  stay parallel), integrated by scipy at rtol = atol = 1e-13.
- ``ANDREWS_T003``: the IVP test set's reference angles of Andrews' squeezer at 0.03 s.
- ``loop_gaps``: how far apart the two frames of every revolute joint are (positions and
  axes), computed from the bodies' coordinates with quaternions written out here, not
  with mbsynth's constraint rows: the loop closure of Bricard's and Bennett's linkages.
"""

import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.special import ellipj, ellipk

# ---------------------------------------------------------------------------------------
# A01: the simple pendulum


def pendulum_period(L, g, theta0):
    """Exact period 4 K(k) sqrt(L/g), k = sin(theta0/2) (K: complete elliptic integral of
    the first kind; scipy's ellipk takes the parameter m = k^2)."""
    k = math.sin(theta0 / 2)
    return 4 * ellipk(k * k) * math.sqrt(L / g)


def pendulum_exact(t, L, g, theta0):
    """Position (x, y) of a point pendulum of length L about the origin, gravity g along
    -y, released from rest at theta0 from the downward vertical on the side x < 0 (the
    A01 start, theta0 = pi/2: (-L, 0)).

    The angle phi (from the downward vertical, positive towards -x) obeys
    sin(phi/2) = k sn(K(k) - t sqrt(g/L); k), k = sin(theta0/2): at t = 0, sn(K) = 1 and
    phi = theta0 with zero rate (the classical solution, e.g. Lawden, "Elliptic Functions
    and Applications", 1989, section 5.2)."""
    t = np.asarray(t, dtype=float)
    k = math.sin(theta0 / 2)
    sn, _, _, _ = ellipj(ellipk(k * k) - t * math.sqrt(g / L), k * k)
    phi = 2 * np.arcsin(np.clip(k * sn, -1.0, 1.0))
    return -L * np.sin(phi), -L * np.cos(phi)


# ---------------------------------------------------------------------------------------
# A02: the N-four-bar mechanism

# The benchmark (González et al., Multibody System Dynamics 16 (2006) 179-190, problem
# A02; restated with the OpenSim model in RehabEngGroup/MBSbenchmarksInOpenSim,
# src/A02-NFourBarMechanism/modelProperties.h and help/benchmarks/A02_N_FourBarMechanism.rst):
# N + 1 vertical bars on ground pivots 1 m apart, their tops joined by N horizontal bars;
# every bar 1 m and 1 kg (a slender rod: cylinderAlongY(0, L/2) in the OpenSim model,
# I = m L^2 / 12 about its centre); gravity 9.81 m/s^2 along -y; all bars start vertical,
# the top B0 of the first vertical bar moving at 1 m/s along +x; 10 s in the benchmark
# (N = 40 in the library's statement of the problem, N = 2 in the OpenSim restatement);
# issue 18 runs 20 s.
N_FOUR_BAR = dict(L=1.0, m=1.0, g=9.81, v0=1.0)


def n_four_bar_yaml(N, L=1.0, m=1.0, g=9.81, v0=1.0):
    """The model text of the N-four-bar mechanism (planar bodies, revolute joints).

    Vertical bar ``v{i}`` (i = 0..N) on the ground pivot (i L, 0), its frames ``bottom``
    and ``top``; horizontal bar ``h{i}`` (i = 0..N-1) joining the tops of v{i} and v{i+1}.
    3 (2N + 1) coordinates, 2 (3N + 1) independent joint rows (each planar revolute
    joint has 5 rows of which 3 vanish identically in the plane): one degree of freedom,
    N + 1 when the bars are horizontal (the singular positions). Initial state: bars
    vertical, every vertical bar turning at -v0/L about z (B0 moving at v0 along +x),
    the horizontal bars translating at v0 along +x: consistent as written."""
    if N < 1:
        raise ValueError("N must be at least 1")
    lines = [
        f"# The IFToMM A02 N-four-bar mechanism with N = {N} (written by n_four_bar_yaml in",
        "# benchmarks/iftomm_reference.py; see its comments for the benchmark's statement).",
        f"# {N + 1} vertical bars on ground pivots L apart, their tops joined by {N} horizontal",
        "# bars; every bar a uniform slender rod of length L and mass m; gravity g along -y;",
        "# all bars vertical at the start, the first bar's top B0 moving at `speed` along +x.",
        "# Reference: the exact one-degree-of-freedom motion (n_four_bar_reference).",
        f"name: n_four_bar_{N}",
        f"parameters: {{L: {L!r}, m: {m!r}, g: {g!r}, speed: {v0!r}}}",
        "gravity: [0, -g, 0]",
        "world:",
        "  frames:",
    ]
    for i in range(N + 1):
        lines.append(f"    p{i}: {{position: [{i}*L, 0, 0]}}")
    lines.append("subsystems:")
    for i in range(N + 1):
        lines.append(f"  v{i}: {{type: planar_body, mass: m, inertia: m*L**2/12, "
                     f"frames: {{bottom: {{position: [0, -L/2, 0]}}, top: {{position: [0, L/2, 0]}}}}, "
                     f"initial: {{position: [{i}*L, L/2], theta: 0, velocity: [speed/2, 0], "
                     f"angular_velocity: -speed/L}}}}")
    for i in range(N):
        lines.append(f"  h{i}: {{type: planar_body, mass: m, inertia: m*L**2/12, "
                     f"frames: {{left: {{position: [-L/2, 0, 0]}}, right: {{position: [L/2, 0, 0]}}}}, "
                     f"initial: {{position: [{i}*L + L/2, L], theta: 0, velocity: [speed, 0]}}}}")
    lines.append("joints:")
    for i in range(N + 1):
        lines.append(f"  - {{name: ground{i}, type: revolute, parent: world.p{i}, child: v{i}.bottom}}")
    for i in range(N):
        lines.append(f"  - {{name: left{i}, type: revolute, parent: v{i}.top, child: h{i}.left}}")
        lines.append(f"  - {{name: right{i}, type: revolute, parent: v{i + 1}.top, child: h{i}.right}}")
    return "\n".join(lines) + "\n"


def n_four_bar_constants(N, L=1.0, m=1.0, g=9.81):
    """(J, K) of the one-degree-of-freedom equation J psi'' = K sin(psi).

    psi: the angle of every vertical bar from the upward vertical, clockwise (towards +x).
    The N + 1 vertical bars turn about their pivots (each m L^2/3, its centre at height
    (L/2) cos psi); the N horizontal bars translate without turning (each m, moving with
    the tops: speed L psi', height L cos psi). So
        T = 1/2 [(N + 1) m L^2/3 + N m L^2] psi'^2,  V = [(N + 1) m g L/2 + N m g L] cos psi,
    and Lagrange's equation gives J psi'' = K sin psi with J, K the brackets."""
    J = (N + 1) * m * L**2 / 3 + N * m * L**2
    K = (N + 1) * m * g * L / 2 + N * m * g * L
    return J, K


def n_four_bar_state(coordinates, N, psi, psi_dot, L=1.0):
    """(q, q') of the n_four_bar_yaml model with every vertical bar at psi turning at psi'
    (the exact one-degree-of-freedom motion's state): bar v{i}'s centre at
    (i L + (L/2) sin psi, (L/2) cos psi), its angle -psi; h{i} translating with the tops."""
    index = {name: k for k, name in enumerate(coordinates)}
    q, qd = np.zeros(len(coordinates)), np.zeros(len(coordinates))
    s, c = math.sin(psi), math.cos(psi)
    for i in range(N + 1):
        for name, value, rate in (("x", i * L + L / 2 * s, L / 2 * c * psi_dot),
                                  ("y", L / 2 * c, -L / 2 * s * psi_dot), ("theta", -psi, -psi_dot)):
            q[index[f"v{i}.{name}"]], qd[index[f"v{i}.{name}"]] = value, rate
    for i in range(N):
        for name, value, rate in (("x", i * L + L / 2 + L * s, L * c * psi_dot), ("y", L * c, -L * s * psi_dot)):
            q[index[f"h{i}.{name}"]], qd[index[f"h{i}.{name}"]] = value, rate
    return q, qd


def n_four_bar_reference(times, N, L=1.0, m=1.0, g=9.81, v0=1.0, rtol=1e-13, atol=1e-13):
    """Position of B0 (the first vertical bar's top) at ``times``: (x, y) arrays.

    Integrates J psi'' = K sin psi from psi = 0, psi' = v0/L with scipy's DOP853 at
    rtol = atol = 1e-13 (dense output); B0 = (L sin psi, L cos psi). The bars pass the
    singular (horizontal) positions psi = pi/2 + k pi without noticing: the reduced
    equation has none."""
    times = np.asarray(times, dtype=float)
    J, K = n_four_bar_constants(N, L, m, g)
    sol = solve_ivp(lambda t, y: (y[1], K / J * math.sin(y[0])), (0.0, float(times.max())), (0.0, v0 / L),
                    method="DOP853", rtol=rtol, atol=atol, dense_output=True)
    psi = sol.sol(times)[0]
    return L * np.sin(psi), L * np.cos(psi)


def n_four_bar_singular_times(N, t_end, L=1.0, m=1.0, g=9.81, v0=1.0):
    """The times in [0, t_end] when the bars are horizontal (psi = pi/2 + k pi)."""
    J, K = n_four_bar_constants(N, L, m, g)

    def crossing(t, y):
        return math.cos(y[0])
    sol = solve_ivp(lambda t, y: (y[1], K / J * math.sin(y[0])), (0.0, t_end), (0.0, v0 / L),
                    method="DOP853", rtol=1e-13, atol=1e-13, events=crossing)
    return sol.t_events[0]


# ---------------------------------------------------------------------------------------
# A03 / IVP test set: Andrews' squeezing mechanism

# The angles (beta, theta, gamma, phi, delta, omega, epsilon) at t = 0.03 s: subroutine
# SOLN of the test set's andrews.f (Mazzia & Magherini, Test Set for IVP Solvers,
# release 2.4; computed with PSIDE at rtol = atol = 1e-14 on a Cray C90). The same
# numbers are in the test set's report and in the copies of the problem in pySDC
# (projects/DAE, qend_ref_testset) and the SUNDIALS-style radau5 drivers.
ANDREWS_COORDINATES = ("beta", "theta", "gamma", "phi", "delta", "omega", "epsilon")
ANDREWS_T003 = np.array([
    0.1581077119629904e+2,
    -0.1575637105984298e+2,
    0.4082224013073101e-1,
    -0.5347301163226948e+0,
    0.5244099658805304e+0,
    0.5347301163226948e+0,
    0.1048080741042263e+1,
])
ANDREWS_MOM = 0.033   # the motor torque on beta (N m): its work mom (beta - beta0) enters the energy balance


# ---------------------------------------------------------------------------------------
# Loop closure of rigid-body models, computed from the coordinates alone


def quaternion_matrix(w, x, y, z):
    """Rotation matrix of the unit quaternion (w, x, y, z), scalar first."""
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def body_pose(coordinates, q, body):
    """(position of the centre of mass, rotation matrix) of rigid body ``body``."""
    index = {c: i for i, c in enumerate(coordinates)}
    r = np.array([q[index[f"{body}.{c}"]] for c in "xyz"])
    u = np.array([q[index[f"{body}.{c}"]] for c in ("qw", "qx", "qy", "qz")])
    return r, quaternion_matrix(*(u / np.linalg.norm(u)))


def loop_gaps(coordinates, q, joints):
    """The largest distance between the two points of the revolute joints and the largest
    |z_A x z_B| of their axes, for one state q.

    joints: a list of ((body or None, point in body, axis in body), (body, point, axis)),
    body None for the world (point and axis then in world coordinates); points and axes
    are those of the model file, relative to the body's centre of mass in its axes."""
    worst_point = worst_axis = 0.0
    for ends in joints:
        points, axes = [], []
        for body, point, axis in ends:
            if body is None:
                points.append(np.asarray(point, float))
                axes.append(np.asarray(axis, float))
            else:
                r, R = body_pose(coordinates, q, body)
                points.append(r + R @ np.asarray(point, float))
                axes.append(R @ np.asarray(axis, float))
        worst_point = max(worst_point, float(np.linalg.norm(points[0] - points[1])))
        a, b = (v / np.linalg.norm(v) for v in axes)
        worst_axis = max(worst_axis, float(np.linalg.norm(np.cross(a, b))))
    return worst_point, worst_axis


# The Bricard mechanism of models/mechanisms/bricard.yaml: the joint frames of each link
# (relative to its centre, in its axes; every link starts unrotated) and the ground.
BRICARD_JOINTS = [
    ((None, (0, 0, 0), (0, 1, 0)), ("link1", (-0.5, 0, 0), (0, 1, 0))),
    (("link1", (0.5, 0, 0), (0, 0, 1)), ("link2", (0, 0.5, 0), (0, 0, 1))),
    (("link2", (0, -0.5, 0), (1, 0, 0)), ("link3", (0, 0, -0.5), (1, 0, 0))),
    (("link3", (0, 0, 0.5), (0, 1, 0)), ("link4", (0.5, 0, 0), (0, 1, 0))),
    (("link4", (-0.5, 0, 0), (0, 0, 1)), ("link5", (0, -0.5, 0), (0, 0, 1))),
    (("link5", (0, 0.5, 0), (1, 0, 0)), (None, (0, 0, 1), (1, 0, 0))),
]
