/* DOP853: the explicit Runge-Kutta method of order 8 of Dormand and Prince, with its
 * embedded error estimators of orders 5 and 3, its step-size control and its dense output
 * of order 7; written from E. Hairer, S. P. Norsett and G. Wanner, Solving Ordinary
 * Differential Equations I, Nonstiff Problems, 2nd ed., Springer 1993: the method and its
 * tableau (section II.10 and the authors' published code dop853.f), the step-size control
 * and the initial step (section II.4).
 *
 * One step from (t, y) with f = y'(t) and step h:
 *   k_1 = f,  k_s = f(t + c_s h, y + h sum_{j<s} a_sj k_j)   (s = 2 .. 12, c_12 = 1),
 *   y_new = y + h sum_s b_s k_s,                             k_13 = f(t + h, y_new),
 *   e5 = sum_s er_s k_s,   e3 = sum_s (b_s - bhh_s) k_s      (orders 5 and 3),
 *   err = |h| |e5|^2 / sqrt(n (|e5|^2 + 0.01 |e3|^2)),  |.|^2 = sum_i (./sc_i)^2,
 *   sc_i = atol_i + rtol max(|y_i|, |y_new_i|).
 * The step is accepted when err < 1; either way the next step is h times
 *   min(fac_max, max(fac_min, safety err^(-1/8)))   (fac_max for err = 0),
 * with no growth right after a rejection, and never longer than max_step nor past t_bound.
 * A step shorter than 10 units in the last place of t stops the run (MB_DOP_TOO_SMALL).
 * The defaults safety 0.9, fac_min 0.2, fac_max 10 and the acceptance err < 1 are those of
 * scipy.integrate.DOP853, whose accepted steps these then are, step for step
 * (tests/test_dop853.py); dop853.f's own defaults are 0.9, 1/3, 6 and err <= 1.
 *
 * Mechanisms held by projection (mbody.simulate): an optional `project` callback moves y
 * after every accepted step; when it moved y by more than `refresh` times atol (or the
 * step was a filtered one, below), f(t, y) is evaluated again for the next step. The
 * callback also says whether the next step is *filtered*: each evaluation of that step
 * (and of its dense output) is made at the `stage` callback's projection of a copy of
 * its state, and the error estimates e5, e3 pass through the `tangent` callback (their
 * part along the constraints) before their norms are taken.
 *
 * All the state of a run lives in two caller-owned arrays: `state` (MB_DOP_STATE_SIZE
 * slots: settings, time, step, counters, status) and `work` (mb_dop853_work_size(n)
 * doubles: y, f, the last step's stages and dense output, scratch); the caller may read
 * y and f there between calls (offsets MB_DOP_W_*, in units of n).
 */
#ifndef MBODY_DOP853_H
#define MBODY_DOP853_H

#include <stdint.h>

/* y' = f(t, y) into ydot; a nonzero return stops the run with that code. */
typedef int (*mb_rhs_fn)(void *ctx, double t, const double *y, double *ydot);
/* After each accepted step: may move y (in place); fills info[MB_DOP_PROJECT_INFO]:
 * [0] the size of the move (compared with refresh * atol), [1] nonzero: filter the next
 * step, [2], [3] the caller's own figures (kept in state[MB_DOP_INFO ..]). */
typedef int (*mb_project_fn)(void *ctx, double t, double *y, double *info);
/* In filtered steps: the state a stage is evaluated at, moved in place (a copy). */
typedef int (*mb_stage_fn)(void *ctx, double t, double *y);
/* In filtered steps: e (an error estimate, unscaled) mapped in place, at the step's start
 * (t, y). */
typedef int (*mb_tangent_fn)(void *ctx, double t, const double *y, double *e);

typedef struct {
    int64_t n;              /* size of y */
    mb_rhs_fn rhs;          /* required */
    mb_project_fn project;  /* optional (NULL) */
    mb_stage_fn stage;      /* optional: filtered steps' stage states */
    mb_tangent_fn tangent;  /* optional: filtered steps' error estimates */
    void *ctx;              /* handed to every callback */
    const double *atol;     /* n absolute tolerances, or NULL: state[MB_DOP_ATOL] for all */
    double (*clock)(void);  /* optional: a monotonic clock in seconds (mb_dop853_sampled's
                             * MB_DOP_RETURN_AFTER) */
} mb_ode;

/* Slots of `state`. The caller writes the settings (mb_dop853_settings writes them with
 * the defaults) and MB_DOP_FILTER_NEXT (whether the first step is filtered; 0 usually),
 * then calls mb_dop853_start. */
enum {
    /* settings */
    MB_DOP_RTOL, MB_DOP_ATOL, MB_DOP_MAX_STEP, MB_DOP_T_BOUND, MB_DOP_SAFETY, MB_DOP_FAC_MIN,
    MB_DOP_FAC_MAX, MB_DOP_REFRESH,
    /* the run */
    MB_DOP_T,           /* time of y */
    MB_DOP_H,           /* |h| proposed for the next step */
    MB_DOP_DIRECTION,   /* +1 or -1 */
    MB_DOP_T_OLD,       /* start of the last accepted step */
    MB_DOP_H_OLD,       /* its (signed) size: t = t_old + h_old */
    MB_DOP_STATUS,      /* MB_DOP_RUNNING, _FINISHED, _TOO_SMALL, _STOPPED */
    MB_DOP_CODE,        /* the callback's nonzero return that stopped the run */
    MB_DOP_STEPS,       /* accepted steps */
    MB_DOP_REJECTED,    /* rejected attempts */
    MB_DOP_NFEV,        /* evaluations of rhs */
    MB_DOP_REFRESHED,   /* of which fresh f after a projection */
    MB_DOP_FILTER,      /* whether the last accepted step was filtered */
    MB_DOP_FILTER_NEXT, /* whether the next one is */
    MB_DOP_DENSE,       /* whether the last step's dense output is prepared */
    MB_DOP_DENSE_NFEV,  /* evaluations of rhs made for dense output (part of NFEV) */
    MB_DOP_WALL,        /* seconds spent in the binding's calls of _start and _sampled */
    MB_DOP_MARK_WIDTH,  /* the marks' window (mb_dop853_sampled; 0: no marks) */
    MB_DOP_MARK_NEXT,   /* the next mark's time (the caller sets the first) */
    MB_DOP_RETURN_AFTER, /* mb_dop853_sampled returns after the first step past this many
                          * seconds of its call (by p->clock; 0: no limit) */
    MB_DOP_INFO,        /* the last projection's info (MB_DOP_PROJECT_INFO slots) */
    MB_DOP_STATE_SIZE = MB_DOP_INFO + 4
};
enum { MB_DOP_PROJECT_INFO = 4 };
enum { MB_DOP_RUNNING = 0, MB_DOP_FINISHED = 1, MB_DOP_TOO_SMALL = 2, MB_DOP_STOPPED = 3 };

/* Rows (of n doubles) of `work`: y, f = y'(t, y) (the next step's first stage), the last
 * step's start y_old, its stages k_1 .. k_13 (k_13 = f(t, y_new) before any projection)
 * and the dense output's k_14 .. k_16, the dense output's 7 coefficient rows, scratch. */
enum { MB_DOP_W_Y = 0, MB_DOP_W_F = 1, MB_DOP_W_Y_OLD = 2, MB_DOP_W_K = 3,
       MB_DOP_W_DENSE = 19, MB_DOP_W_Y_NEW = 26, MB_DOP_W_Z = 27, MB_DOP_W_E5 = 28,
       MB_DOP_W_E3 = 29, MB_DOP_W_S = 30, MB_DOP_W_ROWS = 31 };

int64_t mb_dop853_work_size(int64_t n);

/* The settings with the defaults (safety 0.9, fac_min 0.2, fac_max 10, refresh 0). */
void mb_dop853_settings(double *state, double rtol, double atol, double max_step,
                        double t_bound);

/* Starts a run at (t0, y0): f(t0, y0), and the first step: first_step > 0 as given,
 * else HNW's initial step (II.4; one more evaluation). Returns the status. */
int mb_dop853_start(const mb_ode *p, double t0, const double *y0, double first_step,
                    double *state, double *work);

/* Steps until the first accepted step that reaches t_stop (in the direction of the run),
 * or max_steps accepted steps, or t_bound, or a failure. Returns the status
 * (MB_DOP_RUNNING when stopped by t_stop or max_steps). */
int mb_dop853_run(const mb_ode *p, double t_stop, int64_t max_steps, double *state,
                  double *work);

/* The dense output of the last accepted step at m times inside it (out: m rows of n),
 * its three extra stages evaluated on the first call after the step. Returns 0, -1
 * without a step to interpolate, or MB_DOP_STOPPED when a callback stopped it (its code
 * in state[MB_DOP_CODE]). */
int mb_dop853_dense(const mb_ode *p, const double *t, int64_t m, double *out,
                    double *state, double *work);

/* Steps as mb_dop853_run (until the first that reaches t_stop, max_steps of them, t_bound
 * or a failure), and after each accepted step the dense output at the sample times
 * t_eval[*k], t_eval[*k + 1], ... (of m, increasing in the run's direction) that the step
 * reached, into the rows *k, *k + 1, ... of out (m rows of n); with project_samples each
 * such row is then moved by the project callback at its time (its info discarded). *k
 * advances past the rows written.
 *
 * Marks (marks not NULL, state[MB_DOP_MARK_WIDTH] = w > 0): after each accepted step
 * that reaches state[MB_DOP_MARK_NEXT] or t_bound, the row (t, accepted steps) is written
 * to marks[2 * *count ..] and *count advances; the next mark is then at
 * (floor(t / w) + 1) w. The run returns when *count reaches marks_cap. These are the
 * points at which a caller stepping window by window (t_stop at each window's end) would
 * have been called back, without the round trips (mbody.simulate's step-rate windows).
 * With state[MB_DOP_RETURN_AFTER] = s > 0 and a clock in p, the call also returns after
 * the first accepted step that ends s seconds or more after the call began: a caller
 * that looks at its budgets and progress between calls does so at a steady pace, however
 * cheap or dear a step is.
 * Returns the status, as mb_dop853_run. */
int mb_dop853_sampled(const mb_ode *p, double t_stop, int64_t max_steps, const double *t_eval,
                      int64_t m, int64_t *k, double *out, int project_samples, double *state,
                      double *work, double *marks, int64_t marks_cap, int64_t *count);

/* The tableau as data (for tests): c (16), a (16 x 16, row s: stage s's weights), b (12),
 * e5, e3 (13), d (4 x 16). */
void mb_dop853_tableau(double *c, double *a, double *b, double *e5, double *e3, double *d);

#endif
