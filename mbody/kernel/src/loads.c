/* Applied loads: gravity, point forces and couples, spring-dampers, and the gyroscopic
 * term, summed per body as Q - b = [W_F (world); B_M - w x J w (body axes)]. Each load's
 * and each spring end's own wrench comes from one function (load_wrench, spring_wrench),
 * which both the sum and the free-body listing (mb_load_wrenches_at) use. */
#include "internal.h"

/* Point load j's wrench on its body: W (world force), M (moment about G, body axes).
 * Returns 1 for a force, 0 for a couple (W is then 0). */
static int load_wrench(const mb_model *md, const mb_work *w, int64_t j, double *W, double *M) {
    const int64_t *li = md->loads_i + 3 * j;
    const double *Rb = w->R + 9 * li[0];
    const double *f = w->loads + 3 * j;
    double B[3];
    if (li[1]) { /* body-axis components: the world force is R f */
        for (int a = 0; a < 3; a++) W[a] = Rb[3 * a] * f[0] + Rb[3 * a + 1] * f[1] + Rb[3 * a + 2] * f[2];
        B[0] = f[0], B[1] = f[1], B[2] = f[2];
    } else {
        W[0] = f[0], W[1] = f[1], W[2] = f[2];
        for (int a = 0; a < 3; a++) B[a] = Rb[a] * f[0] + Rb[3 + a] * f[1] + Rb[6 + a] * f[2];
    }
    if (li[2]) {
        M[0] = B[0], M[1] = B[1], M[2] = B[2];
        W[0] = W[1] = W[2] = 0.0;
        return 0;
    }
    mb_cross(md->loads + MB_LOAD_W * j + L_BR, B, M);
    return 1;
}

/* Spring j's state: its length L, rate L', tension T = k (L - L0) + c L' and direction
 * u = (P_b - P_a) / L (0 when the ends meet): out [L, L', T, u (3)]. */
static void spring_state(const mb_model *md, const mb_work *w, int64_t j, const double *y,
                         double *out) {
    int64_t n = md->n;
    const double *x = y, *v = y + 7 * n, *om = y + 10 * n;
    const double *row = md->springs + MB_SPRING_W * j;
    double Pa[3], Va[3], Pb[3], Vb[3];
    mb_body_point(md->springs_i[2 * j], row + S_RA, x, w->R, v, om, Pa, Va);
    mb_body_point(md->springs_i[2 * j + 1], row + S_RB, x, w->R, v, om, Pb, Vb);
    double d0 = Pb[0] - Pa[0], d1 = Pb[1] - Pa[1], d2 = Pb[2] - Pa[2];
    double L = sqrt(d0 * d0 + d1 * d1 + d2 * d2);
    double u0 = 0.0, u1 = 0.0, u2 = 0.0;
    if (L > 1e-12) u0 = d0 / L, u1 = d1 / L, u2 = d2 / L;
    double Ldot = u0 * (Vb[0] - Va[0]) + u1 * (Vb[1] - Va[1]) + u2 * (Vb[2] - Va[2]);
    out[0] = L;
    out[1] = Ldot;
    out[2] = row[S_STIFF] * (L - row[S_REST]) + row[S_DAMP] * Ldot;
    out[3] = u0, out[4] = u1, out[5] = u2;
}

/* Spring j: T = k (L - L0) + c L' along u = (P_b - P_a) / L; +T u on end a, -T u on
 * end b, each with its moment B_r x (W_R_B^T f). W, M (2 x 3): ends a and b. */
static void spring_wrench(const mb_model *md, const mb_work *w, int64_t j, const double *y,
                          double *W, double *M) {
    const double *row = md->springs + MB_SPRING_W * j;
    int64_t ends[2] = {md->springs_i[2 * j], md->springs_i[2 * j + 1]};
    double st[6];
    spring_state(md, w, j, y, st);
    double T = st[2];
    double f[3] = {T * st[3], T * st[4], T * st[5]};
    for (int e = 0; e < 2; e++) {
        double sign = e == 0 ? 1.0 : -1.0;
        double *g = W + 3 * e;
        g[0] = sign * f[0], g[1] = sign * f[1], g[2] = sign * f[2];
        if (ends[e] < 0) {
            M[3 * e] = M[3 * e + 1] = M[3 * e + 2] = 0.0;
            continue;
        }
        const double *Rb = w->R + 9 * ends[e];
        double B[3];
        for (int a = 0; a < 3; a++) B[a] = Rb[a] * g[0] + Rb[3 + a] * g[1] + Rb[6 + a] * g[2];
        mb_cross(row + (e == 0 ? S_RA : S_RB), B, M + 3 * e);
    }
}

/* out (s x 6): each spring's [L, L', T, u (3)] at y with w->R in place. */
void mb_springs_at(const mb_model *md, mb_work *w, const double *y, double *out) {
    for (int64_t j = 0; j < md->s; j++) spring_state(md, w, j, y, out + 6 * j);
}

/* out (n x 6) = Q: gravity, point loads and springs [W_F (world); B_M (body axes)], at y
 * with w->R and w->loads in place. */
static void applied_at(const mb_model *md, mb_work *w, const double *y, double *out) {
    int64_t n = md->n;
    for (int64_t i = 0; i < n; i++) {
        double m = md->bodies[MB_BODY_W * i + B_MASS];
        for (int c = 0; c < 3; c++) {
            out[6 * i + c] = m * md->gravity[c];
            out[6 * i + 3 + c] = 0.0;
        }
    }
    double W[6], M[6];
    for (int64_t j = 0; j < md->k; j++) {
        double *o = out + 6 * md->loads_i[3 * j];
        if (load_wrench(md, w, j, W, M)) {
            o[0] += W[0], o[1] += W[1], o[2] += W[2];
        }
        o[3] += M[0], o[4] += M[1], o[5] += M[2];
    }
    for (int64_t j = 0; j < md->s; j++) {
        spring_wrench(md, w, j, y, W, M);
        for (int e = 0; e < 2; e++) {
            int64_t b = md->springs_i[2 * j + e];
            if (b < 0) continue;
            double *o = out + 6 * b;
            o[0] += W[3 * e], o[1] += W[3 * e + 1], o[2] += W[3 * e + 2];
            o[3] += M[3 * e], o[4] += M[3 * e + 1], o[5] += M[3 * e + 2];
        }
    }
}

/* g = w x (J w) of body i (body axes): the gyroscopic term b on its Euler rows. */
static void gyroscopic(const mb_model *md, const double *y, int64_t i, double *g) {
    const double *J = md->bodies + MB_BODY_W * i + B_J;
    const double *wi = y + 10 * md->n + 3 * i;
    double h[3];
    h[0] = J[0] * wi[0] + J[1] * wi[1] + J[2] * wi[2];
    h[1] = J[3] * wi[0] + J[4] * wi[1] + J[5] * wi[2];
    h[2] = J[6] * wi[0] + J[7] * wi[1] + J[8] * wi[2];
    mb_cross(wi, h, g);
}

/* out (n x 6) = Q - b at y with w->R and w->loads in place. */
void mb_net_wrench_at(const mb_model *md, mb_work *w, const double *y, double *out) {
    applied_at(md, w, y, out);
    for (int64_t i = 0; i < md->n; i++) { /* - w x (J w) */
        double g[3];
        gyroscopic(md, y, i, g);
        out[6 * i + 3] -= g[0];
        out[6 * i + 4] -= g[1];
        out[6 * i + 5] -= g[2];
    }
}

void mb_wrench_parts(const mb_model *md, mb_work *w, double t, const double *y, double *Q,
                     double *b) {
    mb_rotations(md->n, y + 3 * md->n, w->R);
    mb_eval_all(md, w, t);
    mb_loads_at(md, w);
    applied_at(md, w, y, Q);
    for (int64_t i = 0; i < md->n; i++) {
        double *o = b + 6 * i;
        o[0] = o[1] = o[2] = 0.0;
        gyroscopic(md, y, i, o + 3);
    }
}

/* out ((k + 2 s) x 7): per point load, then per spring end a and b, [body (-1: ground),
 * W_F (world), B_M (about G, body axes)]: each one's share of mb_net_wrench. */
void mb_load_wrenches_at(const mb_model *md, mb_work *w, const double *y, double *out) {
    double W[6], M[6];
    for (int64_t j = 0; j < md->k; j++) {
        double *o = out + 7 * j;
        load_wrench(md, w, j, W, M);
        o[0] = (double)md->loads_i[3 * j];
        for (int a = 0; a < 3; a++) o[1 + a] = W[a], o[4 + a] = M[a];
    }
    for (int64_t j = 0; j < md->s; j++) {
        spring_wrench(md, w, j, y, W, M);
        for (int e = 0; e < 2; e++) {
            double *o = out + 7 * (md->k + 2 * j + e);
            o[0] = (double)md->springs_i[2 * j + e];
            for (int a = 0; a < 3; a++) o[1 + a] = W[3 * e + a], o[4 + a] = M[3 * e + a];
        }
    }
}

void mb_net_wrench(const mb_model *md, mb_work *w, double t, const double *y, double *out) {
    mb_rotations(md->n, y + 3 * md->n, w->R);
    mb_eval_all(md, w, t);
    mb_loads_at(md, w);
    mb_net_wrench_at(md, w, y, out);
}

void mb_springs(const mb_model *md, mb_work *w, double t, const double *y, double *out) {
    mb_rotations(md->n, y + 3 * md->n, w->R);
    (void)t; /* a spring's law does not depend on t; kept for a uniform signature */
    mb_springs_at(md, w, y, out);
}
