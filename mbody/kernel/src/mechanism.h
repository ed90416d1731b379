/* A simulation's problem as the integrator's callbacks (dop853.h's mb_ode): the core's
 * right-hand side (mb_derivative: the unknown reactions solved at every evaluation,
 * Baumgarte's terms when rate > 0) and, for a mechanism held by projection
 * (mbody.simulate.mechanism), the coordinate projection after every accepted step
 * (mb_project), the stage projection of filtered steps and the part of an error estimate
 * along the joints. With these bound in C a whole run steps without Python.
 *
 * The callbacks' ctx is an mb_mechanism. Its params (MB_MECH_PARAMS of them, written by
 * mbody.simulate.stepping) and the known reaction values lam (m; 0 on the unknown
 * components, those varying in t set by the core) are read at every call.
 */
#ifndef MBODY_MECHANISM_H
#define MBODY_MECHANISM_H

#include "dop853.h"
#include "kernel.h"

/* Slots of the params: Baumgarte's alpha = beta (1/s; 0: none), the geometric ratio below
 * which the next step is filtered and the projections take the null-space route, the
 * Gauss-Newton iterations of the projection after a step and of a stage's projection. */
enum { MB_MECH_RATE = 0, MB_MECH_ROBUST = 1, MB_MECH_ITERS = 2, MB_MECH_STAGE_ITERS = 3,
       MB_MECH_PARAMS = 4 };

typedef struct {
    const mb_model *md;
    const mb_unknowns *u;
    mb_work *w;
    const double *params; /* MB_MECH_PARAMS */
    const double *lam;    /* m */
    double *scratch;      /* MB_STATE_SIZE + n doubles (mb_mechanism_scratch) */
} mb_mechanism;

/* Doubles of scratch the tangent callback needs. */
int64_t mb_mechanism_scratch(const mb_model *md);

/* y' = mb_derivative(t, y); returns its singular-mass code (0: fine). */
int mb_mechanism_rhs(void *ctx, double t, const double *y, double *ydot);

/* After each accepted step: y moved onto the joints at t (MB_MECH_ITERS Gauss-Newton
 * steps, then the velocities); info <- [the largest position step or velocity change,
 * 1 if the geometric ratio is below MB_MECH_ROBUST (the next step is filtered), the
 * ratio, 0]. Returns the singular-mass code. */
int mb_mechanism_project(void *ctx, double t, double *y, double *info);

/* A filtered step's stage state moved onto the joints (MB_MECH_STAGE_ITERS steps). */
int mb_mechanism_stage(void *ctx, double t, double *y);

/* e (an error estimate in y's layout, at the step's start y) <- its part along the
 * joints: its velocity block and its position block (dx, and the body rotation
 * 2 vec(conj(q) (x) dq) of the quaternion block) each projected mass-orthogonally onto
 * the motions the joints allow at y (the tangent space: G^T dv = 0, laws left out); the
 * quaternion's radial part (its norm) kept. What the projection after the step removes
 * whatever its size should not shrink the step: near a singular position it is
 * rounding noise amplified by the small singular values. */
int mb_mechanism_tangent(void *ctx, double t, const double *y, double *e);

/* A run's figures at its K output samples, in one pass: the states are the rows of Y
 * (`stride` doubles apart, MB_STATE_SIZE or 13 n used) at the times t. With reactions
 * (K x m) not NULL: every reaction value (mb_solve: the unknown components solved with
 * the exact gamma, the others at lam, those varying in t at t); with lengths (K x s) not
 * NULL: each spring's length; drift[2] <- the largest |phi| and |G^T v - f'| over every
 * component and sample. Returns 0, or -1 out of memory. */
int mb_samples(const mb_model *md, const mb_unknowns *u, mb_work *w, const double *lam,
               int64_t K, const double *t, const double *Y, int64_t stride,
               double *reactions, double *lengths, double *drift);

/* A run's K stored samples (the rows of Y, `stride` doubles apart: the core's layout)
 * finished in place: each quaternion divided by its norm, and with `planar` each carried
 * angle theta set to its quaternion's own angle 2 atan2(q_z, q_w) on theta's branch (the
 * turns a quaternion cannot count kept; mbody.simulate.trajectory.keep_planar_angles).
 * Returns the largest |norm - 1| before (NaN if a norm is). */
double mb_unit_samples(int64_t n, int planar, int64_t K, double *Y, int64_t stride);

/* What a run conserves, at its K samples (the rows of Y, `stride` doubles apart: the core's
 * layout; a planar model's spatial form: x, v with z = 0, q from the carried angle, w
 * about z alone): T[k] = sum of 1/2 m v.v + 1/2 w.J w; V[k] = -sum m x.g + sum of
 * 1/2 k (L - L0)^2 over the s springs (their lengths: lengths, K x s); H[k] (3) the
 * angular momentum, kind 1: the spins sum W_R_B J w alone, kind 0: with the orbital terms
 * x x m v about the world origin, kind 2: about the system's mass centre (x and v relative
 * to its position and velocity). figures (6): the largest relative changes of E = T + V
 * (over max(|E(0)|, max T)), of p = sum m v and of H (each over the largest sum of its
 * terms' magnitudes), 0 where that scale is 0; figures[3 ..] (3) <- p at the first
 * sample; spin_peak (n) <- each body's largest |w| over the samples (planar: |w_z|). mass (n),
 * J (n x 9, body axes), gravity (3), stiffness and rest (s). Returns 0, or -1 out of
 * memory. */
int mb_conservation(int64_t n, int planar, const double *mass, const double *J,
                    const double *gravity, int64_t s, const double *stiffness,
                    const double *rest, const double *lengths, int64_t K, const double *Y,
                    int64_t stride, int kind, double *T, double *V, double *H,
                    double *figures, double *spin_peak);

#endif
