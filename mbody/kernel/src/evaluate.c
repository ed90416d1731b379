/* The entry points that evaluate a mechanism at one state with its unknown reactions
 * solved: mb_solve (what Assembly.solve returns) and mb_derivative (the simulation's
 * right-hand side, Baumgarte-stabilised). */
#include <string.h>

#include "internal.h"

/* Loads, columns and the constrained solve at (t, y) into w; lam: the known values
 * (0 on unknown components), completed at t into w->lam. Returns the singular code. */
static int evaluate(const mb_model *md, const mb_unknowns *u, mb_work *w, double t,
                    const double *y, const double *lam, double rate, int refine,
                    int64_t *rank, double *berr, int *path) {
    int64_t n = md->n, m = md->m;
    mb_rotations(n, y + 3 * n, w->R);
    mb_eval_all(md, w, t);
    mb_loads_at(md, w);
    mb_net_wrench_at(md, w, y, w->r6);
    mb_columns_at(md, w, y, 1, w->child6, w->parent6, NULL, NULL, w->gamma, w->phi, w->gtv);
    mb_known_at(md, w, lam, w->lam);
    for (int64_t i = 0; i < m; i++) { /* known reactions: r6 += G_K lam_K */
        double li = w->lam[i];
        if (li == 0.0) continue;
        int64_t j = md->comps_i[4 * i];
        int64_t p = md->joints_i[3 * j], c = md->joints_i[3 * j + 1];
        for (int r = 0; r < 6; r++) w->r6[6 * c + r] += w->child6[6 * i + r] * li;
        if (p >= 0)
            for (int r = 0; r < 6; r++) w->r6[6 * p + r] += w->parent6[6 * i + r] * li;
    }
    for (int64_t k = 0; k < u->mu; k++) {
        int64_t i = u->U[k];
        w->stab[k] = -2.0 * rate * w->gtv[i] - rate * rate * w->phi[i];
        w->gam[k] = w->gamma[i] + w->stab[k];
    }
    return mb_constrained(md, u, w, refine, rank, berr, path);
}

/* fmax and fmin as the broken-joint check needs them (a NaN loses), inline: the libm
 * calls were a fortieth of a small model's solve. */
static inline double larger(double a, double b) { return a > b || b != b ? a : b; }
static inline double smaller(double a, double b) { return a < b || b != b ? a : b; }

void mb_solve(const mb_model *md, const mb_unknowns *u, mb_work *w, double t,
              const double *y, const double *lam, double *out) {
    int64_t n = md->n, m = md->m, mu = u->mu;
    int64_t rank;
    double berr;
    int path;
    int singular = evaluate(md, u, w, t, y, lam, 0.0, 1, &rank, &berr, &path);
    const double *acc = w->acc, *x = y, *v = y + 7 * n, *om = y + 10 * n;
    int64_t N = (md->planar ? 3 : 6) * n;
    for (int64_t i = 0; i < n; i++) {
        if (md->planar) {
            out[3 * i] = acc[6 * i], out[3 * i + 1] = acc[6 * i + 1], out[3 * i + 2] = acc[6 * i + 5];
        } else {
            for (int r = 0; r < 6; r++) out[6 * i + r] = acc[6 * i + r];
        }
    }
    for (int64_t i = 0; i < m; i++) {
        out[N + i] = w->lam[i];
        out[N + m + i] = w->gtv[i];
        out[N + 2 * m + i] = 0.0;
    }
    for (int64_t k = 0; k < mu; k++) {
        out[N + u->U[k]] = w->lamU[k];
        out[N + 2 * m + u->U[k]] = w->nonunique[k] ? 1.0 : 0.0;
    }
    /* broken-joint check on the enforced (unknown) components
     * (mbody.equations.constraints.joint_errors) */
    double size = 0.0;
    if (n > 1)
        for (int a = 0; a < 3; a++) {
            double lo = x[a], hi = x[a];
            for (int64_t i = 0; i < n; i++) {
                lo = smaller(lo, x[3 * i + a]);
                hi = larger(hi, x[3 * i + a]);
            }
            size = larger(size, hi - lo);
        }
    for (int64_t i = 0; i < m; i++) {
        const double *row = md->joints + MB_JOINT_W * md->comps_i[4 * i];
        for (int a = 0; a < 3; a++) size = larger(size, fabs(row[J_BRC + a]));
    }
    size = larger(size, 1e-3);
    double speed = 1e-3;
    for (int64_t i = 0; i < 3 * n; i++) speed = larger(speed, larger(fabs(v[i]), fabs(om[i])));
    int64_t broken = 0;
    for (int64_t k = 0; k < mu; k++) {
        int64_t i = u->U[k];
        if (fabs(w->phi[i]) > JOINT_TOL * size || fabs(w->gtv[i]) > JOINT_TOL * speed) broken++;
    }
    double *info = out + N + 3 * m;
    info[MB_ST_RANK] = (double)rank;
    info[MB_ST_BERR] = berr;
    info[MB_ST_BROKEN] = (double)broken;
    info[MB_ST_MU] = (double)mu;
    info[MB_ST_PATH] = (double)path;
    info[MB_ST_SINGULAR] = (double)singular;
}

int mb_derivative(const mb_model *md, const mb_unknowns *u, mb_work *w, double t,
                  const double *y, const double *lam, double rate, double *ydot) {
    int64_t n = md->n, rank;
    int path;
    /* no backward error asked for: the solve skips its residual (mb_constrained) */
    int singular = evaluate(md, u, w, t, y, lam, rate, 0, &rank, NULL, &path);
    if (singular) return singular;
    const double *acc = w->acc, *q = y + 3 * n, *v = y + 7 * n, *om = y + 10 * n;
    for (int64_t i = 0; i < n; i++) {
        for (int a = 0; a < 3; a++) {
            ydot[3 * i + a] = v[3 * i + a];
            ydot[7 * n + 3 * i + a] = acc[6 * i + a];
            ydot[10 * n + 3 * i + a] = acc[6 * i + 3 + a];
        }
        /* q' = 1/2 q (x) (0, w) */
        double qw = q[4 * i], qx = q[4 * i + 1], qy = q[4 * i + 2], qz = q[4 * i + 3];
        double p = om[3 * i], r = om[3 * i + 1], s = om[3 * i + 2];
        double *o = ydot + 3 * n + 4 * i;
        o[0] = 0.5 * (-qx * p - qy * r - qz * s);
        o[1] = 0.5 * (qw * p + qy * s - qz * r);
        o[2] = 0.5 * (qw * r + qz * p - qx * s);
        o[3] = 0.5 * (qw * s + qx * r - qy * p);
    }
    if (md->planar) /* out-of-plane rows are identically zero; theta' = w_z */
        for (int64_t i = 0; i < n; i++) {
            ydot[7 * n + 3 * i + 2] = 0.0;
            ydot[10 * n + 3 * i] = 0.0;
            ydot[10 * n + 3 * i + 1] = 0.0;
            ydot[13 * n + i] = om[3 * i + 2];
        }
    return 0;
}

void mb_solve_given(const mb_model *md, const mb_unknowns *u, mb_work *w, const double *r6,
                    const double *child6, const double *parent6, const double *gam,
                    double *out) {
    int64_t n = md->n, m = md->m, mu = u->mu;
    memcpy(w->r6, r6, sizeof(double) * 6 * n);
    memcpy(w->child6, child6, sizeof(double) * 6 * m);
    memcpy(w->parent6, parent6, sizeof(double) * 6 * m);
    for (int64_t k = 0; k < mu; k++) {
        w->gam[k] = gam[k];
        w->stab[k] = 0.0;
    }
    int64_t rank;
    double berr;
    int path;
    int singular = mb_constrained(md, u, w, 1, &rank, &berr, &path);
    memcpy(out, w->acc, sizeof(double) * 6 * n);
    for (int64_t k = 0; k < mu; k++) {
        out[6 * n + k] = w->lamU[k];
        out[6 * n + mu + k] = w->nonunique[k] ? 1.0 : 0.0;
    }
    double *info = out + 6 * n + 2 * mu;
    info[MB_ST_RANK] = (double)rank;
    info[MB_ST_BERR] = berr;
    info[MB_ST_BROKEN] = 0.0;
    info[MB_ST_MU] = (double)mu;
    info[MB_ST_PATH] = (double)path;
    info[MB_ST_SINGULAR] = (double)singular;
}
