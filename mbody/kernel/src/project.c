/* The coordinate projection (mbody.simulate.mechanism's JointProjection calls it):
 * positions moved onto the enforced joints by
 * Gauss-Newton steps M D - G_U mu = 0, G_U^T D = -phi_U (the smallest move in the
 * kinetic metric), then velocities by the mass-orthogonal projection
 * M Dv - G_U mu = 0, G_U^T Dv = -(G^T v - f'). Near a singular position (geometric
 * ratio below robust_below) both solves take the null-space route. */
#include <string.h>

#include "internal.h"

/* The smallest ratio of a squared Cholesky pivot of G^^T G^ (G^ = T G_U, T = diag(1, 1/l)
 * per body) to its diagonal entry: how close the joints are to a singular position,
 * whatever the masses. A column below DROPPED_RTOL (an exactly redundant constraint) is
 * left out, as a pivoted Cholesky would. */
static double geometric_ratio(const mb_model *md, const mb_unknowns *u, mb_work *w) {
    int64_t n = md->n, mu = u->mu, W = u->bw + 1;
    double il = mb_inv_length(md, u, w->child6, w->parent6);
    memset(w->unit, 0, sizeof(double) * MB_BODY_W * n);
    for (int64_t i = 0; i < n; i++) {
        w->unit[MB_BODY_W * i + B_MASS] = 1.0;
        for (int a = 0; a < 3; a++) w->unit[MB_BODY_W * i + B_JINV + 4 * a] = il * il;
    }
    memset(w->Sb, 0, sizeof(double) * mu * W);
    mb_schur(md, u, w->unit, w->child6, w->parent6, w->Sb, 1);
    /* a redundant mechanism (generic_rank < mu): its redundant columns' pivots are the
     * squared distance off the manifold, up to MB_GENERIC_GAP^2: left out too */
    double drop = u->generic_rank < mu ? MB_GENERIC_GAP * MB_GENERIC_GAP : DROPPED_RTOL;
    return mb_band_cholesky(w->Sb, mu, u->bw, drop, 0);
}

/* The solve of one projection step (w->gam set, w->r6 and w->stab 0). */
static int project_solve(const mb_model *md, const mb_unknowns *u, mb_work *w, int robust) {
    int64_t rank;
    double berr;
    int path;
    if (robust) return mb_null_space(md, u, w, 1, &rank);
    return mb_constrained(md, u, w, 1, &rank, &berr, &path);
}

/* x += d (positions), q <- q (x) (1, d_theta / 2) renormalised, planar theta += d_z:
 * one step d (n x 6: world translation, body-axes rotation) applied to y. */
static void move(const mb_model *md, double *y, const double *d) {
    int64_t n = md->n;
    double *x = y, *q = y + 3 * n;
    for (int64_t i = 0; i < n; i++) {
        for (int a = 0; a < 3; a++) x[3 * i + a] += d[6 * i + a];
        double p0 = 0.5 * d[6 * i + 3], p1 = 0.5 * d[6 * i + 4], p2 = 0.5 * d[6 * i + 5];
        double *qi = q + 4 * i;
        double qw = qi[0], qx = qi[1], qy = qi[2], qz = qi[3];
        double nw = qw - qx * p0 - qy * p1 - qz * p2;
        double nx = qx + qw * p0 + qy * p2 - qz * p1;
        double ny = qy + qw * p1 + qz * p0 - qx * p2;
        double nz = qz + qw * p2 + qx * p1 - qy * p0;
        double s = 1.0 / sqrt(nw * nw + nx * nx + ny * ny + nz * nz);
        qi[0] = nw * s, qi[1] = nx * s, qi[2] = ny * s, qi[3] = nz * s;
        if (md->planar) y[13 * n + i] += d[6 * i + 5];
    }
}

void mb_project(const mb_model *md, const mb_unknowns *u, mb_work *w, double t, double *y,
                int iters, double robust_below, int homogeneous, double *info) {
    int64_t n = md->n, mu = u->mu;
    double *q = y + 3 * n, *v = y + 7 * n, *om = y + 10 * n;
    info[MB_PR_STEP] = 0.0, info[MB_PR_VELOCITY] = 0.0, info[MB_PR_RATIO] = 1.0;
    info[MB_PR_SINGULAR] = 0.0;
    if (mu == 0) return;
    int laws = !homogeneous;
    if (laws) mb_eval_all(md, w, t);
    memset(w->r6, 0, sizeof(double) * 6 * n);
    memset(w->stab, 0, sizeof(double) * mu);
    double *d = w->acc;
    int robust = 0;
    for (int it = 0; it <= iters; it++) {
        mb_rotations(n, q, w->R);
        mb_columns_at(md, w, y, laws, w->child6, w->parent6, NULL, NULL, w->gamma, w->phi,
                      w->gtv);
        if (it == 0) {
            info[MB_PR_RATIO] = geometric_ratio(md, u, w);
            robust = info[MB_PR_RATIO] < robust_below;
        }
        if (it == iters) break;
        for (int64_t k = 0; k < mu; k++) w->gam[k] = -w->phi[u->U[k]];
        int singular = project_solve(md, u, w, robust);
        if (singular) {
            info[MB_PR_SINGULAR] = singular;
            return;
        }
        double step = 0.0;
        for (int64_t i = 0; i < 6 * n; i++) step = fmax(step, fabs(d[i]));
        if (step == 0.0) break;
        info[MB_PR_STEP] = fmax(info[MB_PR_STEP], step);
        if (md->planar) /* the in-plane rows only (the others are 0 up to rounding) */
            for (int64_t i = 0; i < n; i++) d[6 * i + 2] = d[6 * i + 3] = d[6 * i + 4] = 0.0;
        move(md, y, d);
        if (step < 1e-15) break;
    }
    for (int64_t k = 0; k < mu; k++) w->gam[k] = -w->gtv[u->U[k]];
    int singular = project_solve(md, u, w, robust);
    if (singular) {
        info[MB_PR_SINGULAR] = singular;
        return;
    }
    for (int64_t i = 0; i < n; i++) {
        for (int a = 0; a < 3; a++) {
            v[3 * i + a] += d[6 * i + a];
            om[3 * i + a] += d[6 * i + 3 + a];
            info[MB_PR_VELOCITY] = fmax(info[MB_PR_VELOCITY],
                                        fmax(fabs(d[6 * i + a]), fabs(d[6 * i + 3 + a])));
        }
        if (md->planar) {
            v[3 * i + 2] = 0.0;
            om[3 * i] = 0.0;
            om[3 * i + 1] = 0.0;
        }
    }
}

void mb_predict(const mb_model *md, double *y, double dt) {
    int64_t n = md->n;
    const double *v = y + 7 * n, *om = y + 10 * n;
    double d[6];
    for (int64_t i = 0; i < n; i++) {
        double *x = y + 3 * i, *qi = y + 3 * n + 4 * i;
        for (int a = 0; a < 3; a++) {
            d[a] = v[3 * i + a] * dt;
            d[3 + a] = om[3 * i + a] * dt;
        }
        for (int a = 0; a < 3; a++) x[a] += d[a];
        /* the exact rotation by w dt (body axes) rather than move()'s first-order one */
        mb_turn_exact(qi, d + 3);
        if (md->planar) y[13 * n + i] += d[5];
    }
}

/* max_i |phi_i| / phi_scale[i] over the enforced components (w->phi at hand). */
static double phi_error(const mb_unknowns *u, const mb_work *w, const double *phi_scale) {
    double err = 0.0;
    for (int64_t k = 0; k < u->mu; k++) {
        int64_t i = u->U[k];
        double e = fabs(w->phi[i]) / phi_scale[i];
        if (!(e <= err)) err = e; /* a NaN stays */
    }
    return err;
}

void mb_kinematics(const mb_model *md, const mb_unknowns *u, mb_work *w, double t, double *y,
                   const double *phi_scale, int max_iters, double step_tol, double phi_tol,
                   double robust_below, int fast, double *info) {
    int64_t n = md->n, mu = u->mu;
    double pinfo[MB_PROJECT_INFO];
    info[MB_KN_ITERS] = 0.0, info[MB_KN_ERROR] = 0.0, info[MB_KN_SINGULAR] = 0.0;
    info[MB_KN_STEP] = 0.0;
    if (mu == 0) return;
    if (!fast) {
        for (int it = 0; it < max_iters; it++) {
            mb_project(md, u, w, t, y, 1, robust_below, 0, pinfo);
            info[MB_KN_ITERS] = it + 1;
            info[MB_KN_STEP] = pinfo[MB_PR_STEP];
            if (pinfo[MB_PR_SINGULAR]) {
                info[MB_KN_SINGULAR] = pinfo[MB_PR_SINGULAR];
                return;
            }
            if (pinfo[MB_PR_STEP] <= step_tol) break;
        }
        /* w->phi: at the last position (project computes it after its step) */
        info[MB_KN_ERROR] = phi_error(u, w, phi_scale);
        return;
    }
    mb_eval_all(md, w, t);
    memset(w->r6, 0, sizeof(double) * 6 * n);
    memset(w->stab, 0, sizeof(double) * mu);
    double *d = w->acc;
    int robust = 0;
    for (int it = 0;; it++) {
        mb_rotations(n, y + 3 * n, w->R);
        mb_columns_at(md, w, y, 1, w->child6, w->parent6, NULL, NULL, w->gamma, w->phi,
                      w->gtv);
        if (it == 0) robust = geometric_ratio(md, u, w) < robust_below;
        double err = phi_error(u, w, phi_scale);
        info[MB_KN_ERROR] = err;
        if (err <= phi_tol || it == max_iters) break;
        if (it > 0 && info[MB_KN_STEP] <= step_tol) break;
        for (int64_t k = 0; k < mu; k++) w->gam[k] = -w->phi[u->U[k]];
        int singular = project_solve(md, u, w, robust);
        if (singular) {
            info[MB_KN_SINGULAR] = singular;
            return;
        }
        double step = 0.0;
        for (int64_t i = 0; i < 6 * n; i++) step = fmax(step, fabs(d[i]));
        info[MB_KN_ITERS] = it + 1;
        info[MB_KN_STEP] = step;
        if (md->planar)
            for (int64_t i = 0; i < n; i++) d[6 * i + 2] = d[6 * i + 3] = d[6 * i + 4] = 0.0;
        move(md, y, d);
    }
    /* velocities: the mass-orthogonal projection onto G^T v = f' at the final position
     * (w->gtv computed there with the last columns) */
    for (int64_t k = 0; k < mu; k++) w->gam[k] = -w->gtv[u->U[k]];
    int singular = project_solve(md, u, w, robust);
    if (singular) {
        info[MB_KN_SINGULAR] = singular;
        return;
    }
    double *v = y + 7 * n, *om = y + 10 * n;
    for (int64_t i = 0; i < n; i++) {
        for (int a = 0; a < 3; a++) {
            v[3 * i + a] += d[6 * i + a];
            om[3 * i + a] += d[6 * i + 3 + a];
        }
        if (md->planar) {
            v[3 * i + 2] = 0.0;
            om[3 * i] = 0.0;
            om[3 * i + 1] = 0.0;
        }
    }
}
