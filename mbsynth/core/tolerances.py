"""Every threshold by which mbsynth decides a numerical question, in one place, each with its
own name: what counts as zero, as consistent, as converged, as agreeing; and the few small
numbers its numerical methods run with (a differentiation step, a scale's floor). No module
writes such a number inline (tests/core/test_tolerances.py holds it).

All are relative (to the scale named beside each) and dimensionless unless said otherwise.
The compiled kernels read theirs as compile-time constants: a change here recompiles them
(compiled/cache.py salts its cache with this file).
"""

import sys

EPS = sys.float_info.epsilon  # the spacing of floats at 1 (numpy's finfo(float).eps): rounding's unit
DIVISION_GUARD = 1e-300  # added to (or the floor of) a scale that may be zero, so that 0 / scale is 0, not nan

# ---- the equations (core/equations.py, core/solvers.py): rank and consistency of (2.14)
RANK_RTOL = 1e-12  # singular values below RANK_RTOL · σ_max of the equilibrated matrix are zero
CONSISTENCY_RTOL = 1e-9  # least relative size of b ∉ range(A) or of wᵀ(Q + C) that is an error
SYMMETRY_RTOL = 1e-10  # largest |M − Mᵀ| accepted, relative to max |M|
NAME_RTOL = 1e-6  # a component below this fraction of the largest one is not named in errors
NEAR_SINGULAR = 1e-5  # σ_i below this fraction of σ₁ (of the equilibrated A): a nearly dependent direction
DRIFT_RANK = 10.0  # off the manifold, a nearly dependent σ_i below this times the relative drift δ (× σ₁) is dependent
VERDICT_MARGIN = 1e2  # a singular value within this factor of the rank cut-off makes the verdict uncertain
# (a mass ratio of 1e-9, 1e3 times the cut-off, is a legitimate model and is not flagged)
CONSISTENCY_ROUNDING = 8 * EPS  # equations.py: rounding of b along a dropped direction, per row and unit condition
TERM_FLOOR = 1e-3  # term_scales: the share of ‖A_i‖₁ ‖x‖∞ that a row with coordinates near zero keeps
KKT_RCOND_MIN = 1e-8  # solvers.py: KKT systems less well conditioned than this go to the reference (2.14)
KKT_RESIDUAL_MAX = 1e-9  # solvers.py: a KKT solution whose relative residual of (2.12) exceeds this goes too

# ---- the compiled path (compiled/)
PIVOT_RTOL = 1e-9  # tree.py: a pivot below this fraction of its scale (for a mass: its node's or the model's
# largest, whichever is larger) counts as zero; three decades above RANK_RTOL, so a link near (2.14)'s cut goes there
SCHUR_ZERO_RTOL = 1e-10  # kernel.py: Schur eigenvalues below this fraction of max(the largest, 1) are zero
KERNEL_CONSISTENCY_RTOL = 1e-10  # kernel.py: largest part of the right side along dropped directions,
# relative to b's (tighter than CONSISTENCY_RTOL: the kernel hands a doubtful state to the exact path)
KERNEL_NULL_RTOL = 1e-8  # kernel.py: largest acceleration a dropped (unit) direction may move
SCHUR_DEPENDENT_RTOL = 1e-14  # kernel.py, off the manifold: Schur eigenvalues below this fraction (~50 ε) are
# rounding of rows dependent on the manifold, whatever the drift
DRIFT_MASS_SPREAD = 1e-4  # kernel.py, off the manifold: masses (diagonal, over the largest) spanning more than this
# send a model's stages to the exact drift rule (the Schur eigenvalues mix masses with the rows' geometry)
SCHUR_CONDITION_MAX = 1e8  # kernel.py, off the manifold with extra coordinates: a Schur (or bordered) matrix more ill-conditioned
# than this sends the stage to the exact drift rule (the solve's relative error, about ε κ, would pass 1e-8: near a
# singular position, where the exact rule's own solution keeps its accuracy, an integrator would crawl on the noise)
SPLIT_MOVES = 1e4  # kernel.py, off the manifold: a dropped direction of Schur eigenvalue λ may move accelerations
# up to this times √(λ / the largest) (the drift splits dependent rows by about that much)
MASS_PROJECTION_RTOL = 1e-14  # compiled/projection.py: largest |φ| left, relative to the largest coordinate
# (at least 1): ~50 ε; extra_projection.py: relative to each row's terms
MASS_PROJECTION_RATE_RTOL = 1e-12  # compiled/projection.py: a velocity step must leave φ̇ below this, relative to the
# largest coordinate (at least 1) times the largest rate (or cut it by MASS_PROJECTION_SHRINK)
DRIFT_FLOOR = 0.1  # projection.relative_drift, extra_projection.py: a row's scale is at least this share of
# ‖A_i‖₁ ‖x‖∞: at a singular position some rows' terms vanish (the N-four-bar's horizontal velocity rows when the
# bars lie flat), and the same absolute drift must not read a thousand times larger there (TERM_FLOOR's floor),
# or the spans between projections shrink without end
MASS_PROJECTION_REUSE = 1e-8  # compiled/projection.py: the largest position step and φ̇ (relative) for which the
# velocity step reuses a factorization
MASS_PROJECTION_SHRINK = 1e-3  # compiled/projection.py, extra_projection.py: a velocity step must cut φ̇ by this
# much at least (or leave it below MASS_PROJECTION_RATE_RTOL of its terms)
KERNEL_RESIDUAL_MAX = 1e-9  # kernel.py: a solution whose relative residual exceeds this goes to the exact path
JACOBI_OFF_RTOL = EPS ** 2  # eigen.py: Jacobi sweeps stop when the off-diagonal's squared norm is below this share
# of the whole (its entries at rounding, ε of the matrix: where eigenvalues repeat, sweeps cannot push them lower)
STACKED_CHECK_RTOL = 1e-12  # grouped.py: a stacked call must agree with the single calls to this,
# relative to the group's largest value (checked once, at the first state)

# ---- the model (model/)
BALANCE_ZERO_RTOL = 1e-9  # balances.py: a sampled balance below this (relative to the force scale) is zero
ANGLES_IN_NULLSPACE = 1e-6  # angle_singularity.py: a body's turning-nothing angle rates (unit) within this of
# null([M; A]) make that indeterminate direction the angles' singular position (√RANK_RTOL: M holds H twice)
DEPENDENT_RTOL = 1e-8  # reactions.py: a row takes part in a dependency when its weight in one exceeds this
COULOMB_LOAD_RTOL = 1e-12  # friction.py: Coulomb loads N have converged when they change by less than this
COULOMB_NOISE = 16 * EPS  # friction.py: a load's change below this times its rows' size and the force scale is rounding
READABLE_DROP = 1e-9  # balances.py: a term of a sum below this times its largest coefficient is left out of a
# printed balance
BALANCE_ENTRY_ZERO = 1e-12  # balances.py: a balance's coefficient below this (its largest is 1) is not listed
RATIONAL_TOL = 1e-12  # balances.py: a null-space entry is written as the simplest rational within this of it
MASS_NEGATIVE_RTOL = 1e-12  # system.py: a mass matrix eigenvalue below −this × max |M| is negative, not rounding
GRAM_ZERO_RTOL = 1e-14  # parts/flexible_body.py: invariant entries below this fraction of the largest are rounding:
# written as zero
BEAM_UP_PARALLEL_RTOL = 1e-9  # flexible/beam.py: a section's up vector whose part across the axis is below this
# (relative to |up|, at least 1) is parallel to the axis
PARALLEL_SIN2 = 1e-16  # segments.py: two capsules' axes with sin² of their angle below this are parallel (no division
# by it): there the gap is off by at most sin × their overlap (1e-8 L); above it the lines' pair rounds by ~ε/sin

# ---- finite-element models (model/flexible/)
FE_SYMMETRY_RTOL = 1e-8  # matrices.py: largest |A − Aᵀ| accepted, relative to max |A| (exports round to ~8 digits)
FE_TRANSLATION_MASS_RTOL = 1e-6  # matrices.py: the rigid translations' 3 × 3 mass must be m·I to this, relative to m
FE_SEMIDEFINITE_RTOL = 1e-8  # matrices.py: A + FE_SEMIDEFINITE_RTOL · max|A| · I must be positive definite
FE_ZERO_RTOL = 1e-15  # reduction.py: ω² below FE_ZERO_RTOL · tr K / tr M is rounding of K's null space (a few ε of
# the largest ω²)
FE_SHIFT_RTOL = 1e-14  # reduction.py: the default shift −FE_SHIFT_RTOL · tr K / tr M: 10× the zero level
# (rigid-body modes factor)
FE_DENSE_SHIFT_RTOL = 1e-8  # reduction.py: the dense solver's shift: finite modes up to 1e4 · tr K / tr M stay apart
# from a singular M's infinite ones (FE_FINITE_RTOL); a dense solve needs no convergence, and the Ritz quotients refine
# the lowest
FE_CLUSTER_RTOL = 1e-4  # reduction.py: modes whose ω² differ by less than this fraction span one eigenspace (a
# 2,000-element beam's equal frequencies come out 1e-5 apart)
FE_TIE_RTOL = 1e-4  # reduction.py: components within this fraction of the largest tie: the first DOF of them fixes a
# cluster's basis
FE_RIGID_RANK_RTOL = 1e-9  # reduction.py: singular values of the rigid-body modes at the interface below this
# fraction: a motion it leaves free
FE_FINITE_RTOL = 1e-12  # reduction.py: a dense mode with 1/(λ + shift) below FE_FINITE_RTOL / shift is an infinite
# one (M φ = 0)

# ---- reading model files (io/)
ASSEMBLED_TOL = 1e-6  # loader.py: a joint whose rows are all below this (SI units) at the initial state is assembled
INERTIA_SYMMETRY_RTOL = 1e-12  # parts.py: largest |J − Jᵀ| of an inertia accepted, relative to max |J|
INERTIA_NEGATIVE_RTOL = 1e-12  # parts.py: a principal moment below −this × max |J| is negative, not rounding
TRIANGLE_RTOL = 1e-9  # parts.py: I1 + I2 may fall short of I3 by this share of I3 (and INERTIA_NEGATIVE_RTOL of
# max |J|) before the moments break the triangle inequality
QUATERNION_NORM_TOL = 1e-6  # parts.py: a given quaternion's norm may differ from 1 by this (files round)
PLANE_RTOL = 1e-12  # placement.py: a turn whose R_zz is this close to 1 keeps the xy plane (rpy rounding)
SIGN_TOL = 1e-12  # placement.py: a unit quaternion's component below this is rounding (w of a half turn): it cannot
# fix the sign

# ---- analysis (analysis/)
INTEGRATION_RTOL = 1e-10  # simulate's (and the CLI's) default relative tolerance of the integrator
INTEGRATION_ATOL = 1e-10  # simulate's (and the CLI's) default absolute tolerance of the integrator
LAST_INTERVAL_MERGE = 1e-12  # simulate.py: a last output interval shorter than this times dt joins the one before
SAMPLE_ROUNDING = 1e-9  # schedule.py: a span within this many sample intervals of a whole number of them has that many
FIRST_STEP_ZERO_NORM = 1e-5  # dop853.py: a state or rate of scaled RMS norm below this counts as zero when the
# first step is chosen (Hairer, Nørsett & Wanner II.4, as scipy's select_initial_step); the trial step is then
FIRST_STEP_GUESS = 1e-6  # dop853.py: that trial step, and the least first step where the rate does not change
FIRST_STEP_FLAT = 1e-15  # dop853.py: scaled norms of the rate and of its change below this count as no change
JACOBIAN_STEP = 1.5e-8  # derivative.py: √ε, a forward difference's truncation and rounding errors balance (per unit of y)
DIP_FLOOR = 1e-12  # singular_watch.py: σ_r/σ₁ below its neighbours by less than this is the SVD's rounding (~n ε), not a dip
MAX_STATE = 1e12  # derivative.py: a coordinate or velocity beyond this (SI units) counts as an exploding state
COLLAPSE_SPAN = 1e-8  # derivative.py: COLLAPSE_CALLS evaluations that advance t by less than this share of the
# interval are a step-size collapse
STEP_RESOLUTION = 1e4 * EPS  # derivative.py: steps below this times |t| are near the resolution of t: a collapse too
ANGLES_NEAR = 1e-2  # derivative.py: |det H| of a part's angles below this (0.57° from their singular position):
# angle rates above 100 times the angular velocity
RELAXED_RTOL = 1e-8  # cut.py: a span that crawls near a singular position is integrated again at this rtol (and atol)
RELAXED_MAX = 1e-7  # cut.py: ... then ten times looser each time, up to this
DRIFT_TARGET = 1e-9  # drift.py: largest relative drift off the manifold between two projections
DRIFT_REDO = 1e3  # drift.py: a span that drifted more than this × DRIFT_TARGET is integrated again, shorter
REDO_MIN_SPAN = 1e-6  # drift.py: of the output interval: the shortest span that is integrated again
PROJECTION_DIVERGED = 1e6  # projection.py: a last pass stops where its largest residual exceeds this times its
# smallest so far
SPARSE_ACCEPT = 1e-10  # projection.py: relative residual under which the sparse least-norm step is taken
PROJECTION_RCOND = 1e-8  # projection.py: directions of J (columns equilibrated) below this × σ₁ count as dependent
VELOCITY_ACCEPT = 1e-9  # projection.py: largest relative ψ after the one (linear) velocity step
COLUMN_FLOOR = 1e-4  # projection.py: a retried projection's smallest column scale, relative to the largest entry of
# its rows
CURVATURE_STEP = 1e-5  # projection.py: central differences of A, relative to the largest coordinate (at least 1)
COMPLEX_STEP = 1e-30  # linearization.py: Im f(x + i h)/h = f'(x) + O(h²): no cancellation, so h can be tiny
STEADY_FIT_TOL = 1e-15  # steady.py: xtol, ftol and gtol of the steady motion's least-squares fit (to rounding)
PROJECTION_RTOL = 1e-12  # projection.py: largest residual accepted after projection, relative to the row's terms
ON_MANIFOLD_RTOL = 1e-8  # linearization.py: largest φ, ψ residual accepted, relative to its row's terms
STRUCTURAL_ZERO_RTOL = 1e-12  # linearization.py: an entry of A below this times its row's largest is zero
# (a cyclic coordinate's column, a conserved speed's row): it splits A into blocks whose eigenvalues are taken apart
CHANGE_POINT_RTOL = 1e-7  # linearization.py: a dependency's second derivative on the tangent space above
# this (relative) marks a change point
ACCELERATION_TOL = 1e-10  # statics.py: largest |q̈| (SI units) accepted at an equilibrium, relative to
# (1 + the scale of K)
ISOLATED_RTOL = 1e-9  # statics.py: a singular value of K below this times the largest: a free direction
MODE_ZERO_RTOL = 1e-6  # modes.py: an eigenvalue below this times the largest |s| is zero (a free direction):
# a zero stiffness computed with rounding error ε splits a double zero eigenvalue into ±√ε, so the cut is near √ε
STABILITY_RTOL = 1e-6  # modes.py: an exponent whose real part is within this times the largest |s| of 0 is
# neutral (it neither grows nor decays to the linearization's accuracy: rounding splits a double zero into ±√ε)
COMPONENT_TOL = 1e-12  # diagnose.py: a direction's component below this is left out of its description
AXIS_TOL = 1e-9  # diagnose.py: a unit vector within this of a body's or the world's axis is that axis
V_ROUNDING = 1e-9  # statics.py: a change of V below this share of |V| is rounding-limited: the trapezoid judges it
TRUST_CURVATURE_RTOL = 1e-12  # statics.py, the trust-region problem: a curvature below this times the largest is 0
FREE_SHOWN_RTOL = 1e-6  # statics.py: a free direction's component below this share of its largest is not shown
DEGENERATE_RTOL = 1e-6  # modes.py: eigenvalues this close (relative) are one repeated mode, split by rounding
NODE_SHAPE_RTOL = 1e-9  # modes.py: a flexible body's elastic coordinates below this share of a shape's largest: it
# does not bend
DAMPING_ROUNDING = 8 * EPS  # modes.py: Re s below this times the largest |s| is rounding: no damping
MODE_SHOWN_RTOL = 1e-6  # modes.py: a shape's component below this share of its largest is shown as 0 (or not named)
IMAGINARY_SHOWN_RTOL = 1e-9  # modes.py: an imaginary part below this share of |z| is not printed
SHAPE_ENTRY_ZERO = 1e-12  # modes.py: a mode shape's entry below this (its largest is 1) is left out of the JSON
COMPLEX_SHAPE_TOL = 1e-9  # modes.py: a mode shape whose imaginary parts exceed this (its largest is 1) is complex
REST_HOP = 1.0  # impacts.py: a rebound whose hop height v²/(2|g̈|) is below this times the run's atol (a hop its
# position accuracy cannot resolve) ends the bouncing: the gap comes to rest, no accumulation of impacts to chase
SPEED_ROUNDING = 1e3 * EPS  # impacts.py: a gap's rate within this times ‖a‖₁ max |q̇| of zero is rounding (of the
# jumps before it at that instant): neither striking nor separating
EVENT_TIME_RTOL = 4 * EPS  # impacts.py: an event's time is found to this relative accuracy (Brent's least: rounding)
COMPLEMENTARITY_RTOL = 1e-9  # impacts.py: an impulse or contact force above −this × the largest, and a gap's rate or
# acceleration above −this × its terms' size, meets its sign condition (the KKT solve's rounding)
CONE_TOL = 1e-10  # cones.py: the cutting planes stop where the true largest cone violation at the program's force
# is within this (in units of the forces' size) of the program's value: the lower and upper bounds on s* meet
CONE_DEPTH = 1e-3  # cones.py: a true violation below −this (in the forces' size) is well inside the cones: the
# programs stop there (an upper bound on s*, so its sign is right; exact values are needed only near s* = 0)
LP_FEASIBILITY_TOL = 1e-10  # cones.py: HiGHS's primal and dual feasibility tolerances (the least it accepts)
SLIP_DIRECTION_TOL = 1e-8  # impacts.py: a sliding contact's unit slip direction and its slip's acceleration's agree
# within this (a fixed point: the friction opposes the slip it starts)
CHECK_RESIDUAL_TOL = 1e-9  # cli/check.py: an initial constraint residual beyond this (SI units) is a violation

# ---- validation against Pinocchio (robots/)
VALIDATION_RTOL = 1e-9  # validate.py: largest relative error that passes
SELF_STRESS_RTOL = 1e-9  # validate.py: singular values of J below this · σ_max are self-stresses;
# wrench directions likewise
SAME_STATE_TOL = 1e-8  # validate.py: two maximal states agree when positions differ by less than this (and
# velocities relative to (1 + the largest))
NULLSPACE_SHOWN_TOL = 1e-6  # validate.py: a coordinate moving less than this along every indeterminate direction is
# not named
PROXIMAL_ACCURACY = 1e-13  # twin.py: Pinocchio's constraintDynamics: the proximal iterations' accuracy
PROXIMAL_MU = 1e-10  # twin.py: constraintDynamics's proximal μ (it admits redundant loop rows)
URDF_INERTIA_RTOL = 1e-12  # urdf.py: a principal moment below −this × the largest (and −URDF_INERTIA_ATOL): negative
URDF_INERTIA_ATOL = 1e-15  # urdf.py: a principal moment above −this (kg m²) is rounding (icub's head has moments of
# ±2.4e-35 kg m²: zero, printed with noise)
EXACT_ENTRY_TOL = 1e-15  # build.py: a matrix entry within this of −1, 0 or 1 is made that exact integer

# ---- drawing and reporting (view/, studies/)
FRAME_SPACING_RTOL = 1e-9  # scene.py: rows 1/fps apart less this share of it are drawn both (times round)
SEGMENT_SCALE_FLOOR = 1e-9  # scene.py: a zero-length segment's scale along x (a transform must stay invertible)
GRID_SPACING_RTOL = 1e-12  # viewer.py: a grid step this share above size / 5 still counts as not above it
VIEW_TIE_BREAK = 1e-9  # viewer.py: extents equal to this look along y, then x
LOG_PLOT_FLOOR = 1e-18  # plot.py: residuals below this are drawn at it on the logarithmic axis
ELAPSED_FLOOR = 1e-9  # sweep.py: the elapsed time (s) a progress rate divides by at least
