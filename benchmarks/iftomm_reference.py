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
- ``flyball_reference``: the stiff flyball governor (IFToMM A05) in its four coordinates,
  Lagrange's equations written by hand (the library's own time history was not found).
- ``slider_crank_3d_reference``: the IFToMM library's spatial rigid slider-crank, the
  crank angle's one equation written by hand; ``SLIDER_CRANK_3D_PUBLISHED``: the
  library's published solution (M. González), the slider's x every 0.1 s.
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
    lines.append("parts:")
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


# ---------------------------------------------------------------------------------------
# A05: the stiff flyball governor (models/mechanisms/flyball_governor.yaml)

# The benchmark's data (the library's A05 specification; restated in
# RehabEngGroup/MBSbenchmarksInOpenSim src/A05-FlyballGovernor/createModel.cpp and
# modelProperties.h, and in Exudyn's Examples/stiffFlyballGovernorKT.py): bars of
# 1 m x 0.01 m x 0.01 m at 3000 kg/m^3, a 0.1 m cube of 3 kg, 5 kg point masses, springs
# k = 8e5 N/m, c = 4e4 N s/m, rest length 0.5 m, pins at (+-0.05, 0, 1) m, slider at
# s = 0.5 m, rods 30 degrees below the horizontal, shaft turning freely at 2 pi rad/s.
# The library's own reference time history (s(t)) could not be read from the sources
# searched (only the header of A05_specification.xml is stored; the OpenSim restatement
# shows it as a plot only), so the reference here is independent: flyball_reference.
FLYBALL = dict(rho=3000.0, a=0.01, L=1.0, b=0.1, ms=3.0, mb=5.0, d=0.05, alpha=math.pi / 6, s0=0.5,
               k=8.0e5, c=4.0e4, l0=0.5, omega0=2 * math.pi, g=9.81)


def flyball_reference(times, rtol=1e-12, atol=1e-12, **data):
    """The flyball governor's motion in its four coordinates, at ``times``.

    Coordinates: the shaft angle phi, the slider height s (its centre above the shaft's
    foot), and each rod's angle beta_i below the horizontal. In the shaft's turning frame
    rod i's direction is u_i = (+-cos beta_i, 0, -sin beta_i) from its pin (+-d, 0, L); the
    rod (mass m_r, inertia It across and Ia along about its middle) turns at
    phi' e_z + beta_i' e_y, its middle and its point mass at L/2 and L along u_i. Every
    point p = (x, 0, z) of the turning frame moves at |v|^2 = x'^2 + z'^2 + phi'^2 x^2, so
    the kinetic energy is T = 1/2 [M_phi phi'^2 + m_s s'^2 + M_b (beta_1'^2 + beta_2'^2)] with
        M_phi = I_shaft + I_slider + sum_i [It - (It - Ia) sin^2 beta_i
                + m_r (d + L/2 cos beta_i)^2 + m_b (d + L cos beta_i)^2],
        M_b = It + m_r L^2/4 + m_b L^2;
    the potential is g [m_s s + sum_i (m_r (L - L/2 sin beta_i) + m_b (L - L sin beta_i))]
    + sum_i k (l_i - l0)^2 / 2, l_i the length of spring i from the slider's side
    (+-d, 0, s) to rod i's middle: (L/2 cos beta_i, L - L/2 sin beta_i - s) in the plane;
    the dampers dissipate c l_i'^2. Lagrange's equations: (M_phi phi')' = 0 (phi cyclic),
    m_s s'' = Q_s, M_b beta_i'' = 1/2 dM_phi/dbeta_i phi'^2 + Q_i, with Q the spring,
    damper and gravity forces. Integrated by scipy's DOP853 at rtol = atol = 1e-12 (the
    dampers' fast mode, about 2 c sin^2(alpha)/m_s = 7e3 1/s, only bounds its steps).
    Returns a dict of arrays: phi, s, beta1, beta2, their rates (phi_dot, s_dot, ...), and
    W, the work the dampers dissipated since t = 0 (E(t) = E(0) - W)."""
    p = dict(FLYBALL, **data)
    a, L, d, g, k, c, l0 = p["a"], p["L"], p["d"], p["g"], p["k"], p["c"], p["l0"]
    m_bar = p["rho"] * a * a * L
    It, Ia = m_bar * (L * L + a * a) / 12, m_bar * 2 * a * a / 12
    I_axis = m_bar * 2 * a * a / 12 + p["ms"] * 2 * p["b"] ** 2 / 12    # shaft and slider about z
    ms, mb = p["ms"], p["mb"]
    Mb = It + m_bar * L * L / 4 + mb * L * L

    def M_phi(beta):
        s, co = math.sin(beta), math.cos(beta)
        return It - (It - Ia) * s * s + m_bar * (d + L / 2 * co) ** 2 + mb * (d + L * co) ** 2

    def dM_phi(beta):
        s, co = math.sin(beta), math.cos(beta)
        return -2 * (It - Ia) * s * co - m_bar * (d + L / 2 * co) * L * s - 2 * mb * (d + L * co) * L * s

    def spring(s_, beta, s_dot, beta_dot):
        """(force along the spring, dl/ds, dl/dbeta, l')."""
        hx, hz = L / 2 * math.cos(beta), L - L / 2 * math.sin(beta) - s_
        length = math.hypot(hx, hz)
        dl_ds = -hz / length
        dl_db = (hx * (-L / 2 * math.sin(beta)) + hz * (-L / 2 * math.cos(beta))) / length
        rate = dl_ds * s_dot + dl_db * beta_dot
        return k * (length - l0) + c * rate, dl_ds, dl_db, rate

    def rhs(t, y):
        _, s_, b1, b2, w, sd, bd1, bd2, _ = y
        M = I_axis + M_phi(b1) + M_phi(b2)
        f1, ds1, db1, r1 = spring(s_, b1, sd, bd1)
        f2, ds2, db2, r2 = spring(s_, b2, sd, bd2)
        Qs = -ms * g - f1 * ds1 - f2 * ds2
        Q1 = g * (m_bar * L / 2 + mb * L) * math.cos(b1) - f1 * db1
        Q2 = g * (m_bar * L / 2 + mb * L) * math.cos(b2) - f2 * db2
        w_dot = -(dM_phi(b1) * bd1 + dM_phi(b2) * bd2) * w / M
        return (w, sd, bd1, bd2, w_dot, Qs / ms, (0.5 * dM_phi(b1) * w * w + Q1) / Mb,
                (0.5 * dM_phi(b2) * w * w + Q2) / Mb, c * (r1 * r1 + r2 * r2))

    times = np.asarray(times, dtype=float)
    y0 = (0.0, p["s0"], p["alpha"], p["alpha"], p["omega0"], 0.0, 0.0, 0.0, 0.0)
    sol = solve_ivp(rhs, (0.0, float(times.max())), y0, method="DOP853", rtol=rtol, atol=atol,
                    dense_output=True)
    y = sol.sol(times)
    names = ("phi", "s", "beta1", "beta2", "phi_dot", "s_dot", "beta1_dot", "beta2_dot", "W")
    return dict(zip(names, y))


# ---------------------------------------------------------------------------------------
# The IFToMM library's spatial rigid slider-crank (models/mechanisms/slider_crank_3d.yaml)

# Data of the IFToMM problem (as restated in Exudyn's TestModels/sliderCrank3Dbenchmark.py):
# crank 0.08 m, 0.12 kg, Ixx = 1e-4 kg m^2, turning about x at A = (0, 0.1, 0.12) m;
# rod 0.3 m, 0.5 kg, 4e-4 along and 4e-3 across (kg m^2); slider 2 kg on the x axis;
# spherical joint at B, universal joint at C; gravity 9.81 m/s^2 along -z; crank angle 0
# (straight up) turning at 6 rad/s; 5 s.
SLIDER_CRANK_3D = dict(l1=0.08, l2=0.3, ya=0.1, za=0.12, m1=0.12, m2=0.5, m3=2.0, I1=1.0e-4,
                       I_along=4.0e-4, I_across=4.0e-3, omega0=6.0, g=9.81)

# The library's published solution by M. González (University of A Coruña), the slider's
# x [m] every 0.01 s for 5 s, file "Spatial_rigid_slider-crank_mechanism_Gonzalez.txt" of
# the IFToMM benchmark (copied in jgerstmayr/EXUDYN, docs/verification/
# Slidercrank3DiftommBenchmark/, commit 657f9c6392c48831530f98e18cbccb81a9097953): here
# its values every 0.1 s, as printed there (9 digits). It agrees with the independent
# minimal-coordinate solution (slider_crank_3d_reference) to 7e-5 m over the 5 s, 1.8e-6 m
# at 0.1 s; the other published solutions copied there differ more (Masarati's by 7e-4 m
# at 1 s; Chaojie's starts from another geometry).
SLIDER_CRANK_3D_PUBLISHED = np.array([
    (0.0, 0.2), (0.1, 0.226785384), (0.2, 0.263034975), (0.3, 0.28194126), (0.4, 0.222848664),
    (0.5, 0.184952803), (0.6, 0.205149298), (0.7, 0.233436939), (0.8, 0.272248997),
    (0.9, 0.269894777), (1.0, 0.211754668), (1.1, 0.187182557), (1.2, 0.210516025),
    (1.3, 0.240573702), (1.4, 0.281610048), (1.5, 0.25696554), (1.6, 0.201710317),
    (1.7, 0.191482337), (1.8, 0.216149918), (1.9, 0.248250449), (2.0, 0.289063554),
    (2.1, 0.24408996), (2.2, 0.193077751), (2.3, 0.196281891), (2.4, 0.22210812),
    (2.5, 0.256509783), (2.6, 0.288514279), (2.7, 0.231657711), (2.8, 0.186751704),
    (2.9, 0.201300274), (3.0, 0.228450093), (3.1, 0.26535947), (3.2, 0.279033697),
    (3.3, 0.219906306), (3.4, 0.185121916), (3.5, 0.206512886), (3.6, 0.235235487),
    (3.7, 0.274692757), (3.8, 0.266571846), (3.9, 0.209037413), (4.0, 0.188208161),
    (4.1, 0.211955412), (4.2, 0.242522956), (4.3, 0.283917157), (4.4, 0.25357518),
    (4.5, 0.199295373), (4.6, 0.192711279), (4.7, 0.217680687), (4.8, 0.250365225),
    (4.9, 0.289954884), (5.0, 0.240761815),
])


def _slider_crank_3d_kinematics(theta, p):
    """(slider x, J(theta), dV/dtheta) at crank angle theta (complex-safe: J's derivative is
    taken by a complex step).

    B = A + l1 (0, -sin theta, cos theta); the slider x = sqrt(l2^2 - B_y^2 - B_z^2) (the
    branch x > 0); the rod's axis e = (C - B)/l2, the cross's rod axis u = e x e_x / |.|
    and w = e x u; per unit crank rate the rod turns at e x e' + (u' . w) e (its spin about
    e is u' . w). With both centres of mass at the middles,
        J = I1 + m1 |B'/2|^2 + m2 |(B' + C')/2|^2 + I_across e'.e' + I_along (u'.w)^2 + m3 x'^2
    is the mechanism's inertia about the crank axis (T = J theta'^2/2), and
    V = g (m1 (z_A + B_z)/2 + m2 B_z/2) (the centres' heights; C stays at z = 0)."""
    l1, l2 = p["l1"], p["l2"]
    s, co = np.sin(theta), np.cos(theta)
    By, Bz = p["ya"] - l1 * s, p["za"] + l1 * co
    dBy, dBz = -l1 * co, -l1 * s
    x = np.sqrt(l2 * l2 - By * By - Bz * Bz)
    dx = -(By * dBy + Bz * dBz) / x
    e = np.array([x, -By, -Bz]) / l2
    de = np.array([dx, -dBy, -dBz]) / l2
    n, dn = np.array([0 * x, e[2], -e[1]]), np.array([0 * x, de[2], -de[1]])   # e x e_x and its rate
    norm = np.sqrt(n @ n)
    u = n / norm
    du = dn / norm - n * (n @ dn) / norm**3
    w = np.cross(e, u)
    spin = du @ w
    J = (p["I1"] + p["m1"] * (dBy * dBy + dBz * dBz) / 4 + p["m2"] * (dx * dx + dBy * dBy + dBz * dBz) / 4
         + p["I_across"] * (de @ de) + p["I_along"] * spin * spin + p["m3"] * dx * dx)
    dV = p["g"] * (p["m1"] + p["m2"]) * dBz / 2
    return x, J, dV


def slider_crank_3d_reference(times, rtol=1e-13, atol=1e-13, **data):
    """The spatial slider-crank's slider x and crank angle theta at ``times``.

    One degree of freedom: Lagrange's equation of the crank angle,
    J(theta) theta'' + 1/2 J'(theta) theta'^2 + V'(theta) = 0, with J and V' from
    _slider_crank_3d_kinematics (J' by a complex step, exact to rounding), from theta = 0,
    theta' = omega0, integrated by scipy's DOP853 at rtol = atol = 1e-13. Returns
    (x, theta) arrays."""
    p = dict(SLIDER_CRANK_3D, **data)
    h = 1e-30

    def rhs(t, y):
        _, J, dV = _slider_crank_3d_kinematics(y[0], p)
        dJ = _slider_crank_3d_kinematics(y[0] + 1j * h, p)[1].imag / h
        return (y[1], -(0.5 * dJ * y[1] ** 2 + dV) / J)

    times = np.asarray(times, dtype=float)
    sol = solve_ivp(rhs, (0.0, float(times.max())), (0.0, p["omega0"]), method="DOP853", rtol=rtol,
                    atol=atol, dense_output=True)
    theta = sol.sol(times)[0]
    return np.array([_slider_crank_3d_kinematics(th, p)[0] for th in theta]), theta


# --- the Whipple bicycle (Meijaard, Papadopoulos, Ruina & Schwab, Proc. R. Soc. A 463 (2007)
# 1955-1982, doi 10.1098/rspa.2007.1857) ----------------------------------------------------
# The benchmark's linearized equations M q'' + v C1 q' + (g K0 + v^2 K2) q = 0 for q = (lean,
# steer), with the matrices the paper prints for its benchmark parameters (its eq. 5.4), and
# its Table 2: the eigenvalues at 4, 5 and 10 m/s and the weave and capsize speeds.
WHIPPLE_M = np.array([[80.81722, 2.31941332208709], [2.31941332208709, 0.29784188199686]])
WHIPPLE_C1 = np.array([[0.0, 33.86641391492494], [-0.85035641456978, 1.68540397397560]])
WHIPPLE_K0 = np.array([[-80.95, -2.59951685249872], [-2.59951685249872, -0.80329488458618]])
WHIPPLE_K2 = np.array([[0.0, 76.59734589573222], [0.0, 2.65431523794604]])
WHIPPLE_TABLE_2 = {4.0: [-12.15861426576450, -1.42944427361326, 0.41325331521125 - 3.07910818603206j,
                         0.41325331521125 + 3.07910818603206j],
                   5.0: [-14.07838969279822, -0.32286642900409, -0.77534188219585 - 4.46486771378823j,
                         -0.77534188219585 + 4.46486771378823j],
                   10.0: [-24.62459635017404, 0.16105338653172, -3.72016840437287 - 10.90681139476287j,
                          -3.72016840437287 + 10.90681139476287j]}
WHIPPLE_WEAVE_SPEED, WHIPPLE_CAPSIZE_SPEED = 4.29238253634111, 6.02426201538837


def whipple_linear_lean(times, v, lean_rate, g=9.81, rtol=1e-13, atol=1e-15):
    """The lean angle of the benchmark's linearized equations at speed v after a lean rate
    ``lean_rate`` at t = 0 (lean, steer and steer rate 0), at ``times`` (scipy DOP853)."""
    K = g * WHIPPLE_K0 + v * v * WHIPPLE_K2

    def rhs(t, y):
        return np.concatenate([y[2:], np.linalg.solve(WHIPPLE_M, -v * WHIPPLE_C1 @ y[2:] - K @ y[:2])])

    times = np.asarray(times, dtype=float)
    sol = solve_ivp(rhs, (0.0, float(times.max())), (0.0, 0.0, lean_rate, 0.0), method="DOP853", rtol=rtol,
                    atol=atol, dense_output=True)
    return sol.sol(times)[0]
