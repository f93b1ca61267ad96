"""A fixed-base Pinocchio model as an Exudyn ObjectKinematicTree, for benchmarks/end_to_end.py.

Exudyn's fastest route for an open chain: its minimal-coordinate kinematic tree (one
joint coordinate per link, as Pinocchio's), integrated by its own adaptive explicit
Runge–Kutta pair (``DOPRI5``, automatic step size at the given tolerances; the redundant
rigid-body formulation with generalized-α is benchmarks/exudyn_chain.py's). Each joint of
``model`` (revolute about x, y or z: JointModelRX/RY/RZ, below a fixed base) becomes one
link: the joint's placement as ``jointTransformations``/``jointOffsets``, Pinocchio's
mass, centre of mass and rotational inertia about it, gravity on the tree. The mass
matrix is factored by Eigen's dense LU (``EigenDense``: on the 100-link chain 3.3 ms a
step against 17.5 ms with Exudyn's default ``EXUdense``).
"""

import time

import exudyn as exu
import numpy as np
from exudyn.itemInterface import NodeGenericODE2, ObjectKinematicTree

JOINTS = {"JointModelRX": exu.JointType.RevoluteX, "JointModelRY": exu.JointType.RevoluteY,
          "JointModelRZ": exu.JointType.RevoluteZ}


class ExudynTree:
    """Exudyn's kinematic tree of a fixed-base Pinocchio ``model`` (module docstring)."""

    def __init__(self, model):
        kinds = [model.joints[i].shortname() for i in range(1, model.njoints)]
        if any(kind not in JOINTS for kind in kinds):
            raise ValueError("Exudyn's kinematic tree here takes revolute joints about x, y or z only")
        self.nv = model.nv
        links = range(1, model.njoints)
        self.tree = dict(
            jointTypes=[JOINTS[kind] for kind in kinds],
            linkParents=[model.parents[i] - 1 for i in links],  # -1: the base
            jointTransformations=exu.Matrix3DList([model.jointPlacements[i].rotation for i in links]),
            jointOffsets=exu.Vector3DList([model.jointPlacements[i].translation for i in links]),
            linkInertiasCOM=exu.Matrix3DList([model.inertias[i].inertia for i in links]),
            linkCOMs=exu.Vector3DList([model.inertias[i].lever for i in links]),
            linkMasses=[model.inertias[i].mass for i in links],
            gravity=list(model.gravity.linear))

    def run(self, q, v, t_end, tolerance, steps=1000):
        """(seconds of SolveDynamic, accepted steps, joint angles at t_end) from (q, v);
        no step longer than t_end / ``steps``."""
        mbs = exu.SystemContainer().AddSystem()
        node = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0] * self.nv, initialCoordinates=list(q),
                                           initialCoordinates_t=list(v), numberOfODE2Coordinates=self.nv))
        mbs.AddObject(ObjectKinematicTree(nodeNumber=node, **self.tree))
        mbs.Assemble()
        settings = exu.SimulationSettings()
        settings.linearSolver.solverType = exu.LinearSolverType.EigenDense  # 5x its own EXUdense on the chain
        integration = settings.timeIntegration
        integration.endTime, integration.numberOfSteps = t_end, steps
        integration.minimumStepSize = 1e-14 * t_end  # the default 1e-8 s stops error control on the chain
        integration.explicitIntegration.dynamicSolverType = exu.DynamicSolverType.DOPRI5
        integration.automaticStepSize = True
        integration.relativeTolerance = integration.absoluteTolerance = tolerance
        integration.verboseMode = 0
        settings.solution.file.write = False
        settings.solution.sensors.active = False
        started = time.perf_counter()
        mbs.SolveDynamic(settings, solverType=exu.DynamicSolverType.DOPRI5)
        seconds = time.perf_counter() - started
        solver = mbs.sys["dynamicSolver"].it
        if abs(solver.currentTime - t_end) > 1e-9 * t_end:
            raise RuntimeError(f"Exudyn stopped at t = {solver.currentTime}")
        angles = np.array(mbs.GetNodeOutput(node, exu.OutputVariableType.Coordinates))
        return seconds, solver.currentStepIndex, angles
