"""A straight 3D beam as an FE model: ``elements`` two-node elements of 6 DOFs per node
(ux uy uz θx θy θz, world axes), Euler–Bernoulli or Timoshenko bending in both planes,
axial and Saint-Venant torsion, consistent or lumped mass.

Section axes: x along the beam, z the ``up`` direction made normal to x, y = z × x. ``Iy``
and ``Iz`` are the second moments about y and z (``Iz`` governs bending in the x–y plane,
uy and θz); ``J`` the torsion constant; the torsional inertia uses the polar moment
Iy + Iz. Each bending plane uses the interdependent interpolation of Friedman & Kosmatka
(1993): exact for the static beam under end loads (Timoshenko's with Φ = 12EI/(κGAL²),
Euler–Bernoulli's cubic Hermite for Φ = 0), its element matrices integrated exactly by
Gauss quadrature. Euler–Bernoulli mass has no rotary inertia of bending (the classical
theory's), Timoshenko's has ρI. ``mass="lumped"``: ρAL/2 on each translation of each
element end and nothing on rotations, so M is singular. ``geometric_stiffness`` gives the
same beam's K_G under axial forces (buckling, stiffening by tension).
"""

import numpy as np
import scipy.sparse

from ...core.errors import ModelError
from .matrices import fe_model
from ...core.tolerances import BEAM_UP_PARALLEL_RTOL

GAUSS = np.polynomial.legendre.leggauss(5)  # exact to degree 9; the products here are of degree ≤ 6
THEORIES = ("euler_bernoulli", "timoshenko")
MASSES = ("consistent", "lumped")
BEAM_ELEMENTS_MAX = 100_000  # 600,000 DOFs: beyond, the assembly alone takes gigabytes, and a beam's few modes need no finer mesh


def beam(length, elements, *, area, Iy, Iz, J, E, density, G=None, nu=None, shear_factor=None,
         theory="euler_bernoulli", mass="consistent", start=(0.0, 0.0, 0.0), axis=(1.0, 0.0, 0.0),
         up=(0.0, 0.0, 1.0)):
    """An FEModel (matrices.py) of a uniform straight beam from ``start`` along ``axis``:
    nodes 0..``elements`` equally spaced, node 0 at ``start``. Material: ``E``, ``density``
    and ``G`` or ``nu`` (G = E / 2(1 + ν)); ``shear_factor`` κ (Timoshenko only)."""
    where = "beam"
    if theory not in THEORIES:
        raise ModelError(f"{where}: theory must be one of {', '.join(THEORIES)}, not {theory!r}")
    if mass not in MASSES:
        raise ModelError(f"{where}: mass must be one of {', '.join(MASSES)}, not {mass!r}")
    if isinstance(elements, (bool, np.bool_)) or not (isinstance(elements, (int, np.integer))
                                                       and 1 <= elements <= BEAM_ELEMENTS_MAX):
        raise ModelError(f"{where}: elements must be an integer from 1 to {BEAM_ELEMENTS_MAX}, not {elements!r}")
    if (G is None) == (nu is None):
        raise ModelError(f"{where}: give exactly one of G (shear modulus) and nu (Poisson's ratio)")
    if theory == "timoshenko" and shear_factor is None:
        raise ModelError(f"{where}: a Timoshenko beam needs shear_factor (κ: 5/6 rectangle, 0.9 circle, about)")
    if theory == "euler_bernoulli" and shear_factor is not None:
        raise ModelError(f"{where}: shear_factor is for theory: timoshenko; an Euler–Bernoulli beam has no shear strain")
    for name, value in dict(length=length, area=area, Iy=Iy, Iz=Iz, J=J, E=E, G=G, nu=nu, density=density,
                            shear_factor=shear_factor).items():
        problem = value is not None and number_problem(name, value)
        if problem:
            raise ModelError(f"{where}: {problem}")
    G = E / (2 * (1 + nu)) if G is None else G
    frame = _section_axes(axis, up, where)
    h = length / elements
    local_K, local_M = _element(h, area, Iy, Iz, J, E, G, density, shear_factor, theory, mass)
    K, M = _assemble(local_K, frame, np.ones(elements)), _assemble(local_M, frame, np.ones(elements))
    nodes = np.asarray(start, float) + np.outer(np.linspace(0.0, length, elements + 1), frame[0])
    label = f"beam ({theory}, {mass} mass, {elements} elements)"
    return fe_model(M, K, nodes, dofs_per_node=6, where=dict(mass=label, stiffness=label, nodes=label))


def number_problem(name, value):
    """Why ``value`` cannot be the number ``name`` of ``beam`` (nu: Poisson's ratio of an
    isotropic material, −1 < ν ≤ 0.5; the others: positive and finite), or None."""
    if name == "nu":
        return None if -1 < value <= 0.5 else (f"nu (Poisson's ratio) must be above -1 and at most 0.5 (an isotropic "
                                               f"material's), not {value!r}")
    return None if np.isfinite(value) and value > 0 else f"{name} must be a positive number, not {value!r}"


def geometric_stiffness(length, elements, force, *, axis=(1.0, 0.0, 0.0)):
    """K_G of the beam of ``beam(length, elements, axis=axis, ...)`` under the axial force
    ``force`` (tension > 0; a number, or one per element): ∫ N (v'² + w'²) dx with the cubic
    deflection line's slopes, the classical consistent geometric stiffness (used for
    Timoshenko beams too). K + K_G is the stiffness about a state under that force: its
    buckling (K + λK_G singular) and its stiffening (spinning beams' centrifugal tension)."""
    where = "beam geometric stiffness"
    forces = np.broadcast_to(np.asarray(force, float), (elements,)) if np.ndim(force) == 0 else np.asarray(force, float)
    if forces.shape != (elements,) or not np.isfinite(forces).all():
        raise ModelError(f"{where}: force must be a finite number or {elements} of them (one per element), "
                         f"got shape {forces.shape}")
    frame = _section_axes(axis, np.eye(3)[np.argmin(np.abs(axis))], where)  # any section axes: K_G is round
    unit = np.zeros((12, 12))
    slope = _bending(length / elements, 0.0, 0.0, 0.0, 1.0)[1]  # ∫ w'ᵀ w' dx: the rotary term with ρI = 1, Φ = 0
    for dofs, sign in (([1, 5, 7, 11], 1.0), ([2, 4, 8, 10], -1.0)):
        S = np.diag([1.0, sign, 1.0, sign])
        unit[np.ix_(dofs, dofs)] = S @ slope @ S
    return _assemble(unit, frame, forces)


def _assemble(local, frame, scales):
    """The sparse sum over elements e of scales[e] × ``local`` (12 × 12, section axes) turned
    to world axes, element e joining nodes e and e + 1."""
    T = np.kron(np.eye(4), frame)  # local components = T @ global components
    block = T.T @ local @ T
    elements = len(scales)
    dofs = 6 * np.arange(elements)[:, None] + np.arange(12)
    rows, cols = np.repeat(dofs, 12, axis=1).ravel(), np.tile(dofs, 12).ravel()
    n = 6 * (elements + 1)
    A = scipy.sparse.coo_array((np.multiply.outer(scales, block).ravel(), (rows, cols)), shape=(n, n)).tocsr()
    return (A + A.T) / 2  # rounding of the rotation products


def stress_stiffness(length, elements, *, area, E, axis=(1.0, 0.0, 0.0), **_section):
    """The map u ↦ K_G(N(u)) of the beam of ``beam(length, elements, area=area, E=E,
    axis=axis, ...)`` (the other section keys are accepted and unused): N_e = EA (u_e+1 −
    u_e)·x / h, each element's axial force of the nodal displacements u, and K_G
    ``geometric_stiffness`` under those forces."""
    x = _section_axes(axis, np.eye(3)[np.argmin(np.abs(axis))], "beam stress stiffness")[0]
    h = length / elements
    translation = 6 * np.arange(elements + 1)[:, None] + np.arange(3)

    def stiffness(u):
        along = np.asarray(u, float)[translation] @ x
        return geometric_stiffness(length, elements, area * E * np.diff(along) / h, axis=axis)
    return stiffness


def _section_axes(axis, up, where):
    """Rows x, y, z of the section frame in world components."""
    x = np.asarray(axis, float)
    if x.shape != (3,) or not np.linalg.norm(x) > 0:
        raise ModelError(f"{where}: axis must be a nonzero 3-vector, not {axis!r}")
    x = x / np.linalg.norm(x)
    z = np.asarray(up, float)
    z = z - (z @ x) * x if z.shape == (3,) else z
    if z.shape != (3,) or not np.linalg.norm(z) > BEAM_UP_PARALLEL_RTOL * max(np.linalg.norm(up), 1.0):
        raise ModelError(f"{where}: up must be a 3-vector not parallel to the axis, not {up!r}")
    z = z / np.linalg.norm(z)
    return np.array([x, np.cross(z, x), z])


def _element(h, A, Iy, Iz, J, E, G, rho, kappa, theory, mass):
    """12 × 12 element stiffness and mass in section axes, DOFs (u v w θx θy θz) per end."""
    K, M = np.zeros((12, 12)), np.zeros((12, 12))
    pair = np.array([[1.0, -1.0], [-1.0, 1.0]])
    two_node = np.array([[2.0, 1.0], [1.0, 2.0]]) / 6
    for dofs, stiffness, inertia in (([0, 6], E * A, rho * A), ([3, 9], G * J, rho * (Iy + Iz))):
        K[np.ix_(dofs, dofs)] += stiffness / h * pair
        if mass == "consistent":
            M[np.ix_(dofs, dofs)] += inertia * h * two_node
    # bending: x–y plane (v, θz = dv/dx) about z; x–z plane (w, −θy = dw/dx) about y
    for dofs, sign, I in (([1, 5, 7, 11], 1.0, Iz), ([2, 4, 8, 10], -1.0, Iy)):
        phi = 12 * E * I / (kappa * G * A * h * h) if theory == "timoshenko" else 0.0
        Kb, Mb = _bending(h, E * I, phi, rho * A, rho * I if theory == "timoshenko" else 0.0)
        S = np.diag([1.0, sign, 1.0, sign])
        K[np.ix_(dofs, dofs)] += S @ Kb @ S
        if mass == "consistent":
            M[np.ix_(dofs, dofs)] += S @ Mb @ S
    if mass == "lumped":
        M[[0, 1, 2, 6, 7, 8], [0, 1, 2, 6, 7, 8]] = rho * A * h / 2
    return K, M


def _bending(h, EI, phi, rhoA, rhoI):
    """Stiffness and mass of one bending plane, DOFs (w1, ψ1, w2, ψ2) with ψ the section's
    rotation (dw/dx for Φ = 0): ∫ EI ψ'² + κGA (w' − ψ)² and ∫ ρA w² + ρI ψ²,
    with Friedman & Kosmatka's shape functions in ξ = x/h."""
    K, M = np.zeros((4, 4)), np.zeros((4, 4))
    mu = 1 / (1 + phi)
    points, weights = GAUSS
    for xi, weight in zip((points + 1) / 2, weights / 2):
        w = mu * np.array([1 + phi - phi * xi - 3 * xi**2 + 2 * xi**3,
                           h * ((1 + phi / 2) * xi - (2 + phi / 2) * xi**2 + xi**3),
                           phi * xi + 3 * xi**2 - 2 * xi**3,
                           h * (-phi / 2 * xi - (1 - phi / 2) * xi**2 + xi**3)])
        psi = mu * np.array([6 * (xi**2 - xi) / h, 1 + phi - (4 + phi) * xi + 3 * xi**2,
                             -6 * (xi**2 - xi) / h, -(2 - phi) * xi + 3 * xi**2])
        dpsi = mu * np.array([6 * (2 * xi - 1) / h**2, (-(4 + phi) + 6 * xi) / h,
                              -6 * (2 * xi - 1) / h**2, (-(2 - phi) + 6 * xi) / h])
        shear = mu * np.array([-1 / h, -1 / 2, 1 / h, -1 / 2])  # (w' − ψ)/Φ, constant; κGA = 12EI/(Φh²)
        K += weight * h * (EI * np.outer(dpsi, dpsi) + 12 * EI * phi / h**2 * np.outer(shear, shear))
        M += weight * h * (rhoA * np.outer(w, w) + rhoI * np.outer(psi, psi))
    return K, M
