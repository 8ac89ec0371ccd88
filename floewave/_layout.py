"""The numbers the kernel files share: option codes and the row layouts of the kernels' arrays
(window statistics, drag scratch, cell-table moments).

No function here; but numba freezes these module globals into the compiled code, so this is
one of ``floewave._jit.KERNEL_SOURCES`` (a changed row recompiles every kernel).
"""
from __future__ import annotations

# option codes (decided once from ModelConfig)
CONTACT_HERTZ_DISK = 0
CONTACT_LINEAR = 1
DAMPING_LIGGGHTS = 0
DAMPING_EXACT = 1
INTEG_PREDICTOR = 0
INTEG_HALF_STEP = 1
INTEG_RESPA = 2      # contacts on their own clock, slow force as impulses (floewave._respa)
INTEG_MTS = 3        # ... the slow force held at the outer step's centre (floewave._respa)
DRAG_QUADRATURE = 0
DRAG_EXACT = 1
HOLD_MIDPOINT = 0    # drag_hold: a held drag evaluated at the predicted centre of its steps
HOLD_LINEAR = 1      # ... at the true state, extrapolated linearly from the last two

# rows of the per-window statistics array ``stats`` (shape (N_STATS, R N_f))
ST_S3 = 0        # sum over steps and cells of |u_rel|^3            [m^3 s^-3]
ST_X = 1         # sum over steps of x_i                            [m]
ST_GAP = 2       # sum over steps of gap_i (pair i, i+1)            [m]
ST_CONTACT = 3   # steps in contact (pair i, i+1)                   [-]
ST_COLL = 4      # contact onsets (pair i, i+1)                     [-]
ST_FW = 5        # sum over steps of |F_w,i|                        [N]
ST_FC = 6        # sum over steps of |net contact force on i|       [N]
ST_FD = 7        # sum over steps of |F_d,i|                        [N]
N_STATS = 8

# rows of the drag scratch ``sc`` (shape (N_SC, R N_f + LANES)) of drag_pass /
# drag_pass_exact
SC_C = 0         # cos theta_i
SC_S = 1         # sin theta_i
SC_S2 = 2        # drag sum of |u_rel| u_rel
SC_S3 = 3        # drag sum of |u_rel|^3 (accumulating steps only)
SC_FLAG = 4      # 1: the floe needs the general evaluation
SC_SIG = 5       # sign the closed form gave the floe's whole-floe sums
SC_GATHER = 6    # rows 6-18: the general floes gathered by cell_sums / prefix_sums
N_GATHER = 13
N_SC = SC_GATHER + N_GATHER
LANES = 16       # gathered floes are padded to a multiple of this (vector body)

# rows of the time loop's scratch ``work`` (shape (N_WORK, R N_f + LANES)), each the one
# after the row before
W_UH = 0                 # half-step velocity u_{n+1/2}                          [m s^-1]
W_VS = W_UH + 1          # velocity v* of the velocity-dependent forces          [m s^-1]
W_F = W_VS + 1           # force of eq. 8 (floewave._force_terms.eq8_forces)     [N]
W_CK = W_F + 1           # cos(k x_i), rotated by k dx_i every step              [-]
W_SK = W_CK + 1          # sin(k x_i)                                            [-]
W_FC = W_SK + 1          # contact force of pair (i, i+1), > 0 pushing apart     [N]
W_VC = W_FC + 1          # a held drag's (drag_every > 1, "midpoint") velocity   [m s^-1]
W_CKC = W_VC + 1         # ... and cos, sin(k x_i) at the centre of its steps    [-]
W_SKC = W_CKC + 1
W_D0 = W_SKC + 1         # drag_hold "linear": the sums s2 of the last evaluation [m^2 s^-2]
W_DS = W_D0 + 1          # ... their slope per step from the evaluation before   [m^2 s^-2]
W_DI = W_DS + 1          # ... the step of the last evaluation (a float)         [-]
W_SC = W_DI + 1          # then the drag scratch sc (N_SC rows, SC_* above)
# integrator "respa" (floewave._respa) only, after the drag scratch:
W_AF = W_SC + N_SC       # contact (fast) acceleration, kept from step to step     [m s^-2]
W_XS = W_AF + 1          # a replica's x, u, af, in_contact at the outer step's start
W_US = W_XS + 1
W_AFS = W_US + 1
W_ICS = W_AFS + 1
W_ACT = W_ICS + 1        # 1: pair (i, i+1) sub-stepped this outer step (a float)
W_TX = W_ACT + 1         # the outer step's sums of x, gap, contact steps, onsets and
W_TGAP = W_TX + 1        # |net contact force| before they join ``stats``
W_TCON = W_TGAP + 1
W_TCOLL = W_TCON + 1
W_TFC = W_TCOLL + 1
N_WORK = W_TFC + 1

# entries of the cell-table moments of :func:`drag_tables`
M_N = 0          # number of cells n_x
M_CB = 1         # mean of cxi
M_SB = 2         # mean of sxi
M_VCC = 3        # sum (cxi - M_CB)^2
M_VCS = 4        # sum (cxi - M_CB)(sxi - M_SB)
M_VSS = 5        # sum (sxi - M_SB)^2
M_TCCC = 6       # third central moments: sum dc^3, dc^2 ds, dc ds^2, ds^3
M_TCCS = 7
M_TCSS = 8
M_TSSS = 9
M_CMAX = 10      # cos h (h: offset of the outer cell midpoints), -2 if h >= pi
M_CH = 11        # cos h
M_SH = 12        # sin h
M_FAST = 13      # 1: tables as built by FloeChain (closed forms and prefix sums usable)
M_H = 14         # h = k (L_x - dx) / 2, phase offset of the outer cell midpoints
M_KDX = 15       # delta = k dx, phase step between cells
M_INV_KDX = 16   # 1 / delta
M_NROOT = 17     # most roots of one family on a floe: floor(2 h / 2 pi) + 1
M_HE = 18        # k L_x / 2 = h + delta / 2, phase offset of the floe's ends
M_CHE = 19       # cos, sin of M_HE
M_SHE = 20
M_T1 = 21        # 1 / (2 sin(m delta / 2)), m = 1, 2, 3 (geometric sums of cos(m psi_j))
M_T2 = 22
M_T3 = 23
M_EXACT = 24     # 1: tables of the exact drag (exact_tables): roots at their own phase
M_SCALE = 25     # n_x / (k L_x): the exact drag's integrals in cells
N_MOM = 26
# the geometric sums are evaluated with Taylor series of sin, cos of d, |d| <= delta / 2
# (:func:`_sin_cos_small`): the prefix sums of drag_pass need delta = k dx up to this (at
# most 0.035 in the paper's grid); coarser tables are summed cell by cell
KDX_MAX = 0.05
# ... and down to this: the geometric sums carry 1 / (2 sin(m delta / 2)) ~ 1 / (m delta), so
# their rounding grows as eps / delta (measured: 1.6e-13 of the floe's scale at delta = 1e-3,
# 3e-12 at 5e-7); finer tables are summed cell by cell as well
KDX_MIN = 1e-3
