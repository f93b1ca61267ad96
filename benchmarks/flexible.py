"""1 s of a pinned flexible pendulum in mbsynth and in Exudyn's ObjectFFRFreducedOrder (issue 46).

    .venv/bin/python benchmarks/flexible.py [--quick]

The problem: the pendulum of tests/model/flexible/test_flexible_pendulum.py (its beam, 1 m,
6 Euler–Bernoulli elements, consistent mass, a 20 mm square section of E = 1.518 GPa and
1000 kg/m³, on a revolute joint about z at node 0, released horizontal under gravity −9.81 y),
reduced by Craig–Bampton at node 0 with MODES fixed-interface modes (half of them in the
plane of the swing), that node held at the floating frame (``Reduction.hold``); the tip
(node 6) at t = 1 s.

mbsynth: ``type: flexible_body`` (the test's ``pendulum_yaml``: the beam generator,
``reduction: craig_bampton``),
``simulate`` with DOP853 and with Radau (the implicit method for stiff models) at rtol = atol
as stated (DOP853 from 1e-2: at 1e-2 and 1e-3 the step is held by the stability of the
866 rad/s mode, not by the error control, and down to 1e-5 the error stays near 4e-7 m), one output
interval, the compiled kernels built before anything is timed. The spin-up beam (models/flexible/spin_up_beam.yaml, 15 s, 500 output rows) is timed beside it
with both methods, warm (its second run in the process), its tip against DOP853 at the
default tolerance.

Exudyn (PyPI ``exudyn``, an optional benchmark dependency): the same FE matrices handed to
its ``FEMinterface``. Its FE nodes carry 3 DOFs (translations), a beam node 6, so each beam
node enters as two 'Position' nodes at the node's place, the first holding ux uy uz, the
second θx θy θz: the DOF order and the matrices are unchanged.
``ComputeHurtyCraigBamptonModes`` with the boundary [[0, 1]] (beam node 0's six DOFs) and
``allBoundaryNodes`` gives six static modes and the fixed-interface modes; the static ones
are dropped (node 0 held at the frame, as ``Reduction.hold``). Its basis spans ours (the
principal cosines are printed) with the same frequencies. The body is Exudyn's C++
``ObjectFFRFreducedOrder`` on a NodeRigidBodyEP (Euler parameters) and a NodeGenericODE2, a
``RevoluteJointZ`` between ground and the frame's node, gravity as ``LoadMassProportional``;
``SolveDynamic`` with its default generalized-α (spectral radius 0.9), a fixed number of
steps, no solution file. The object takes its mass terms as inertia invariants (mass,
inertia, centerOfMass, mPhitTPsi, ...), which Exudyn's ``ObjectFFRFreducedOrderInterface``
computes for nodes of 3 translations; on the paired nodes it would move a rotation DOF as
a point (ω × x instead of ω), so the rows use ours instead: mbsynth's Gram matrix
(model/flexible/invariants.py) mapped onto Exudyn's names, which gives the same mass
matrix M(η) for any FE mass matrix. Exudyn's own invariants are run once as a check.

Exudyn's equations are not ours in two places, both shown with numbers in the results:
its gravity turns the frame by the undeformed first moment m χ only (not s(η) = m χ +
mPhitTPsi η), and its quadratic velocity vector is written with identities of nodes of
3 translations with an isotropic mass (mPsiTildePsi antisymmetric in its mode pairs,
mPhitTPsiTilde = [mPhitTPsi]×), which a beam's mass matrix does not satisfy (they are
off the in-plane rows here). The run "Exudyn + s(η) torque" adds the missing gravity torque
(A mPhitTPsi η) × g to the frame's node by a Python load function: it ends where mbsynth
does, which isolates the gap; its Python callback makes each of its steps about 4× dearer.
Exudyn's integration error does not fall steadily with h until h ≲ 1/32000 s: the
fixed-interface modes up to 866 rad/s ring with tip amplitudes near 1e-6 m, and their phase
error after 1 s, ω t (ωh)²/12, is still 0.2 rad at h = 1/16000 s.

Agreement: the tip's distance at 1 s from mbsynth at rtol = atol = 1e-12 (the reference),
and from the same code's own finest run (its integration error); the unreduced FE model of
the test (Lagrange's equations of all 42 DOFs in solve_ivp) is printed beside it. Wall
time: best of REPEATS (1 for a run over LONG s) of ``simulate`` / ``SolveDynamic`` alone
(building, compiling and ``Assemble`` not timed). Writes benchmarks/flexible_results.md
(``--quick``: fewer settings, printed only).
"""

import argparse
import datetime
import os
import platform
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import scipy.sparse

import mbsynth as mb
from mbsynth.compiled import engine_for
from mbsynth.model.flexible.beam import beam
from mbsynth.model.flexible.invariants import invariants
from mbsynth.model.flexible.reduction import craig_bampton

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests" / "model" / "flexible"))
from test_flexible_pendulum import ELEMENTS, G, SECTION, T_END, pendulum_yaml, unreduced_tip  # noqa: E402

try:
    import exudyn as exu
    import exudyn.itemInterface as eii
    from exudyn.FEM import FEMinterface, HCBstaticModeSelection, ObjectFFRFreducedOrderInterface
    sys.path.insert(0, str(HERE))
    from loops import exudyn_settings
except ImportError as missing:
    exu, WHY_NO_EXUDYN = None, f"exudyn is not importable ({missing}); `pip install exudyn` for its rows"

MODES = 8
RTOLS = (1e-2, 1e-3, 1e-4, 1e-5, 1e-7, 1e-9)  # loose ones too: there the highest mode's stability holds the step
RADAU_RTOLS = (1e-4, 3e-5, 1e-5)
SPIN_UP = HERE.parent / "models" / "flexible" / "spin_up_beam.yaml"
SPIN_UP_RUNS = (("DOP853", 1e-10), ("DOP853", 1e-6), ("Radau", 1e-6), ("Radau", 1e-4))
STEPS = (250, 500, 1000, 2000, 4000, 8000, 16000, 32000)
FINEST = 64000  # Exudyn's own finest run: its converged answer
REFERENCE_RTOL = 1e-12
SHORT = 0.1  # s: the first check, both codes
REPEATS, LONG = 3, 2.0
TARGET = 1e-6  # m: integration error for the "matched accuracy" line


# ----------------------------------------------------------------------------- mbsynth

def mbsynth_pendulum(modes=MODES):
    system = mb.loads(pendulum_yaml(modes), name="flexible_pendulum")
    engine_for(system)  # compile (or load) the kernels before anything is timed
    return system


def run_mbsynth(system, rtol, t_end=T_END, method="DOP853"):
    """Tip (x, y) at t_end, wall time of ``simulate``, counters."""
    started = time.perf_counter()
    run = mb.simulate(system, t_end, dt=t_end, method=method, rtol=rtol, atol=rtol)
    wall = time.perf_counter() - started
    assert run.status == "completed", run.status
    tip = np.array([run.column("tip[x]")[-1], run.column("tip[y]")[-1]])
    return tip, wall, dict(steps=run.stats["steps"], evaluations=run.stats["evaluations"],
                           jacobians=run.stats["jacobians"])


# ----------------------------------------------------------------------------- Exudyn

def exudyn_reduction(fe, modes=MODES):
    """Exudyn's Craig–Bampton basis of ``fe`` (beam node j = Exudyn nodes 2j, 2j + 1), its
    static modes at node 0 dropped; (FEMinterface, basis, ω of its modes)."""
    fem = FEMinterface()
    fem.nodes = {"Position": np.repeat(fe.nodes, 2, axis=0)}
    fem.massMatrix = scipy.sparse.csr_matrix(fe.mass)
    fem.stiffnessMatrix = scipy.sparse.csr_matrix(fe.stiffness)
    fem.ComputeHurtyCraigBamptonModes([[0, 1]], modes, useSparseSolver=True,
                                      computationMode=HCBstaticModeSelection.allBoundaryNodes)
    basis = fem.modeBasis["matrix"][:, 6:]
    fem.modeBasis["matrix"] = basis
    return fem, basis, np.sqrt(np.abs(fem.eigenValues))


def our_invariants(reduction):
    """mbsynth's inertia invariants (the Gram matrix W of invariants.py) under Exudyn's
    ObjectFFRFreducedOrder names: Γ_t, Γ_r, Ξ_k and Φ of ours are Exudyn's Φ_t, −x̃, −Ψ̃_k, Ψ."""
    inv = invariants(reduction)
    W, r = inv.gram, inv.modes
    t, rot, xi, phi = slice(0, 3), slice(3, 6), slice(6, 6 + 3 * r), slice(6 + 3 * r, 6 + 4 * r)
    m = W[0, 0]
    return dict(mass=m, inertia=W[rot, rot], centerOfMass=inv.first_moment / m, mPhitTPsi=W[t, phi],
                mPhitTPsiTilde=-W[t, xi], mXRefTildePsi=-W[rot, phi], mXRefTildePsiTilde=W[rot, xi],
                mPsiTildePsi=-W[xi, phi], mPsiTildePsiTilde=W[xi, xi], massMatrixReduced=W[phi, phi])


def exudyn_invariants(fem):
    """Exudyn's own invariants of the paired-node FE model."""
    cms = ObjectFFRFreducedOrderInterface(fem)
    return dict(mass=cms.totalMass, inertia=cms.inertiaLocal, centerOfMass=cms.chiU, mPhitTPsi=cms.mPhitTPsi,
                mPhitTPsiTilde=cms.mPhitTPsiTilde, mXRefTildePsi=cms.mXRefTildePsi,
                mXRefTildePsiTilde=cms.mXRefTildePsiTilde, mPsiTildePsi=cms.mPsiTildePsi,
                mPsiTildePsiTilde=cms.mPsiTildePsiTilde, massMatrixReduced=cms.massMatrixReduced)


class ExudynPendulum:
    """The pendulum as an Exudyn ObjectFFRFreducedOrder with the invariants ``terms``;
    ``torque``: add the gravity torque of the deformation's first moment, (A mPhitTPsi η) × g."""

    def __init__(self, fe, basis, terms, torque=False):
        self.fe, self.basis, self.terms, self.torque = fe, basis, terms, torque
        self.stiffness = basis.T @ (fe.stiffness @ basis)

    def build(self):
        r = self.basis.shape[1]
        mbs = exu.SystemContainer().AddSystem()
        frame = mbs.AddNode(eii.NodeRigidBodyEP(referenceCoordinates=[0, 0, 0, 1, 0, 0, 0], initialVelocities=[0] * 7))
        modal = mbs.AddNode(eii.NodeGenericODE2(numberOfODE2Coordinates=r, referenceCoordinates=[0] * r,
                                                initialCoordinates=[0] * r, initialCoordinates_t=[0] * r))
        mass, stiffness = exu.MatrixContainer(), exu.MatrixContainer()
        mass.SetWithDenseMatrix(self.terms["massMatrixReduced"], useDenseMatrix=False)
        stiffness.SetWithDenseMatrix((self.stiffness + self.stiffness.T) / 2, useDenseMatrix=False)
        invariant = {k: v for k, v in self.terms.items() if k != "massMatrixReduced"}
        body = mbs.AddObject(eii.ObjectFFRFreducedOrder(
            nodeNumbers=[frame, modal], massMatrixReduced=mass, stiffnessMatrixReduced=stiffness, modeBasis=self.basis,
            referencePositions=np.repeat(self.fe.nodes, 2, axis=0).ravel(), computeFFRFterms=True, **invariant))
        mbs.AddLoad(eii.LoadMassProportional(markerNumber=mbs.AddMarker(eii.MarkerBodyMass(bodyNumber=body)),
                                             loadVector=[0, -G, 0]))
        ground = mbs.AddObject(eii.ObjectGround())
        pin = mbs.AddMarker(eii.MarkerNodeRigid(nodeNumber=frame))
        mbs.AddObject(eii.ObjectJointRevoluteZ(markerNumbers=[
            mbs.AddMarker(eii.MarkerBodyRigid(bodyNumber=ground, localPosition=[0, 0, 0])), pin]))
        if self.torque:
            moment = self.terms["mPhitTPsi"]

            def first_moment_torque(mbs, t, load):
                A = np.asarray(mbs.GetNodeOutput(frame, exu.OutputVariableType.RotationMatrix)).reshape(3, 3)
                eta = np.asarray(mbs.GetNodeOutput(modal, exu.OutputVariableType.Coordinates))
                return list(np.cross(A @ (moment @ eta), [0.0, -G, 0.0]))

            mbs.AddLoad(eii.LoadTorqueVector(markerNumber=pin, loadVectorUserFunction=first_moment_torque))
        mbs.Assemble()
        return mbs, body

    def __call__(self, steps, t_end=T_END):
        """Tip (x, y) at t_end, wall time of ``SolveDynamic``, counters."""
        mbs, body = self.build()
        settings = exudyn_settings(t_end, steps)  # sparse, no solution file, no sensors
        started = time.perf_counter()
        mbs.SolveDynamic(settings)
        wall = time.perf_counter() - started
        it = mbs.sys["dynamicSolver"].it
        assert abs(it.currentTime - t_end) < 1e-9, it.currentTime
        tip = mbs.GetObjectOutputSuperElement(body, exu.OutputVariableType.Position, 2 * ELEMENTS)
        return np.array(tip[:2]), wall, dict(steps=it.currentStepIndex, newton=it.newtonStepsCount,
                                             jacobians=it.newtonJacobiCount)


def identity_defects(terms, r):
    """How far a beam's invariants are from the identities Exudyn's quadratic velocity
    vector is written with: (mPsiTildePsi_kl + mPsiTildePsi_lk, mPhitTPsiTilde_k − [mPhitTPsi_k]×),
    each relative to its matrix's largest entry."""
    P = terms["mPsiTildePsi"].reshape(r, 3, r)
    T = terms["mPhitTPsiTilde"].reshape(3, r, 3).transpose(1, 0, 2)
    skew = np.array([_skew(c) for c in terms["mPhitTPsi"].T])
    return np.abs(P + P.transpose(2, 1, 0)).max() / np.abs(P).max(), np.abs(T - skew).max() / np.abs(T).max()


def _skew(v):
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


# ----------------------------------------------------------------------------- runs

def best(run, setting, repeats=REPEATS):
    """The run's tip and counters with the best wall time of ``repeats`` (1 if over LONG s)."""
    tip, wall, counters = run(setting)
    runs = 1
    while runs < repeats and wall < LONG:
        wall = min(wall, run(setting)[1])
        runs += 1
    return dict(tip=tip, wall=wall, runs=runs, **counters)


def benchmark(quick):
    fe = beam(1.0, ELEMENTS, **SECTION)
    ours = craig_bampton(fe, [0], count=MODES).hold(0)
    system = mbsynth_pendulum()
    result = dict(rows=[], checks=[], finest=FINEST // 4 if quick else FINEST)
    print("mbsynth reference ...", flush=True)
    reference = best(lambda rtol: run_mbsynth(system, rtol), REFERENCE_RTOL, 1)
    ref = reference["tip"]
    result["reference"] = ref
    rows = result["rows"]
    for rtol in RTOLS[1:2] if quick else RTOLS:
        entry = best(lambda rtol: run_mbsynth(system, rtol), rtol)
        entry.update(code="mbsynth", settings=f"DOP853, rtol = atol = {rtol:.0e}", own=np.linalg.norm(entry["tip"] - ref))
        rows.append(entry)
        print(f"  mbsynth rtol {rtol:.0e}: {entry['wall']:.3f} s, tip {entry['tip']}", flush=True)
    for rtol in RADAU_RTOLS[:1] if quick else RADAU_RTOLS:
        entry = best(lambda rtol: run_mbsynth(system, rtol, method="Radau"), rtol)
        entry.update(code="mbsynth", settings=f"Radau, rtol = atol = {rtol:.0e}", own=np.linalg.norm(entry["tip"] - ref))
        rows.append(entry)
        print(f"  mbsynth Radau rtol {rtol:.0e}: {entry['wall']:.3f} s, tip {entry['tip']}", flush=True)
    reference.update(code="mbsynth", settings=f"DOP853, rtol = atol = {REFERENCE_RTOL:.0e} (reference)", own=0.0)
    rows.append(reference)
    if not quick:
        started = time.perf_counter()
        full = unreduced_tip(fe)
        result["checks"].append(f"The unreduced FE model (42 DOFs, solve_ivp DOP853 at rtol 1e-10, "
                                f"{time.perf_counter() - started:.1f} s) ends {np.linalg.norm(full - ref):.1e} m from the "
                                f"reference: the reduction's error with {MODES} modes.")
    result["spin_up"] = spin_up(quick)
    if exu is None:
        result["checks"].append(WHY_NO_EXUDYN)
        print(WHY_NO_EXUDYN)
        return result
    fem, basis, omega = exudyn_reduction(fe)
    q1, q2 = np.linalg.qr(ours.basis)[0], np.linalg.qr(basis)[0]
    cosines = np.linalg.svd(q1.T @ q2, compute_uv=False)
    mapped = our_invariants(replace(ours, basis=basis))
    result["checks"].append(
        f"Exudyn's Craig–Bampton basis (FEMinterface.ComputeHurtyCraigBamptonModes) spans mbsynth's: principal "
        f"cosines ≥ 1 − {1 - cosines.min():.0e}; its fixed-interface ω {', '.join(f'{w:.4f}' for w in omega[::2])} rad/s "
        f"(pairs), mbsynth's differ by at most {np.abs(omega - ours.frequencies).max() / omega.max():.0e} relative.")
    theirs = exudyn_invariants(fem)
    worst = max(((np.abs(mapped[k] - theirs[k]).max() / np.abs(mapped[k]).max(), k) for k in mapped))
    result["checks"].append(
        f"Exudyn's own invariants of the paired nodes (ObjectFFRFreducedOrderInterface) against mbsynth's: mass "
        f"{theirs['mass']:.6f} kg for {mapped['mass']:.6f} (the torsional inertia counted as mass), the largest "
        f"relative difference {worst[0]:.0e} ({worst[1]}).")
    P, T = identity_defects(mapped, basis.shape[1])
    result["checks"].append(
        f"The identities Exudyn's quadratic velocity terms use, on this beam's invariants: mPsiTildePsi's mode pairs "
        f"antisymmetric to {P:.0e} (relative), mPhitTPsiTilde = [mPhitTPsi]× to {T:.0e} (both exact for nodes of 3 "
        f"translations with a mass matrix M̄ ⊗ I₃); here they change only the rows out of the swing's plane.")
    plain, fixed, own = (ExudynPendulum(fe, basis, mapped), ExudynPendulum(fe, basis, mapped, torque=True),
                         ExudynPendulum(fe, basis, theirs))
    # the short run first: both codes at tight settings over SHORT s
    short_ref = run_mbsynth(system, REFERENCE_RTOL, SHORT)[0]
    short = {name: np.linalg.norm(code(4000, SHORT)[0] - short_ref) for name, code in
             (("Exudyn", plain), ("Exudyn + s(η) torque", fixed))}
    result["checks"].append(f"Short run ({SHORT} s, Exudyn 4000 steps, mbsynth rtol 1e-12): the tips differ by "
                            + ", ".join(f"{d:.1e} m ({name})" for name, d in short.items()) + ".")
    for name, code, steps in (("Exudyn", plain, STEPS[:6]), ("Exudyn + s(η) torque", fixed, STEPS[1:]),
                              ("Exudyn, its own invariants", own, STEPS[3:4])):
        if quick:
            steps = steps[len(steps) // 2:][:1]
        print(f"{name} ...", flush=True)
        finest = code(result["finest"])[0]
        for n in steps:
            entry = best(code, n)
            entry.update(code=name, settings=f"generalized-α, h = 1/{n} s", own=np.linalg.norm(entry["tip"] - finest))
            rows.append(entry)
            print(f"  {n} steps: {entry['wall']:.3f} s, tip {entry['tip']}", flush=True)
        result["checks"].append(f"{name}, {result['finest']} steps (its converged answer): {np.linalg.norm(finest - ref):.2e} m "
                                f"from mbsynth's reference.")
    return result


def spin_up(quick):
    """The spin-up beam's runs (SPIN_UP_RUNS): per (method, rtol) its warm wall time, counters
    and tip at 15 s."""
    system = mb.load(SPIN_UP)
    engine_for(system)
    t_end = system.parameter_values[list(system.parameters).index("Ts")]
    rows = []
    for method, rtol in SPIN_UP_RUNS[::3] if quick else SPIN_UP_RUNS:
        for _ in range(2):  # the second run warm
            started = time.perf_counter()
            run = mb.simulate(system, t_end, method=method, rtol=rtol, atol=rtol)
            wall = time.perf_counter() - started
        rows.append(dict(method=method, rtol=rtol, wall=wall, steps=run.stats["steps"],
                         evaluations=run.stats["evaluations"], jacobians=run.stats["jacobians"],
                         tip=np.array([run.column("tip[x]")[-1], run.column("tip[y]")[-1]])))
        print(f"  spin-up {method} rtol {rtol:.0e}: {wall:.3f} s", flush=True)
    return rows


# ----------------------------------------------------------------------------- the report

def seconds(value):
    return f"{value:.4f}" if value < 1 else f"{value:.2f}"


def counters(entry):
    if entry["code"] == "mbsynth":
        jacobians = f", {entry['jacobians']} Jacobians" if entry["jacobians"] else ""
        return f"{entry['steps']} steps, {entry['evaluations']} motion(){jacobians}"
    return f"{entry['steps']} steps, {entry['newton']} Newton it., {entry['jacobians']} Jacobians"


def matched(rows):
    """The cheapest run of each code whose integration error is at most TARGET."""
    lines, walls = [], {}
    for code in ("mbsynth", "Exudyn", "Exudyn + s(η) torque"):
        meets = [r for r in rows if r["code"] == code and r["own"] <= TARGET]
        if meets:
            r = min(meets, key=lambda r: r["wall"])
            walls[code] = r["wall"]
            lines.append(f"{code} {seconds(r['wall'])} s ({r['settings']})")
    if "mbsynth" in walls and "Exudyn" in walls:
        lines.append(f"mbsynth / Exudyn {walls['mbsynth'] / walls['Exudyn']:.2f}×")
    return lines


def spin_up_table(rows):
    """The spin-up beam's lines: per run its warm wall time and its tip's distance from the first run's."""
    lines = ["", "The spin-up beam (models/flexible/spin_up_beam.yaml, 15 s, 500 output rows), each run's second in "
                 "the process (warm); *vs first*: its tip's distance at 15 s from the first row's.", "",
             "| method | rtol = atol | steps / evaluations | vs first (m) | wall s |", "|---|---|---|---:|---:|"]
    for r in rows:
        jacobians = f", {r['jacobians']} Jacobians" if r["jacobians"] else ""
        lines.append(f"| {r['method']} | {r['rtol']:.0e} | {r['steps']} steps, {r['evaluations']} motion(){jacobians} | "
                     f"{np.linalg.norm(r['tip'] - rows[0]['tip']):.1e} | {seconds(r['wall'])} |")
    return lines


def report(result, args):
    ref = result.get("reference")
    version = exu.config.Version() if exu is not None else "not installed"
    lines = ["# mbsynth against Exudyn: a pinned flexible pendulum, 1 s", "",
             f"{datetime.date.today()}, {platform.platform()}, {platform.processor() or platform.machine()}, "
             f"{os.cpu_count()} cores (shared), Python {platform.python_version()}, Exudyn {version}; written by "
             f"`.venv/bin/python benchmarks/flexible.py{' --quick' if args.quick else ''}`.", "",
             f"The pendulum of tests/model/flexible/test_flexible_pendulum.py: a 1 m beam of {ELEMENTS} Euler–Bernoulli "
             f"elements (consistent mass) on a revolute joint at node 0, released horizontal; Craig–Bampton at node 0 "
             f"(held at the frame) with {MODES} fixed-interface modes, from the same FE matrices in both codes "
             "(Exudyn: FEMinterface.ComputeHurtyCraigBamptonModes, each beam node as two 3-DOF nodes; the "
             "ObjectFFRFreducedOrder given mbsynth's inertia invariants, see the module docstring). *vs reference*: the "
             f"tip's distance at 1 s from mbsynth at rtol = atol = {REFERENCE_RTOL:.0e}; *integration error*: from the "
             f"same code's own finest run (Exudyn: {result['finest']} steps). *wall s*: best of {REPEATS} (1 for a run over "
             f"{LONG:.0f} s) of `simulate` / `SolveDynamic` alone.", "",
             "| problem | code | settings | steps / evaluations | integration error (m) | vs reference (m) | wall s |",
             "|---|---|---|---|---:|---:|---:|"]
    for r in result["rows"]:
        lines.append(f"| pendulum 1 s | {r['code']} | {r['settings']} | {counters(r)} | {r['own']:.1e} | "
                     f"{np.linalg.norm(r['tip'] - ref):.1e} | {seconds(r['wall'])} |")
    fastest = matched(result["rows"])
    lines += ["", f"Cheapest run with an integration error ≤ {TARGET:.0e} m: " + "; ".join(fastest) + "." if fastest else ""]
    lines += spin_up_table(result["spin_up"])
    lines += ["", "Checks:", ""] + [f"- {c}" for c in result["checks"]] + [""]
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="one setting per code, no unreduced model, print only")
    args = parser.parse_args()
    text = report(benchmark(args.quick), args)
    print(text)
    if not args.quick:
        (HERE / "flexible_results.md").write_text(text)


if __name__ == "__main__":
    main()
