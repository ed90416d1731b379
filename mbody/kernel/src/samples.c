/* A run's figures at its output samples (mechanism.h: mb_samples): the reactions, the
 * springs' lengths and the joints' drift, one pass over the samples in C. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal.h"
#include "mechanism.h"

int mb_samples(const mb_model *md, const mb_unknowns *u, mb_work *w, const double *lam,
               int64_t K, const double *t, const double *Y, int64_t stride,
               double *reactions, double *lengths, double *drift) {
    const int64_t n = md->n, m = md->m, s = md->s;
    const int64_t N = (md->planar ? 3 : 6) * n;
    /* one block: solve's out | child6, parent6 | W_e, W_P | gamma, phi, gtv | springs */
    const int64_t size = (N + 3 * m + MB_INFO) + 12 * m + 6 * m + 3 * m + 6 * s + 1;
    double *buf = malloc((size_t)size * sizeof(double));
    if (buf == NULL) return -1;
    double *out = buf, *c6 = out + N + 3 * m + MB_INFO, *p6 = c6 + 6 * m, *We = p6 + 6 * m;
    double *WP = We + 3 * m, *gamma = WP + 3 * m, *phi = gamma + m, *gtv = phi + m;
    double *sp = gtv + m;
    drift[0] = drift[1] = 0.0;
    for (int64_t k = 0; k < K; k++) {
        const double *y = Y + k * stride;
        if (reactions != NULL) {
            mb_solve(md, u, w, t[k], y, lam, out);
            for (int64_t i = 0; i < m; i++) reactions[k * m + i] = out[N + i];
            /* the solve evaluated every component's phi and G^T v - f' at this state
             * (evaluate.c: mb_columns_at, as mb_columns does): taken from its work */
            memcpy(phi, w->phi, (size_t)m * sizeof(double));
            memcpy(gtv, w->gtv, (size_t)m * sizeof(double));
        } else if (m > 0) {
            mb_columns(md, w, t[k], y, c6, p6, We, WP, gamma, phi, gtv);
        }
        if (m > 0) {
            for (int64_t i = 0; i < m; i++) {
                if (fabs(phi[i]) > drift[0] || phi[i] != phi[i]) drift[0] = fabs(phi[i]);
                if (fabs(gtv[i]) > drift[1] || gtv[i] != gtv[i]) drift[1] = fabs(gtv[i]);
            }
        }
        if (lengths != NULL && s > 0) {
            mb_springs(md, w, t[k], y, sp);
            for (int64_t j = 0; j < s; j++) lengths[k * s + j] = sp[6 * j];
        }
    }
    free(buf);
    return 0;
}

/* a if b is not larger, b otherwise; NaN wins (as numpy's max) */
static double max_nan(double a, double b) {
    if (a != a || b != b) return NAN;
    return b > a ? b : a;
}

static double norm3(const double *a) { return sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

static void cross3(const double *a, const double *b, double *out) {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

int mb_conservation(int64_t n, int planar, const double *mass, const double *J,
                    const double *gravity, int64_t s, const double *stiffness,
                    const double *rest, const double *lengths, int64_t K, const double *Y,
                    int64_t stride, int kind, double *T, double *V, double *H,
                    double *figures, double *spin_peak) {
    /* per body at one sample: x, v, w, q (spatial form), m u, the orbital term, spin */
    double *buf = malloc((size_t)(n > 0 ? n : 1) * 3 * 6 * sizeof(double));
    if (buf == NULL) return -1;
    double *x = buf, *v = x + 3 * n, *w = v + 3 * n, *mv = w + 3 * n, *orb = mv + 3 * n;
    double *spin = orb + 3 * n;
    double M = 0.0;
    for (int64_t i = 0; i < n; i++) M += mass[i];
    double p0[3] = {0.0, 0.0, 0.0}, H0[3] = {0.0, 0.0, 0.0}, E0 = 0.0;
    double t_max = 0.0, e_max = 0.0, p_scale = 0.0, p_max = 0.0, h_scale = 0.0, h_max = 0.0;
    for (int64_t i = 0; i < n; i++) spin_peak[i] = 0.0;
    for (int64_t k = 0; k < K; k++) {
        const double *y = Y + k * stride;
        double Tk = 0.0, Vg = 0.0, p[3] = {0.0, 0.0, 0.0}, mv_sum = 0.0;
        for (int64_t i = 0; i < n; i++) {
            double q[4];
            for (int a = 0; a < 3; a++) {
                x[3 * i + a] = y[3 * i + a];
                v[3 * i + a] = y[7 * n + 3 * i + a];
                w[3 * i + a] = y[10 * n + 3 * i + a];
            }
            if (planar) { /* the trajectory keeps x, y, the angle and w_z: z parts 0 */
                const double theta = y[13 * n + i];
                x[3 * i + 2] = v[3 * i + 2] = 0.0;
                w[3 * i] = w[3 * i + 1] = 0.0;
                q[0] = cos(theta / 2);
                q[1] = q[2] = 0.0;
                q[3] = sin(theta / 2);
            } else {
                for (int a = 0; a < 4; a++) q[a] = y[3 * n + 4 * i + a];
            }
            const double *vi = v + 3 * i, *wi = w + 3 * i, *Ji = J + 9 * i;
            /* spatial: the squared rate, its square root taken once, of the largest
             * (sqrt is monotonic) */
            const double rate = planar ? fabs(wi[2])
                                       : wi[0] * wi[0] + wi[1] * wi[1] + wi[2] * wi[2];
            if (rate > spin_peak[i] || rate != rate) spin_peak[i] = rate;
            double Jw[3];
            for (int r = 0; r < 3; r++)
                Jw[r] = Ji[3 * r] * wi[0] + Ji[3 * r + 1] * wi[1] + Ji[3 * r + 2] * wi[2];
            Tk += 0.5 * mass[i] * (vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2])
                  + 0.5 * (wi[0] * Jw[0] + wi[1] * Jw[1] + wi[2] * Jw[2]);
            const double *xi = x + 3 * i;
            Vg += (xi[0] * gravity[0] + xi[1] * gravity[1] + xi[2] * gravity[2]) * mass[i];
            for (int a = 0; a < 3; a++) {
                mv[3 * i + a] = mass[i] * vi[a];
                p[a] += mv[3 * i + a];
            }
            mv_sum += norm3(mv + 3 * i);
            /* W_R_B J w = u + 2 (q_w c + q_v x c), c = q_v x u */
            double c[3], d[3];
            cross3(q + 1, Jw, c);
            cross3(q + 1, c, d);
            for (int a = 0; a < 3; a++) spin[3 * i + a] = Jw[a] + 2.0 * (q[0] * c[a] + d[a]);
        }
        double Vk = -Vg;
        for (int64_t j = 0; j < s; j++) {
            const double e = lengths[k * s + j] - rest[j];
            Vk += 0.5 * stiffness[j] * e * e;
        }
        /* angular momentum: spin only, or with the orbital terms about the world origin
         * (kind 0) or the system's mass centre (kind 2) */
        double Hk[3] = {0.0, 0.0, 0.0}, terms = 0.0;
        if (kind != 1) {
            double xc[3] = {0.0, 0.0, 0.0}, vc[3] = {0.0, 0.0, 0.0};
            if (kind == 2 && M != 0.0) {
                for (int64_t i = 0; i < n; i++)
                    for (int a = 0; a < 3; a++) xc[a] += mass[i] * x[3 * i + a];
                for (int a = 0; a < 3; a++) {
                    xc[a] /= M;
                    vc[a] = p[a] / M;
                }
            }
            for (int64_t i = 0; i < n; i++) {
                double r[3], mu[3];
                for (int a = 0; a < 3; a++) {
                    r[a] = x[3 * i + a] - xc[a];
                    mu[a] = mass[i] * (v[3 * i + a] - vc[a]);
                }
                cross3(r, mu, orb + 3 * i);
                for (int a = 0; a < 3; a++) Hk[a] += orb[3 * i + a];
                terms += norm3(orb + 3 * i);
            }
        }
        for (int64_t i = 0; i < n; i++) {
            for (int a = 0; a < 3; a++) Hk[a] += spin[3 * i + a];
            terms += norm3(spin + 3 * i);
        }
        T[k] = Tk;
        V[k] = Vk;
        for (int a = 0; a < 3; a++) H[3 * k + a] = Hk[a];
        const double Ek = Tk + Vk;
        if (k == 0) {
            E0 = Ek;
            for (int a = 0; a < 3; a++) {
                p0[a] = p[a];
                H0[a] = Hk[a];
            }
        }
        double dp[3], dH[3];
        for (int a = 0; a < 3; a++) {
            dp[a] = p[a] - p0[a];
            dH[a] = Hk[a] - H0[a];
        }
        t_max = k == 0 ? fabs(Tk) : max_nan(t_max, fabs(Tk));
        e_max = k == 0 ? fabs(Ek - E0) : max_nan(e_max, fabs(Ek - E0));
        p_scale = k == 0 ? mv_sum : max_nan(p_scale, mv_sum);
        /* p_max and h_max squared until the end, as the rates (sqrt is monotonic) */
        const double dp2 = dp[0] * dp[0] + dp[1] * dp[1] + dp[2] * dp[2];
        const double dH2 = dH[0] * dH[0] + dH[1] * dH[1] + dH[2] * dH[2];
        p_max = k == 0 ? dp2 : max_nan(p_max, dp2);
        h_scale = k == 0 ? terms : max_nan(h_scale, terms);
        h_max = k == 0 ? dH2 : max_nan(h_max, dH2);
    }
    free(buf);
    p_max = sqrt(p_max);
    h_max = sqrt(h_max);
    if (!planar)
        for (int64_t i = 0; i < n; i++) spin_peak[i] = sqrt(spin_peak[i]);
    /* relative changes, as simulation.py's numpy did them: energy's relative to
     * max(|E(0)|, max T) (0 unless that is > 0), the momenta's to their largest sum of
     * the terms' magnitudes (0 where that is <= 0) */
    const double e_scale = t_max > fabs(E0) ? t_max : fabs(E0);
    figures[0] = e_scale > 0 ? e_max / e_scale : 0.0;
    figures[1] = !(p_scale <= 0) ? p_max / p_scale : 0.0;
    figures[2] = !(h_scale <= 0) ? h_max / h_scale : 0.0;
    for (int a = 0; a < 3; a++) figures[3 + a] = p0[a];
    return 0;
}

double mb_unit_samples(int64_t n, int planar, int64_t K, double *Y, int64_t stride) {
    const double pi = 3.141592653589793, two_pi = 6.283185307179586; /* numpy's pi, 2 pi */
    double worst = 0.0;
    for (int64_t k = 0; k < K; k++) {
        double *y = Y + k * stride;
        for (int64_t i = 0; i < n; i++) {
            double *q = y + 3 * n + 4 * i;
            const double norm = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
            const double e = fabs(norm - 1.0);
            if (e > worst || e != e) worst = e;
            for (int a = 0; a < 4; a++) q[a] /= norm;
            if (planar) { /* the carried angle moved onto q's own, on its branch */
                double *theta = y + 13 * n + i;
                const double a = 2.0 * atan2(q[3], q[0]) - *theta + pi;
                double r = fmod(a, two_pi); /* numpy's remainder: the sign of the divisor */
                if (r != 0.0) {
                    if (r < 0.0) r += two_pi;
                } else {
                    r = 0.0;
                }
                *theta += r - pi;
            }
        }
    }
    return worst;
}
