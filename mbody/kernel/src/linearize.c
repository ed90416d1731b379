/* The linearisation about a state in generalized coordinates (mbody/solve/linearize.py):
 * the equations there (mb_generalized), the differences K = -df/dq, D = -df/dq' with
 * their error bounds (mb_differences), whether the state is steady and which coordinates
 * are cyclic symmetries to leave out, and the first-order matrix A with the tolerance on
 * its eigenvalues' real parts. One call: the linearisation of a small model costs a few
 * dozen evaluations of f, and a Python loop around them would cost more than they do. */
#include <stdlib.h>
#include <string.h>

#include "internal.h"

/* L (k x k, lower, row-major) <- the Cholesky factor of the symmetric A; 0, or -1 when A
 * is not positive definite. */
static int cholesky(const double *A, int64_t k, double *L) {
    for (int64_t i = 0; i < k; i++)
        for (int64_t j = 0; j <= i; j++) {
            double s = A[i * k + j];
            for (int64_t p = 0; p < j; p++) s -= L[i * k + p] * L[j * k + p];
            if (i == j) {
                if (!(s > 0.0)) return -1;
                L[i * k + i] = sqrt(s);
            } else {
                L[i * k + j] = s / L[j * k + j];
            }
        }
    return 0;
}

int mb_linearize(const mb_model *md, const mb_unknowns *u, mb_work *w, double t,
                 const double *y, const double *lam, int64_t nq, const int64_t *Iq,
                 int64_t nc, const int64_t *cols, const double *scales, const int64_t *quasi,
                 const int64_t *skip, const double *params, const mb_progress *progress,
                 double *out) {
    int64_t k = nq, N = nc, kk = k * k;
    double step = params[MB_LP_STEP], rounding = params[MB_LP_ROUNDING];
    double steady_rtol = params[MB_LP_STEADY], moving_rtol = params[MB_LP_MOVING];
    double *gen = out;
    int64_t ngen = N * k + 2 * N + kk + 4 * k + MB_GENERALIZED_INFO;
    double *K = gen + ngen, *Kerr = K + kk, *D = Kerr + kk, *Derr = D + kk;
    double *resid = Derr + kk, *left = resid + k, *A = left + k, *info = A + 4 * kk;
    memset(info, 0, sizeof(double) * MB_LINEARIZE_INFO);
    if (mb_report(progress, MB_STAGE_GENERALIZED, 0, 1)) return MB_STOPPED;
    if (mb_generalized(md, u, w, t, y, lam, nq, Iq, nc, cols, NULL, gen) < 0) return -1;
    const double *M = gen + N * k + 2 * N, *f = M + kk, *qd = f + 2 * k, *F = qd + k;
    const double *ginfo = F + k;
    if (!(ginfo[MB_GI_RANK] > 0.0) || k == 0) {
        memset(K, 0, sizeof(double) * (4 * kk + 2 * k + 4 * kk));
        info[MB_LI_STEADY] = info[MB_LI_RESTING] = k == 0;
        return 0;
    }
    double *buf = malloc(sizeof(double) * (size_t)(2 * kk + 6 * k));
    if (buf == NULL) return -1;
    double *L = buf, *Minv = L + kk, *h = Minv + kk, *hu = h + k, *x = hu + k, *acc = x + k;
    if (cholesky(M, k, L) < 0) {
        info[MB_LI_SINGULAR] = 1.0;
        free(buf);
        return 0;
    }
    /* steps: positions STEP x scale; rates (exact for a quadratic) of the rates' scale,
     * the larger of the state's and sqrt(f's terms / M) */
    double Fmax = 0.0, Mmax = 0.0, rate = 1e-3;
    for (int64_t i = 0; i < k; i++) Fmax = fmax(Fmax, F[i]);
    for (int64_t i = 0; i < kk; i++) Mmax = fmax(Mmax, fabs(M[i]));
    rate = fmax(rate, sqrt(Fmax / fmax(Mmax, 1e-300)));
    for (int64_t i = 0; i < k; i++) rate = fmax(rate, fabs(qd[i]) / scales[i]);
    for (int64_t i = 0; i < k; i++) h[i] = step * scales[i], hu[i] = rate * scales[i];
    /* one evaluation of f errs by about rounding x f_scale x cond(C) (the projection's
     * QR: its pivot ratio bounds the condition from below; the factor is what its
     * backward stability allows) */
    rounding /= fmax(ginfo[MB_GI_RANK], 1e-8);
    int status = mb_differences(md, u, w, t, y, lam, nq, Iq, nc, cols, qd, h, hu, F, f,
                                rounding, skip, progress, K);
    if (status < 0) {
        free(buf);
        return status;
    }
    /* q'' = M^-1 f; steady when every f_i is below steady_rtol of its terms */
    int steady = 1;
    for (int64_t i = 0; i < k; i++) {
        resid[i] = f[i];
        if (!(fabs(f[i]) <= steady_rtol * F[i])) steady = 0;
    }
    info[MB_LI_RESTING] = steady; /* q'' = 0 (the moving coordinates not yet judged) */
    mb_cho_solve_dense(L, k, k, resid);
    /* moving coordinates; cyclic ones (K's column within its error) moving, or a
     * quasi-velocity's angle, are symmetries: left out */
    double rmax = 0.0;
    for (int64_t j = 0; j < k; j++) rmax = fmax(rmax, fabs(qd[j]) / scales[j]);
    int64_t unsteady = 0, nk = 0;
    for (int64_t j = 0; j < k; j++) {
        int moving = fabs(qd[j]) / scales[j] > moving_rtol * rmax;
        int cyclic = 1;
        for (int64_t i = 0; i < k; i++)
            if (!(fabs(K[i * k + j]) <= 10.0 * Kerr[i * k + j])) cyclic = 0;
        left[j] = cyclic && (moving || quasi[j]);
        if (left[j])
            for (int64_t i = 0; i < k; i++) K[i * k + j] = 0.0;
        else
            nk++;
        if (moving && !cyclic && unsteady == 0) unsteady = j + 1;
    }
    if (unsteady) steady = 0;
    if (params[MB_LP_STOP] == MB_STOP_STIFFNESS) { /* K and what comes with it only */
        info[MB_LI_STEADY] = steady;
        info[MB_LI_UNSTEADY] = (double)unsteady;
        info[MB_LI_KEPT] = (double)nk;
        free(buf);
        return 0;
    }
    /* A = [[0, E], [-M^-1 K_kept, -M^-1 D]] (nz = nk + k); tolerance sqrt(dA |A|) */
    int64_t nz = nk + k;
    memset(A, 0, sizeof(double) * nz * nz);
    /* M^-1 = L^-T L^-1 I, every column at once: row i of Minv is updated by whole rows,
     * each entry by the same operations in the same order as mb_cho_solve_dense on its
     * column (so the same numbers), the forward pass skipping the zeros above the
     * diagonal of L^-1 */
    for (int64_t i = 0; i < k; i++) {
        if (mb_report(progress, MB_STAGE_SYSTEM, i, 3 * k)) {
            free(buf);
            return MB_STOPPED;
        }
        double *row = Minv + i * k;
        for (int64_t c = 0; c < k; c++) row[c] = i == c;
        for (int64_t p = 0; p < i; p++) {
            double l = L[i * k + p];
            const double *above = Minv + p * k;
            for (int64_t c = 0; c <= i; c++) row[c] -= l * above[c];
        }
        for (int64_t c = 0; c <= i; c++) row[c] /= L[i * k + i];
    }
    for (int64_t i = k - 1; i >= 0; i--) {
        if (mb_report(progress, MB_STAGE_SYSTEM, 2 * k - 1 - i, 3 * k)) {
            free(buf);
            return MB_STOPPED;
        }
        double *row = Minv + i * k;
        for (int64_t p = i + 1; p < k; p++) {
            double l = L[p * k + i];
            const double *below = Minv + p * k;
            for (int64_t c = 0; c < k; c++) row[c] -= l * below[c];
        }
        for (int64_t c = 0; c < k; c++) row[c] /= L[i * k + i];
    }
    int64_t r = 0;
    for (int64_t j = 0; j < k; j++)
        if (!left[j]) A[r * nz + nk + j] = 1.0, r++;
    double minv = 0.0, errK = 0.0, errD = 0.0;
    double *sk = acc, *sd = h; /* h's and hu's 2 k doubles are free now */
    for (int64_t i = 0; i < k; i++) {
        if (mb_report(progress, MB_STAGE_SYSTEM, 2 * k + i, 3 * k)) {
            free(buf);
            return MB_STOPPED;
        }
        double a = 0.0, b = 0.0, c = 0.0;
        for (int64_t j = 0; j < k; j++) {
            a += fabs(Minv[i * k + j]);
            b += fabs(Kerr[i * k + j]);
            c += fabs(Derr[i * k + j]);
        }
        minv = fmax(minv, a), errK = fmax(errK, b), errD = fmax(errD, c);
        /* row i of M^-1 K and M^-1 D, by whole rows of K and D (each sum over p in the
         * same order as a dot product of a row and a column would take it) */
        for (int64_t j = 0; j < k; j++) sk[j] = 0.0, sd[j] = 0.0;
        for (int64_t p = 0; p < k; p++) {
            double m = Minv[i * k + p];
            const double *Kp = K + p * k, *Dp = D + p * k;
            for (int64_t j = 0; j < k; j++) sk[j] += m * Kp[j];
            for (int64_t j = 0; j < k; j++) sd[j] += m * Dp[j];
        }
        double *row = A + (nk + i) * nz;
        int64_t col = 0;
        for (int64_t j = 0; j < k; j++) {
            if (!left[j]) row[col++] = -sk[j];
            row[nk + j] = -sd[j];
        }
    }
    double nA = 0.0;
    for (int64_t i = 0; i < nz; i++) {
        double s = 0.0;
        for (int64_t j = 0; j < nz; j++) s += fabs(A[i * nz + j]);
        nA = fmax(nA, s);
    }
    double tol = fmax(sqrt(minv * (errK + errD) * nA), 1e3 * 2.220446049250313e-16 * nA);
    info[MB_LI_STEADY] = steady;
    info[MB_LI_UNSTEADY] = (double)unsteady;
    info[MB_LI_TOL] = fmax(tol, 1e-300);
    info[MB_LI_KEPT] = (double)nk;
    info[MB_LI_DA] = minv * (errK + errD);
    info[MB_LI_NORM] = nA;
    if (params[MB_LP_STOP] == MB_STOP_SYSTEM) {
        free(buf);
        return 0;
    }
    /* the spectrum of A and its modes, in the same call (the verdict needs them all) */
    double *spec = info + MB_LINEARIZE_INFO, *modes = spec + 6 * k + 8 * kk;
    int64_t *kept = (int64_t *)x; /* x's k doubles are free now */
    for (int64_t j = 0, c = 0; j < k; j++)
        if (!left[j]) kept[c++] = j;
    status = mb_spectrum(A, nz, info[MB_LI_DA], info[MB_LI_TOL], progress, spec);
    if (status != 0) {
        free(buf);
        if (status < 0) return status;
        info[MB_LI_UNCONVERGED] = 1.0;
        return 0;
    }
    const double *re = spec, *err = spec + 2 * (nz + nz * nz);
    int64_t growing = 0;
    for (int64_t i = 0; i < nz; i++) growing += !(re[2 * i] <= err[i]);
    info[MB_LI_GROWING] = (double)growing;
    int64_t m = mb_modes(nz, spec, k, nk, kept, modes);
    free(buf);
    if (m < 0) return -1;
    info[MB_LI_MODES] = (double)m;
    /* the oscillations' frequencies, then their damping ratios, in the modes' order */
    double *osc = modes + 12 * k + 4 * kk;
    int64_t count = 0;
    for (int64_t c = 0; c < m; c++)
        if (modes[MB_MODE_W * c + MB_MODE_KIND] == MB_MODE_OSCILLATION) count++;
    for (int64_t c = 0, i = 0; c < m; c++) {
        const double *row = modes + MB_MODE_W * c;
        if (row[MB_MODE_KIND] != MB_MODE_OSCILLATION) continue;
        osc[i] = row[MB_MODE_FREQUENCY], osc[count + i] = row[MB_MODE_DAMPING], i++;
    }
    info[MB_LI_OSCILLATIONS] = (double)count;
    return 0;
}
