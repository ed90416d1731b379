/* A kinematic run (mbody.simulate.kinematic): the configurations that close every joint
 * and driver at a series of times, and at each the accelerations the constraints impose
 * with the reactions and drivers' efforts that take them (kinetostatics), without
 * integrating anything. A fully driven mechanism's motion is this; the same run follows
 * any mechanism's drivers while it holds the rest of its coordinates where they are. */
#include <stdlib.h>
#include <string.h>

#include "internal.h"

/* y carried from the previous sample by dt along its velocities and accelerations (a
 * second-order Taylor step: Newton then starts within O(dt^3) of the answer, on the
 * previous sample's branch). acc: mb_solve's accelerations (planar [a_x, a_y, alpha],
 * spatial [a_G world, w' body axes] per body). */
static void predict(const mb_model *md, double *y, const double *acc, double dt) {
    int64_t n = md->n;
    double *x = y, *q = y + 3 * n, *v = y + 7 * n, *om = y + 10 * n;
    for (int64_t i = 0; i < n; i++) {
        double a[6] = {0, 0, 0, 0, 0, 0};
        if (md->planar) {
            a[0] = acc[3 * i], a[1] = acc[3 * i + 1], a[5] = acc[3 * i + 2];
        } else {
            for (int r = 0; r < 6; r++) a[r] = acc[6 * i + r];
        }
        /* the turn over dt in body axes: w dt + w' dt^2 / 2 (the w x w' term is of the
         * order Newton removes in one step) */
        double th[3];
        for (int r = 0; r < 3; r++) {
            x[3 * i + r] += dt * v[3 * i + r] + 0.5 * dt * dt * a[r];
            th[r] = dt * om[3 * i + r] + 0.5 * dt * dt * a[3 + r];
            v[3 * i + r] += dt * a[r];
            om[3 * i + r] += dt * a[3 + r];
        }
        /* q <- q (x) (cos |th|/2, sin |th|/2 th/|th|): the exact turn, so that a planar
         * body's angle (y[13 n + i], carried beside q) stays q's own angle */
        mb_turn_exact(q + 4 * i, th);
        if (md->planar) y[13 * n + i] += th[2];
    }
}

/* ENERGY's three values at y (after the solve): the applied loads' power Q . v (gravity
 * and springs included; Q at the mass centres, moments in body axes with w), the springs'
 * elastic energy sum k (L - L0)^2 / 2 and its rate sum k (L - L0) L'. */
static void energy_terms(const mb_model *md, mb_work *w, double t, const double *y,
                         double *Q, double *b, double *sp, double *e) {
    int64_t n = md->n, s = md->s;
    const double *v = y + 7 * n, *om = y + 10 * n;
    mb_wrench_parts(md, w, t, y, Q, b);
    double power = 0.0;
    for (int64_t i = 0; i < n; i++)
        for (int a = 0; a < 3; a++)
            power += Q[6 * i + a] * v[3 * i + a] + Q[6 * i + 3 + a] * om[3 * i + a];
    double V = 0.0, dV = 0.0;
    if (s > 0) {
        mb_springs(md, w, t, y, sp);
        for (int64_t j = 0; j < s; j++) {
            const double *row = md->springs + MB_SPRING_W * j;
            double stretch = sp[6 * j] - row[S_REST];
            V += 0.5 * row[S_STIFF] * stretch * stretch;
            dV += row[S_STIFF] * stretch * sp[6 * j + 1];
        }
    }
    e[0] = power, e[1] = V, e[2] = dV;
}

int64_t mb_kinematic_run(const mb_model *md, const mb_unknowns *u, mb_work *w,
                         const double *t, int64_t K, double *y, const double *lam,
                         int max_newton, double tol, double *Y, double *OUT, double *ENERGY,
                         double *info) {
    int64_t S = MB_STATE_SIZE(md->n, md->planar);
    int64_t L = (md->planar ? 3 : 6) * md->n + 3 * md->m + MB_INFO;
    double pr[MB_PROJECT_INFO];
    info[MB_KR_STEP] = 0.0, info[MB_KR_NEWTON] = 0.0, info[MB_KR_SINGULAR] = 0.0;
    info[MB_KR_WORST] = 0.0;
    double *scratch = NULL;
    if (ENERGY != NULL) {
        scratch = malloc(sizeof(double) * (size_t)(12 * md->n + 6 * md->s + 1));
        if (scratch == NULL) {
            info[MB_KR_SINGULAR] = -1.0;
            return 0;
        }
    }
    int64_t done = K;
    for (int64_t k = 0; k < K; k++) {
        if (k > 0) predict(md, y, OUT + (k - 1) * L, t[k] - t[k - 1]);
        int it = 0;
        double step = 0.0;
        for (; it < max_newton; it++) {
            mb_project(md, u, w, t[k], y, 1, 1e-2, 0, pr);
            if (pr[MB_PR_SINGULAR] != 0.0) {
                info[MB_KR_SINGULAR] = pr[MB_PR_SINGULAR];
                done = k;
                break;
            }
            step = pr[MB_PR_STEP];
            if (!(step > tol)) break; /* also a step that is not a number: checked below */
        }
        if (done < K) break;
        info[MB_KR_NEWTON] += (double)(it + 1);
        info[MB_KR_WORST] = fmax(info[MB_KR_WORST], (double)(it + 1));
        info[MB_KR_STEP] = step;
        int finite = 1;
        for (int64_t i = 0; i < S; i++) finite &= isfinite(y[i]);
        if (it == max_newton || !finite) {
            done = k;
            break;
        }
        memcpy(Y + k * S, y, sizeof(double) * S);
        mb_solve(md, u, w, t[k], y, lam, OUT + k * L);
        if (ENERGY != NULL)
            energy_terms(md, w, t[k], y, scratch, scratch + 6 * md->n, scratch + 12 * md->n,
                         ENERGY + 3 * k);
    }
    free(scratch);
    return done;
}

int mb_energy_samples(const mb_model *md, const mb_unknowns *u, mb_work *w,
                      const double *lam, int64_t K, const double *t, const double *Y,
                      int64_t stride, double *ACC, double *ENERGY) {
    int64_t n = md->n, N = (md->planar ? 3 : 6) * n;
    int64_t L = N + 3 * md->m + MB_INFO;
    double *buf = malloc(sizeof(double) * (size_t)(L + 12 * n + 6 * md->s + 1));
    if (buf == NULL) return -1;
    double *out = buf, *scratch = buf + L;
    int status = 0;
    for (int64_t k = 0; k < K; k++) {
        const double *y = Y + k * stride;
        mb_solve(md, u, w, t[k], y, lam, out);
        if (out[N + 3 * md->m + MB_ST_SINGULAR] != 0.0 && status == 0)
            status = (int)out[N + 3 * md->m + MB_ST_SINGULAR];
        memcpy(ACC + k * N, out, sizeof(double) * N);
        energy_terms(md, w, t[k], y, scratch, scratch + 6 * n, scratch + 12 * n,
                     ENERGY + 3 * k);
    }
    free(buf);
    return status;
}
