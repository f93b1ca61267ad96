"""Every threshold by which mbsynth decides a numerical question, in one place, each with its
own name: what counts as zero, as consistent, as converged, as agreeing.

All are relative (to the scale named beside each) and dimensionless unless said otherwise.
The compiled kernels read theirs as compile-time constants: a change here recompiles them
(compiled/cache.py salts its cache with this file).
"""

# ---- the equations (core/equations.py, core/solvers.py): rank and consistency of (2.14)
RANK_RTOL = 1e-12  # singular values below RANK_RTOL · σ_max of the equilibrated matrix are zero
CONSISTENCY_RTOL = 1e-9  # least relative size of b ∉ range(A) or of wᵀ(Q + C) that is an error
SYMMETRY_RTOL = 1e-10  # largest |M − Mᵀ| accepted, relative to max |M|
NAME_RTOL = 1e-6  # a component below this fraction of the largest one is not named in errors
NEAR_SINGULAR = 1e-5  # σ_i below this fraction of σ₁ (of the equilibrated A): a nearly dependent direction
DRIFT_RANK = 10.0  # off the manifold, a nearly dependent σ_i below this times the relative drift δ (× σ₁) is dependent
VERDICT_MARGIN = 1e2  # a singular value within this factor of the rank cut-off makes the verdict uncertain
# (a mass ratio of 1e-9, 1e3 times the cut-off, is a legitimate model and is not flagged)

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
SPLIT_MOVES = 1e4  # kernel.py, off the manifold: a dropped direction of Schur eigenvalue λ may move accelerations
# up to this times √(λ / the largest) (the drift splits dependent rows by about that much)
CORRECTION_RTOL = 1e-14  # correction.py: largest |φ| left, relative to the largest coordinate (at least 1): ~50 ε;
# extra_correction.py: relative to each row's terms
CORRECTION_RATE_RTOL = 1e-12  # correction.py: a velocity step must leave φ̇ below this, relative to the
# largest coordinate (at least 1) times the largest rate (or cut it by SHRINK)
# projection.relative_drift, extra_correction.py: a row's scale is at least this share of ‖A_i‖₁ ‖x‖∞. At a
# singular position some rows' terms vanish (the N-four-bar's horizontal velocity rows when the bars lie flat)
# down to term_scales' default floor of 1e-3 of that, and the same absolute drift read up to a thousand times
# larger there: simulate's spans between projections then shrank to 5e-10 s and stayed there (N = 2 at
# dt = 0.001, its second crossing)
DRIFT_FLOOR = 0.1
STACKED_CHECK_RTOL = 1e-12  # grouped.py: a stacked call must agree with the single calls to this,
# relative to the group's largest value (checked once, at the first state)

# ---- the model (model/)
BALANCE_ZERO_RTOL = 1e-9  # balances.py: a sampled balance below this (relative to the force scale) is zero
ANGLES_IN_NULLSPACE = 1e-6  # angle_singularity.py: a body's turning-nothing angle rates (unit) within this of
# null([M; A]) make that indeterminate direction the angles' singular position (√RANK_RTOL: M holds H twice)
DEPENDENT_RTOL = 1e-8  # reactions.py: a row takes part in a dependency when its weight in one exceeds this
COULOMB_LOAD_RTOL = 1e-12  # friction.py: Coulomb loads N have converged when they change by less than this

# ---- analysis (analysis/)
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

# ---- validation against Pinocchio (robots/)
VALIDATION_RTOL = 1e-9  # validate.py: largest relative error that passes
SELF_STRESS_RTOL = 1e-9  # validate.py: singular values of J below this · σ_max are self-stresses;
# wrench directions likewise
