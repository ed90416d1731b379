/* mbody's compiled core: the one numeric path of the physics.
 *
 * Everything that evaluates a model at a state is written here once, in plain C99:
 * rotations, applied loads and springs, the gyroscopic term, each joint constraint
 * primitive's column of G, phi, G^T v and gamma (time-dependent ones included), the
 * constrained solve (banded Schur complement, pivoted route for redundant joints,
 * null-space route near singular positions), the coordinate projection, load and law
 * expressions of t, and the integrators (DOP853 with dense output). Python packs a model
 * once (mbody/equations/pack.py) into one float array F and one int64 array I, and the
 * unknown reaction components of a solve into a third int64 array Iu; the extension
 * module (module.c) hands those buffers to the functions below. Nothing here knows joint
 * *types*: a joint type (mbody/joints/) is a list of components, each naming one of the
 * primitives MB_KIND_* below.
 *
 * Conventions (docs/conventions.md): every body is spatial inside the core (a planar body
 * lives in the world x-y plane, turns about world z; its rows are (x, y, w3) of the six).
 * Per body six rows [Newton x, y, z in world axes | Euler 1, 2, 3 in body axes].
 * A reaction acts on the child as +R at the joint point, on the parent as -R.
 *
 * Build: compiled with -O2 -ffp-contract=off (no fused multiply-add: results do not
 * depend on the CPU's instruction set).
 */
#ifndef MBODY_KERNEL_H
#define MBODY_KERNEL_H

#include <stddef.h>
#include <stdint.h>

/* ---------------------------------------------------------------------------------------
 * Component kinds: the constraint primitives. Per component, with
 *   E = (R_p P_E3)          the joint frame fixed in the parent, world axes (R_p = I for
 *                           ground), e = E[:, axis] its column `axis`,
 *   P = x_c + R_c B_r_child the child's joint point (world), P_p = x_p + R_p B_r_parent
 *                           the parent's (for ground: B_r_parent is a world point),
 *   A = (R_p P_E3)^T (R_c C_E3)   the child's joint frame seen in the parent's,
 *   h = param1, off = param0, and, when the component has a law l >= 0, f, f', f'' the
 *   law's value and derivatives at t:
 *
 * MB_KIND_FORCE  force along e:   child6 = [e; B_r_c x (R_c^T e)],
 *                                 parent6 = [-e; -(B_r_p x (R_p^T e))], B_r_p = R_p^T (P - x_p)
 *                phi = e . (P - P_p) + off,   gamma = -e . T   (T: constraints.py's vector)
 * MB_KIND_TILT   moment about e, axis in {0, 1}, the joint turning freely about E[:, 2]:
 *                child6 = [0; R_c^T e], parent6 = [0; -R_p^T e]
 *                phi = axis == 0 ? -A[1][2] : A[0][2],   gamma = -e . (w_c x w_p)
 * MB_KIND_LOCK   moment about e, rotation locked: columns as TILT,
 *                phi = 1/2 vee(A - A^T)[axis],          gamma as TILT
 * MB_KIND_RIGHT_ANGLE  the universal joint's moment about e = a x b / |a x b|, a = E[:, 2]
 *                on the parent, b = R_c C_axis2 on the child: columns as TILT with that e,
 *                phi = -a . b,  gamma = -((w_p x a) x b + a x (w_c x b)) . (w_c - w_p)
 * MB_KIND_LINK   a particle link's tension T: d = P - P_p, u = d/|d|, e = -u,
 *                child6 = [e; B_r_c x R_c^T e], parent6 = [-e; -(B_r_parent x R_p^T e)],
 *                phi = L - |d| (L = the joint's link length),
 *                gamma = u . (w_c x (w_c x rho_c) - w_p x (w_p x rho_p))
 *                        + (|d'|^2 - (u . d')^2) / |d|
 * MB_KIND_TURN   moment about e (rotation about e measured as an angle): columns as TILT,
 *                phi = wrap(theta + off - f),  theta = atan2(A[j][i], A[i][i]),
 *                i = (axis + 1) % 3, j = (axis + 2) % 3, wrap to (-pi, pi];
 *                gamma as TILT.  (Drivers of revolute joints; off: the coordinate's value
 *                at the file's pose, e.g. a planar child's angle minus its parent's.)
 * MB_KIND_SCREW  the helical joint's axial wrench along e = E[:, axis]: the FORCE column
 *                plus -h times the moment column about e (h = pitch / 2 pi, m/rad):
 *                child6 = [e; B_r_c x R_c^T e - h R_c^T e], parent6 = -(its parent side),
 *                phi = e . (P - P_p) + off - h theta~, theta~ the relative turn about
 *                e (as TURN) taken on the branch nearest (e . (P - P_p) + off) / h,
 *                gamma = gamma_FORCE - h gamma_TILT.
 *
 * Time dependence (drivers): a component with a law l >= 0 prescribes its coordinate:
 * the kernel reports phi - f(t) (TURN: inside the wrap), the residual G^T v - f'(t) where
 * G^T v is asked for, and gamma + f''(t); so Baumgarte's terms, the projection
 * (G^T dv = -(G^T v - f')) and the drift figures need nothing else.
 * ------------------------------------------------------------------------------------- */
enum {
    MB_KIND_FORCE = 0,
    MB_KIND_TILT = 1,
    MB_KIND_LOCK = 2,
    MB_KIND_RIGHT_ANGLE = 3,
    MB_KIND_LINK = 4,
    MB_KIND_TURN = 5,
    MB_KIND_SCREW = 6,
    MB_KINDS = 7
};

/* ---------------------------------------------------------------------------------------
 * The packed model (written by mbody/equations/pack.py; module.c checks every size).
 *
 * I (int64): header [n, k, s, nj, m, n_expr, n_code, n_varying, n_laws, n_known]
 *   (MB_I_HEADER entries),
 *   then per point load (k x 3)   [body, in_body (0/1), couple (0/1)]
 *   per spring (s x 2)            [a, b]          (-1 = ground)
 *   per joint (nj x 3)            [parent (-1 = ground), child, flags]
 *                                 flags: 1 particle link, 2 the parent is a particle
 *   per component (m x 4)         [joint, kind (MB_KIND_*), axis (0-2), law (-1: none)]
 *   per varying load entry (n_varying x 3) [load row, component (0-2), expression]
 *   per law (n_laws x 3)          [expression of f, of f', of f'']
 *   per known reaction varying in t (n_known x 2) [component, expression]: lam[component]
 *                                 is that expression's value at t (the caller's lam holds
 *                                 the constant known values and 0 on unknown components)
 *   expression starts (n_expr + 1) into the codes, then codes (n_code), postfix
 *                                 (MB_OP_*: the codes of mbody.model.expressions)
 * F (float64): gravity (3),
 *   per body (n x MB_BODY_W)      [mass, J (9, row-major, body axes), J^-1 (9)]
 *   per point load (k x 6)        [B_r (3, body axes), value (3): the constant value,
 *                                  varying entries overwritten at t]
 *   per spring (s x MB_SPRING_W)  [r_a (3), r_b (3), stiffness, rest length, damping]
 *   per joint (nj x MB_JOINT_W)   [B_r_child (3), B_r_parent (3), C_axis2 (3),
 *                                  P_E3 (9), C_E3 (9), link length]
 *   per component (m x 2)         [param0 (off), param1 (h)]
 *   expression numbers (n_code)   the constants the codes push
 *
 * Iu (int64), the unknown components of one solve (pack_unknowns):
 *   [mu, bw, nnz], U (mu: component indices, in solve order), inc_ptr (n + 1),
 *   inc (nnz x 2: [position in U, side 0 child / 1 parent]) per body: the unknown
 *   components acting on it; bw: half bandwidth of S = G_U^T M^-1 G_U in U's order.
 *
 * The state y (float64): [x (n x 3) world | q (n x 4) W_R_B, [w, x, y, z] | v (n x 3)
 * world | w (n x 3) body axes | theta (n), planar models only] (MB_STATE_SIZE).
 * ------------------------------------------------------------------------------------- */
enum { MB_I_HEADER = 10, MB_BODY_W = 19, MB_LOAD_W = 6, MB_SPRING_W = 9, MB_JOINT_W = 28,
       MB_COMP_W = 2 };
enum { MB_J_LINK = 1, MB_J_PARTICLE_PARENT = 2 };
enum { MB_OP_NUM = 0, MB_OP_T = 1, MB_OP_NEG = 2, MB_OP_ADD = 3, MB_OP_SUB = 4,
       MB_OP_MUL = 5, MB_OP_DIV = 6, MB_OP_POW = 7, MB_OP_SIN = 8, MB_OP_COS = 9,
       MB_OP_TAN = 10, MB_OP_EXP = 11, MB_OP_LOG = 12, MB_OP_SQRT = 13, MB_OP_ABS = 14 };
#define MB_STATE_SIZE(n, planar) (13 * (n) + ((planar) ? (n) : 0))

typedef struct {
    int64_t n, k, s, nj, m, n_expr, n_code, n_varying, n_laws, n_known;
    const double *gravity, *bodies, *loads, *springs, *joints, *comps_f, *numbers;
    const int64_t *loads_i, *springs_i, *joints_i, *comps_i, *varying, *laws, *starts,
        *codes, *known;
    int planar;
} mb_model;

typedef struct {
    int64_t mu, bw, nnz;
    const int64_t *U, *inc_ptr, *inc;
    /* The rank G_U has at the mechanism's generic configurations (mu when it is not
     * redundant there; set by the caller after a look at two assembled configurations,
     * mbody/equations/workspace.py). Off the configuration manifold by a distance d a
     * redundant mechanism's G_U gains singular values of about d: the solve keeps this
     * rank whenever the singular values beyond it are below MB_GENERIC_GAP of the largest,
     * so that rounding and integration error never make a redundant loop rigid. */
    int64_t generic_rank;
} mb_unknowns;
#define MB_GENERIC_GAP 1e-4

/* Views of F and I (no copy); returns 0, or -1 when the sizes do not add up. */
int mb_model_view(mb_model *md, const double *F, int64_t nF, const int64_t *I, int64_t nI,
                  int planar);
/* `out` = `md` with its float views moved from F0 (the array md views) onto F: the same
 * model structure (I) with other values (masses, lengths, law constants...), as
 * pack.py packs a model whose I equals md's. No copy, no check beyond md's own. */
void mb_model_rebase(mb_model *out, const mb_model *md, const double *F0, const double *F);
int mb_unknowns_view(mb_unknowns *u, const mb_model *md, const int64_t *Iu, int64_t nIu);
/* Iu (above) of the components U (mu of the m components, in solve order): each one's
 * bodies child[U[k]] and parent[U[k]] (-1 the ground) among n. Per body, its entries in
 * U's order, a component's child side before its parent side; bw the largest spread of
 * one body's positions. Written into out (room for MB_IU_ROOM(n, mu) values); returns
 * the length of Iu; -1 when an index is out of range, -2 when memory runs out. */
#define MB_IU_ROOM(n, mu) (3 + 5 * (mu) + (n) + 1)
int64_t mb_pack_unknowns(const int64_t *child, const int64_t *parent, int64_t m, int64_t n,
                         const int64_t *U, int64_t mu, int64_t *out);

/* Scratch memory for evaluations of one (model, unknowns): allocated once, reused. */
typedef struct mb_work mb_work;
mb_work *mb_work_new(const mb_model *md, const mb_unknowns *u);
void mb_work_free(mb_work *w);

/* The value at t of expression e (MB_OP_* program); out of a function's domain inf/nan
 * as numpy gives them. */
double mb_expression(const mb_model *md, int64_t e, double t);

/* Q - b per body, out (n x 6): [W_F; B_M - w x J w]; with the load values at t. */
void mb_net_wrench(const mb_model *md, mb_work *w, double t, const double *y, double *out);

/* Q and b apart (what Assembly shows): Q (n x 6) [W_F; B_M], b (n x 6) [0; w x J w];
 * mb_net_wrench is Q - b from the same terms. */
void mb_wrench_parts(const mb_model *md, mb_work *w, double t, const double *y, double *Q,
                     double *b);

/* Each spring-damper's state at (t, y): out (s x 6) [L, L', T, u (3)]: its length (m),
 * its rate (m/s), its tension T = k (L - L0) + c L' (N) and its direction u, world axes,
 * from end a to end b (the same numbers its wrench is made of). */
void mb_springs(const mb_model *md, mb_work *w, double t, const double *y, double *out);

/* Per component (m): child6, parent6 (m x 6), W_e (m x 3) its direction (world),
 * W_P (m x 3) its point (world), gamma, phi, gtv (G^T v - f', see above) at (t, y). */
void mb_columns(const mb_model *md, mb_work *w, double t, const double *y, double *child6,
                double *parent6, double *W_e, double *W_P, double *gamma, double *phi,
                double *gtv);

/* Status codes: 0, or 1 + 6 body + row of a motion without mass or inertia. */

/* Slots of mb_solve's info (MB_INFO of them) and of mb_project's (MB_PROJECT_INFO).
 * MB_ST_PATH: 0 Cholesky of S, 1 null-space solve, 2 pivoted Cholesky (redundant). */
enum { MB_ST_RANK = 0, MB_ST_BERR = 1, MB_ST_BROKEN = 2, MB_ST_MU = 3, MB_ST_PATH = 4,
       MB_ST_SINGULAR = 5, MB_INFO = 6 };
enum { MB_PR_STEP = 0, MB_PR_VELOCITY = 1, MB_PR_RATIO = 2, MB_PR_SINGULAR = 3,
       MB_PROJECT_INFO = 4 };

/* Accelerations and reactions at one state (what Assembly.solve returns): out as
 * mbody/solve/compiled.solve_layout: accelerations in the model's coordinates,
 * lambda (m) (known values in place), gtv (m), not-unique flags (m), info
 * [rank, backward error, broken enforced joints, mu, path, singular code]. */
void mb_solve(const mb_model *md, const mb_unknowns *u, mb_work *w, double t,
              const double *y, const double *lam, double *out);

/* The same constrained solve with the columns of G (m x 6, child and parent sides), the
 * right-hand side r6 (n x 6: Q - b + G_K lam_K) and gamma_U (mu) given, not computed
 * (an exported system's stored matrices): out [acc (n x 6) | lam_U (mu) | not-unique
 * flags (mu) | info (MB_INFO)]. */
void mb_solve_given(const mb_model *md, const mb_unknowns *u, mb_work *w, const double *r6,
                    const double *child6, const double *parent6, const double *gam,
                    double *out);

/* dy/dt at (t, y) with the unknown reactions solved (Baumgarte alpha = beta = rate when
 * rate > 0); lam: known reaction values (0 on unknown components). Returns the status. */
int mb_derivative(const mb_model *md, const mb_unknowns *u, mb_work *w, double t,
                  const double *y, const double *lam, double rate, double *ydot);

/* Move y onto the enforced joints at t, in place: `iters` Gauss-Newton position steps,
 * then the mass-orthogonal velocity projection (target G^T v = f'(t); with `homogeneous`
 * the target is G^T v = 0 and laws are ignored: the tangent space, for error estimates).
 * info[4] <- [largest position step, largest velocity change, geometric ratio at the
 * start, status]. Null-space solves below a geometric ratio of robust_below. */
void mb_project(const mb_model *md, const mb_unknowns *u, mb_work *w, double t, double *y,
                int iters, double robust_below, int homogeneous, double *info);

/* Kinematic analysis at t (mbody.solve.kinematics): y (the full state) moved, in place,
 * onto every enforced joint and driver. fast == 0: as the Python loop does it, `max_iters`
 * calls of mb_project(1 step) until a step is at most step_tol. fast == 1 (a fully driven
 * mechanism, whose velocities the constraints fix): Newton steps until every
 * |phi_i| / phi_scale[i] is at most phi_tol or a step is at most step_tol, then one
 * velocity projection. info[MB_KN_INFO] <- [steps, max |phi_i| / phi_scale[i] at the
 * end, singular code (0: none), the last step]. */
enum { MB_KN_ITERS = 0, MB_KN_ERROR = 1, MB_KN_SINGULAR = 2, MB_KN_STEP = 3, MB_KN_INFO = 4 };
void mb_kinematics(const mb_model *md, const mb_unknowns *u, mb_work *w, double t, double *y,
                   const double *phi_scale, int max_iters, double step_tol, double phi_tol,
                   double robust_below, int fast, double *info);
/* y moved along its own velocities for dt (positions by v dt, attitudes by the rotation
 * w dt in body axes, planar angles by w_z dt): a start for the Newton steps at t + dt. */
void mb_predict(const mb_model *md, double *y, double dt);

/* Slots of mb_kinematic_run's info (MB_KR_INFO of them): the last sample's last Newton
 * step, the Newton steps taken in all, the most at one sample, the singular code. */
enum { MB_KR_STEP = 0, MB_KR_NEWTON = 1, MB_KR_WORST = 2, MB_KR_SINGULAR = 3,
       MB_KR_INFO = 4 };

/* A kinematic run: for each of the K times t (increasing), y (in: a state near the first
 * sample's; out: the last sample's) is carried from the previous sample by a Taylor step,
 * moved onto every enforced joint and driver by Newton steps (mb_project, at most
 * max_newton, until the largest step is at most tol), stored in Y (K x state size) and
 * solved (mb_solve, lam: the known values) into OUT (K x mb_solve's out length), with
 * (when ENERGY is not NULL) K x 3 energy terms: the applied loads' power Q . v (gravity
 * and springs included), the springs' elastic energy and its rate. Returns
 * K, or the index of the sample where the loops did not close (a step above tol after
 * max_newton steps, a value not a number, or a motion without mass: info[MB_KR_SINGULAR];
 * -1 there: no memory for the scratch);
 * info (MB_KR_INFO) <- slots MB_KR_*. */
int64_t mb_kinematic_run(const mb_model *md, const mb_unknowns *u, mb_work *w,
                         const double *t, int64_t K, double *y, const double *lam,
                         int max_newton, double tol, double *Y, double *OUT, double *ENERGY,
                         double *info);

/* The accelerations (ACC, K x mb_solve's N: the model's coordinates) and the energy terms
 * (ENERGY, K x 3, as mb_kinematic_run's) of K sampled states, the rows of Y (stride
 * apart), with the unknown reactions solved (lam: the known values): the drivers' energy
 * check of an integrated run. Returns 0, the first singular-mass status met, or -1 (no
 * memory for the scratch). */
int mb_energy_samples(const mb_model *md, const mb_unknowns *u, mb_work *w,
                      const double *lam, int64_t K, const double *t, const double *Y,
                      int64_t stride, double *ACC, double *ENERGY);

/* ---------------------------------------------------------------------------------------
 * The progress of a long call (the linearisation of a large model): report(ctx, stage,
 * done, total) is called before each step of its loops (a column of the differences, a
 * row of the first-order system, an eigenvalue), a few thousand times for a model of a
 * thousand coordinates and a handful for a small one; a nonzero return stops the call,
 * which then returns MB_STOPPED (its output is not to be used). NULL: not reported.
 * ------------------------------------------------------------------------------------- */
typedef struct {
    int (*report)(void *ctx, int stage, int64_t done, int64_t total);
    void *ctx;
} mb_progress;
enum { MB_STAGE_GENERALIZED = 0, MB_STAGE_DAMPING = 1, MB_STAGE_STIFFNESS = 2,
       MB_STAGE_SYSTEM = 3, MB_STAGE_HESSENBERG = 4, MB_STAGE_SCHUR = 5, MB_STAGE_VECTORS = 6,
       MB_STAGES = 7 };
enum { MB_STOPPED = -2 };

/* ---------------------------------------------------------------------------------------
 * Generalized coordinates (generalized.c). A coordinate is a rate row a_k^T v, Iq
 * (nq x MB_GQ_W) [kind, index, axis, rule]:
 *   MB_GQ_TURN        joint `index`'s turn about its joint-frame axis `axis` (fixed in the
 *                     parent): the rate MB_KIND_TURN measures; value atan2 as TURN's theta
 *                     (rule 0), or a universal joint's first angle (rule 1)
 *   MB_GQ_CHILD_TURN  a turn about an axis fixed in the child: axis 0-2 its body axes (a
 *                     ball's quasi-velocities: no value), 3 the joint's axis2 (a universal
 *                     joint's second angle, rule 2)
 *   MB_GQ_SLIDE       the slide along the joint-frame axis `axis` (MB_KIND_FORCE's rate);
 *                     value e . (P - P_p)
 *   MB_GQ_BODY        body `index`'s own velocity component `axis` (0-2 world v, 3-5 body
 *                     w); value its position (planar: its angle about z for axis 5)
 * cols (nc): the velocity columns (indices into 6 n) the system lives on (planar: x, y,
 * w3 per body; a particle's rotations left out), increasing. The held components are the
 * unknowns' U; known components' values (lam) act as loads.
 * mb_generalized's out: [T (N x nq) | v_e (N) | a0 (N) | M_q (nq x nq) | f_q (nq) |
 * q (nq) | q' (nq) | f_scale (nq) | info (MB_GENERALIZED_INFO)] with N = nc, so that v = T q' + v_e and
 * v' = T q'' + a0 keep every held component (drivers' laws included) and
 * M_q q'' = f_q = T^T (Q - b + G_K lam_K - M a0). q' is the given one, or (qdot NULL)
 * A^T v of y's velocities; y's own velocities are otherwise not used.
 * f_scale: the magnitude of the terms each f_q is made of (per group of rows,
 * translations and rotations, the largest entry of T's column times the sum over the
 * group of |m g|, each load's |share|, |w| |J w|, |G_K lam_K| and |M a0|), what its
 * rounding error is relative to.
 * info: [smallest |R_kk| / largest of the scaled QR of C = [G_U^T; A^T] (0: the
 * coordinates do not determine the motion), the least-squares residual of C T = [0; I]
 * (0 on the configuration manifold)].
 * ------------------------------------------------------------------------------------- */
enum { MB_GQ_TURN = 0, MB_GQ_CHILD_TURN = 1, MB_GQ_SLIDE = 2, MB_GQ_BODY = 3,
       MB_GQ_KINDS = 4, MB_GQ_W = 4 };
enum { MB_GI_RANK = 0, MB_GI_RESIDUAL = 1, MB_GENERALIZED_INFO = 2 };

/* 0 when Iq and cols describe coordinates of this model, else -1. */
int mb_coordinates_check(const mb_model *md, int64_t nq, const int64_t *Iq, int64_t nc,
                         const int64_t *cols);
/* The coordinates' rate rows at y, rows (nq x nc) over the columns `cols`, and their values
 * (nq); returns 0, or -1 when memory ran out. */
int mb_coordinate_rows(const mb_model *md, mb_work *w, double t, const double *y, int64_t nq,
                       const int64_t *Iq, int64_t nc, const int64_t *cols, double *rows,
                       double *values);
/* See above; returns 0, or -1 when memory ran out. */
int mb_generalized(const mb_model *md, const mb_unknowns *u, mb_work *w, double t,
                   const double *y, const double *lam, int64_t nq, const int64_t *Iq,
                   int64_t nc, const int64_t *cols, const double *qdot, double *out);
/* How far each of the rows of B = D_r [G_U^T; A^T] S (S = diag(colscale), D_r scaling each
 * row to unit length) is from the span of the others, for a square B: out (r + 1) [d_i =
 * 1 / |B^-1 e_i| (0: B singular) | the pivot ratio of mb_generalized's QR (0: B not square
 * or singular)], at the band's cost per row. A lower bound on B's smallest singular value
 * is 1 / sqrt(sum 1 / d_i^2). Returns 0, or -1 when memory ran out. */
int mb_independence(const mb_model *md, const mb_unknowns *u, mb_work *w, double t,
                    const double *y, int64_t nq, const int64_t *Iq, int64_t nc,
                    const int64_t *cols, const double *colscale, double *out);
/* f_q at np perturbed states, P (np x 2 nq) rows [dq | du]: the positions of y0 moved along
 * v = T(y0) dq for a unit time (x + v, q (x) exp(w / 2)), the rates q0' + du: fout (np x
 * nq). For the linearisation's differences (its curves have the tangents T e_k). */
int mb_generalized_perturbed(const mb_model *md, const mb_unknowns *u, mb_work *w, double t,
                             const double *y0, const double *lam, int64_t nq,
                             const int64_t *Iq, int64_t nc, const int64_t *cols,
                             const double *qdot0, int64_t np, const double *P, double *fout);
/* The linearisation's differences at y0 (rates q0'): K = -df_q/dq by central differences at
 * steps h, h/2, h/4 per coordinate (h: nq) extrapolated twice (Richardson, O(h^6)), with the
 * error bound |R1 - R2| / 15 + 4 rounding fscale_i / (h_j / 4); a column whose differences
 * at h and h/2 (d0, d1) agree within that rounding term in every row stops at R1, bound
 * |d0 - d1| + the rounding term (no step h/4); with f0 (f at y0; NULL: no such test), a
 * column whose f at +-h equals f0 within 4 rounding fscale_i in every row (flat: a
 * coordinate the forces do not depend on) is its difference d0, bound |d0| + the
 * rounding term (no step h/2 either); D = -df_q/dq' by one central
 * difference at steps hu (exact for f quadratic in q'), error 4 rounding max|f| / hu.
 * A coordinate with skip[j] != 0 is known not to enter f (a free body's position without
 * springs...): its K column is 0 without evaluations.
 * out: [K | K_err | D | D_err], each nq x nq (row i: the equation, column j: the
 * coordinate), a column at a time (D's, then K's: MB_STAGE_DAMPING, MB_STAGE_STIFFNESS
 * reported before each). Returns 0, MB_STOPPED, or -1 when memory ran out. */
int mb_differences(const mb_model *md, const mb_unknowns *u, mb_work *w, double t,
                   const double *y0, const double *lam, int64_t nq, const int64_t *Iq,
                   int64_t nc, const int64_t *cols, const double *qdot0, const double *h,
                   const double *hu, const double *fscale, const double *f0, double rounding,
                   const int64_t *skip, const mb_progress *progress, double *out);
/* The linearisation about (t, y) (linearize.c): mb_generalized there, mb_differences with
 * steps params[MB_LP_STEP] x scales (positions) and the rates' scale (rates), the residual
 * q'' = M^-1 f, steadiness (every |f_i| <= params[MB_LP_STEADY] f_scale_i, and no moving
 * coordinate whose K column exceeds 10 x its error), the coordinates left out (cyclic and
 * moving, or a quasi-velocity's angle: their K columns zeroed), the first-order matrix
 * A = [[0, E], [-M^-1 K_kept, -M^-1 D]] (params[MB_LP_ROUNDING], the rounding of one
 * evaluation of f relative to f_scale, is divided by the projection's pivot ratio) and
 * the tolerance sqrt(|M^-1| (|dK| + |dD|) |A|)
 * (infinity norms; at least 1e3 eps |A|) on its eigenvalues, with |dA| = |M^-1| (|dK| +
 * |dD|) and |A| themselves (info's DA and NORM), and RESTING: q'' = 0 within params[MB_LP_STEADY]
 * of f's terms; then A's spectrum (mb_spectrum; UNCONVERGED when its QR iteration did
 * not converge), the number of eigenvalues beyond their bounds on the growing side
 * (GROWING) and the modes (mb_modes, MODES of them). out: [mb_generalized's out |
 * K | K_err | D | D_err (nq x nq each) | q'' (nq) | left out (nq, 0/1) | A (nz x nz in a
 * slot of (2 nq)^2) | info (MB_LINEARIZE_INFO) | spectrum (of nz, in a slot of
 * 6 nq + 8 nq^2) | modes (of nz, in a slot of 12 nq + 4 nq^2) | the OSCILLATIONS modes'
 * frequencies, then their damping ratios (in a slot of 4 nq)], nz = kept + nq.
 * params[MB_LP_STOP]: MB_STOP_STIFFNESS stops once K, D, q'' and the left-out flags are
 * made (info's STEADY, UNSTEADY, RESTING, KEPT and SINGULAR set: what a Newton step for an
 * equilibrium needs, without A and its O(nz^3) spectrum); MB_STOP_SYSTEM once A and its
 * info (TOL, DA, NORM) are (the caller finds the spectrum: LAPACK's, for a large A). Its
 * stages are reported (MB_STAGE_*). Returns 0, MB_STOPPED, or -1 when memory ran out. */
enum { MB_LP_STEP = 0, MB_LP_ROUNDING = 1, MB_LP_STEADY = 2, MB_LP_MOVING = 3,
       MB_LP_STOP = 4, MB_LINEARIZE_PARAMS = 5 };
enum { MB_STOP_NONE = 0, MB_STOP_STIFFNESS = 1, MB_STOP_SYSTEM = 2 };
enum { MB_LI_STEADY = 0, MB_LI_UNSTEADY = 1, MB_LI_TOL = 2, MB_LI_KEPT = 3,
       MB_LI_SINGULAR = 4, MB_LI_DA = 5, MB_LI_NORM = 6, MB_LI_RESTING = 7,
       MB_LI_GROWING = 8, MB_LI_MODES = 9, MB_LI_UNCONVERGED = 10, MB_LI_OSCILLATIONS = 11,
       MB_LINEARIZE_INFO = 12 };
int mb_linearize(const mb_model *md, const mb_unknowns *u, mb_work *w, double t,
                 const double *y, const double *lam, int64_t nq, const int64_t *Iq,
                 int64_t nc, const int64_t *cols, const double *scales, const int64_t *quasi,
                 const int64_t *skip, const double *params, const mb_progress *progress,
                 double *out);

/* spectrum.c: the eigenvalues of the real n x n matrix A (row-major), by real part then
 * imaginary part, with unit right eigenvectors (largest entry real and positive) and a
 * bound on each eigenvalue's error: kappa dA for a simple one (kappa its condition
 * number |x| |y| / |y^H x|, dA the bound on A's error), at most tol, at least
 * 1e3 eps |A|_inf (tol where kappa dA is not finite: a Jordan block). out (float64,
 * 2 n + 2 n^2 + n): [eigenvalues (n complex, interleaved re, im) | V (n x n complex,
 * row-major, column k the k-th eigenvalue's vector) | bounds (n)]. Its stages are reported
 * (MB_STAGE_HESSENBERG, MB_STAGE_SCHUR: eigenvalues found, MB_STAGE_VECTORS). Returns 0, 1
 * when the QR iteration did not converge, MB_STOPPED, or -1 when memory ran out. */
int mb_spectrum(const double *A, int64_t n, double dA, double tol,
                const mb_progress *progress, double *out);
/* The modes of a spectrum (mb_spectrum's out, n eigenvalues) of a linearisation with k
 * coordinates, nk of them kept (their indices in kept; z = (their delta q, all delta q')):
 * one of each conjugate pair, classified as neutral (|lambda| within its bound: a free or
 * cyclic motion), oscillation, growth or decay, neutral first, then by |lambda|. out
 * (MB_MODE_W n + 2 n k): [rows of MB_MODE_W | shapes (k complex each, interleaved)], the
 * first m of each used: a shape is delta q'/lambda
 * (a neutral mode's delta q if it has one, else its rate), its largest entry 1, entries
 * below 1e-14 set to 0, real when its imaginary parts are all below 1e-12. Returns m, or
 * -1 when memory ran out. */
enum { MB_MODE_INDEX = 0, MB_MODE_KIND = 1, MB_MODE_RE = 2, MB_MODE_IM = 3,
       MB_MODE_FREQUENCY = 4, MB_MODE_DAMPING = 5, MB_MODE_W = 6 };
enum { MB_MODE_NEUTRAL = 0, MB_MODE_OSCILLATION = 1, MB_MODE_GROWTH = 2, MB_MODE_DECAY = 3 };
int64_t mb_modes(int64_t n, const double *spectrum, int64_t k, int64_t nk,
                 const int64_t *kept, double *out);

#endif
