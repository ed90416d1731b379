/* A run's figures at its output samples (mechanism.h: mb_samples): the reactions, the
 * springs' lengths and the joints' drift, one pass over the samples in C. */
#include <limits.h>
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

/* Two samples at once, one a lane: the same operations in the same order as one sample
 * alone, so each lane's numbers are the scalar ones bit for bit (no contraction:
 * -ffp-contract=off); SSE2 on x86-64, NEON on arm64, both in their baselines. An odd
 * sample out is paired with itself. */
typedef double v2 __attribute__((vector_size(16)));
/* long long lanes: the type Clang gives a comparison of v2s (GCC: the same size) */
typedef long long v2i __attribute__((vector_size(16)));

static inline v2 pair(double a, double b) { return (v2){a, b}; }

static inline v2 vsqrt(v2 a) { return (v2){sqrt(a[0]), sqrt(a[1])}; }

static inline v2 vabs(v2 a) { return (v2)((v2i)a & (v2i){LLONG_MAX, LLONG_MAX}); }

/* max_nan lane by lane */
static inline v2 vmax_nan(v2 a, v2 b) {
    const v2i take_b = (v2i)(b > a), either_nan = (v2i)(a != a) | (v2i)(b != b);
    const v2 larger = (v2)(((v2i)b & take_b) | ((v2i)a & ~take_b));
    return (v2)(((v2i)pair(NAN, NAN) & either_nan) | ((v2i)larger & ~either_nan));
}

static inline v2 vnorm3(const v2 *a) { return vsqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

static inline void vcross3(const v2 *a, const v2 *b, v2 *out) {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

/* body i's x, v (offset 0, 7 n) or w (10 n) at the samples ya, yb in their spatial form:
 * a planar model's trajectory keeps x, y, the angle and w_z, the other parts 0 */
static inline void load3(const double *ya, const double *yb, int64_t at, int planar,
                         int64_t zero_from, int64_t zero_to, v2 *out) {
    for (int a = 0; a < 3; a++)
        out[a] = planar && a >= zero_from && a < zero_to ? pair(0.0, 0.0)
                                                          : pair(ya[at + a], yb[at + a]);
}

int mb_conservation(int64_t n, int planar, const double *mass, const double *J,
                    const double *gravity, int64_t s, const double *stiffness,
                    const double *rest, const double *lengths, int64_t K, const double *Y,
                    int64_t stride, int kind, double *T, double *V, double *H,
                    double *figures, double *spin_peak) {
    /* per body at the two samples: the spin term W_R_B J w; the largest (squared) rates */
    v2 *buf = malloc((size_t)(n > 0 ? n : 1) * 4 * sizeof(v2));
    if (buf == NULL) return -1;
    v2 *spin = buf, *peak = spin + 3 * n;
    double M = 0.0;
    for (int64_t i = 0; i < n; i++) {
        M += mass[i];
        peak[i] = pair(0.0, 0.0);
    }
    double E0 = 0.0;
    v2 p0[3], H0[3];
    v2 t_max = pair(0.0, 0.0), e_max = t_max, p_scale = t_max, p_max = t_max;
    v2 h_scale = t_max, h_max = t_max;
    /* sample 0 alone first (its E, p, H are the references), then pairs */
    for (int64_t ka = 0; ka < K; ka = ka == 0 ? 1 : ka + 2) {
        const int64_t kb = ka == 0 || ka + 1 >= K ? ka : ka + 1;
        const double *ya = Y + ka * stride, *yb = Y + kb * stride;
        v2 Tk = pair(0.0, 0.0), Vg = Tk, p[3] = {Tk, Tk, Tk}, mv_sum = Tk;
        for (int64_t i = 0; i < n; i++) {
            v2 x[3], v[3], w[3], q[4];
            load3(ya, yb, 3 * i, planar, 2, 3, x);
            load3(ya, yb, 7 * n + 3 * i, planar, 2, 3, v);
            load3(ya, yb, 10 * n + 3 * i, planar, 0, 2, w);
            if (planar) {
                const double ta = ya[13 * n + i], tb = yb[13 * n + i];
                q[0] = pair(cos(ta / 2), cos(tb / 2));
                q[1] = q[2] = pair(0.0, 0.0);
                q[3] = pair(sin(ta / 2), sin(tb / 2));
            } else {
                for (int a = 0; a < 4; a++) q[a] = pair(ya[3 * n + 4 * i + a], yb[3 * n + 4 * i + a]);
            }
            const double *Ji = J + 9 * i;
            const v2 m = pair(mass[i], mass[i]);
            /* spatial: the squared rate, its square root taken once, of the largest
             * (sqrt is monotonic) */
            const v2 rate = planar ? vabs(w[2]) : w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
            peak[i] = vmax_nan(peak[i], rate);
            v2 Jw[3];
            for (int r = 0; r < 3; r++)
                Jw[r] = Ji[3 * r] * w[0] + Ji[3 * r + 1] * w[1] + Ji[3 * r + 2] * w[2];
            Tk += 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
                  + 0.5 * (w[0] * Jw[0] + w[1] * Jw[1] + w[2] * Jw[2]);
            Vg += (x[0] * gravity[0] + x[1] * gravity[1] + x[2] * gravity[2]) * m;
            v2 mv[3];
            for (int a = 0; a < 3; a++) {
                mv[a] = m * v[a];
                p[a] += mv[a];
            }
            mv_sum += vnorm3(mv);
            /* W_R_B J w = u + 2 (q_w c + q_v x c), c = q_v x u */
            v2 c[3], d[3];
            vcross3(q + 1, Jw, c);
            vcross3(q + 1, c, d);
            for (int a = 0; a < 3; a++) spin[3 * i + a] = Jw[a] + 2.0 * (q[0] * c[a] + d[a]);
        }
        v2 Vk = -Vg;
        for (int64_t j = 0; j < s; j++) {
            const v2 e = pair(lengths[ka * s + j], lengths[kb * s + j]) - rest[j];
            Vk += 0.5 * stiffness[j] * e * e;
        }
        /* angular momentum: spin only, or with the orbital terms about the world origin
         * (kind 0) or the system's mass centre (kind 2) */
        const v2 zero = pair(0.0, 0.0);
        v2 Hk[3] = {zero, zero, zero}, terms = zero;
        if (kind != 1) {
            v2 xc[3] = {zero, zero, zero}, vc[3] = {zero, zero, zero};
            if (kind == 2 && M != 0.0) {
                for (int64_t i = 0; i < n; i++) {
                    v2 x[3];
                    load3(ya, yb, 3 * i, planar, 2, 3, x);
                    for (int a = 0; a < 3; a++) xc[a] += mass[i] * x[a];
                }
                for (int a = 0; a < 3; a++) {
                    xc[a] /= M;
                    vc[a] = p[a] / M;
                }
            }
            for (int64_t i = 0; i < n; i++) {
                v2 x[3], v[3], r[3], mu[3], orb[3];
                load3(ya, yb, 3 * i, planar, 2, 3, x);
                load3(ya, yb, 7 * n + 3 * i, planar, 2, 3, v);
                for (int a = 0; a < 3; a++) {
                    r[a] = x[a] - xc[a];
                    mu[a] = mass[i] * (v[a] - vc[a]);
                }
                vcross3(r, mu, orb);
                for (int a = 0; a < 3; a++) Hk[a] += orb[a];
                terms += vnorm3(orb);
            }
        }
        for (int64_t i = 0; i < n; i++) {
            for (int a = 0; a < 3; a++) Hk[a] += spin[3 * i + a];
            terms += vnorm3(spin + 3 * i);
        }
        T[ka] = Tk[0];
        T[kb] = Tk[1];
        V[ka] = Vk[0];
        V[kb] = Vk[1];
        for (int a = 0; a < 3; a++) {
            H[3 * ka + a] = Hk[a][0];
            H[3 * kb + a] = Hk[a][1];
        }
        const v2 Ek = Tk + Vk;
        if (ka == 0) {
            E0 = Ek[0];
            for (int a = 0; a < 3; a++) {
                p0[a] = pair(p[a][0], p[a][0]);
                H0[a] = pair(Hk[a][0], Hk[a][0]);
            }
        }
        v2 dp[3], dH[3];
        for (int a = 0; a < 3; a++) {
            dp[a] = p[a] - p0[a];
            dH[a] = Hk[a] - H0[a];
        }
        /* all start at 0, which sample 0's values (>= 0) replace, a NaN too */
        t_max = vmax_nan(t_max, vabs(Tk));
        e_max = vmax_nan(e_max, vabs(Ek - E0));
        p_scale = vmax_nan(p_scale, mv_sum);
        /* p_max and h_max squared until the end, as the rates (sqrt is monotonic) */
        p_max = vmax_nan(p_max, dp[0] * dp[0] + dp[1] * dp[1] + dp[2] * dp[2]);
        h_scale = vmax_nan(h_scale, terms);
        h_max = vmax_nan(h_max, dH[0] * dH[0] + dH[1] * dH[1] + dH[2] * dH[2]);
    }
    for (int64_t i = 0; i < n; i++) {
        const double top = K > 0 ? max_nan(peak[i][0], peak[i][1]) : 0.0;
        spin_peak[i] = planar ? top : sqrt(top);
    }
    free(buf);
    double p0_1[3] = {0.0, 0.0, 0.0};
    if (K > 0)
        for (int a = 0; a < 3; a++) p0_1[a] = p0[a][0];
    const double t_top = max_nan(t_max[0], t_max[1]), e_top = max_nan(e_max[0], e_max[1]);
    const double p_top = sqrt(max_nan(p_max[0], p_max[1]));
    const double h_top = sqrt(max_nan(h_max[0], h_max[1]));
    const double p_sc = max_nan(p_scale[0], p_scale[1]);
    const double h_sc = max_nan(h_scale[0], h_scale[1]);
    /* relative changes, as simulation.py's numpy did them: energy's relative to
     * max(|E(0)|, max T) (0 unless that is > 0), the momenta's to their largest sum of
     * the terms' magnitudes (0 where that is <= 0) */
    const double e_scale = t_top > fabs(E0) ? t_top : fabs(E0);
    figures[0] = e_scale > 0 ? e_top / e_scale : 0.0;
    figures[1] = !(p_sc <= 0) ? p_top / p_sc : 0.0;
    figures[2] = !(h_sc <= 0) ? h_top / h_sc : 0.0;
    for (int a = 0; a < 3; a++) figures[3 + a] = p0_1[a];
    return 0;
}

double mb_unit_samples(int64_t n, int planar, int64_t K, double *Y, int64_t stride) {
    const double pi = 3.141592653589793, two_pi = 6.283185307179586; /* numpy's pi, 2 pi */
    /* two samples at once (a short run's samples outnumber its steps) */
    v2 worst = pair(0.0, 0.0);
    for (int64_t k = 0; k < K; k += 2)
        for (int64_t i = 0; i < n; i++) {
            double *qa = Y + k * stride + 3 * n + 4 * i;
            double *qb = k + 1 < K ? qa + stride : qa;
            v2 q[4];
            for (int a = 0; a < 4; a++) q[a] = pair(qa[a], qb[a]);
            const v2 norm = vsqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
            worst = vmax_nan(worst, vabs(norm - 1.0));
            for (int a = 0; a < 4; a++) {
                q[a] /= norm;
                qa[a] = q[a][0];
                qb[a] = q[a][1];
            }
        }
    if (planar) /* each carried angle moved onto its unit q's own, on its branch */
        for (int64_t k = 0; k < K; k++) {
            double *y = Y + k * stride;
            for (int64_t i = 0; i < n; i++) {
                const double *q = y + 3 * n + 4 * i;
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
    return max_nan(worst[0], worst[1]);
}
