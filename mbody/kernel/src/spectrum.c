/* The spectrum of a small real matrix, without LAPACK: eigenvalues, right eigenvectors and
 * each eigenvalue's condition number, for the linearisation's first-order system
 * (mbody/solve/linearize.py). The matrices are a few to a few dozen rows, so the cost that
 * matters is the call around the arithmetic: numpy's eig, then inv(V) for the condition
 * numbers, sorting and the bounds, took about three times the arithmetic on a 12 x 12.
 *
 * The method is the textbook one (Golub and Van Loan, Matrix Computations, 7.5 and 7.6):
 *   1. balance by powers of 2 (Parlett and Reinsch), B = D^-1 A D, so that rows and
 *      columns of mixed units (rad and m, positions and rates) weigh alike;
 *   2. reduce B to upper Hessenberg form H = Z^T B Z by Householder reflections;
 *   3. Francis double-shift QR steps until H is quasi-triangular (the real Schur form
 *      T = Z^T B Z: 1 x 1 blocks for real eigenvalues, 2 x 2 ones for pairs or for two
 *      real ones left together), Z accumulated;
 *   4. for each eigenvalue, its right vector x (T x = lam x) by back substitution and its
 *      left vector u (u^T T = lam u^T) by forward substitution, in complex arithmetic,
 *      block by block; in A's coordinates v = D Z x and l = D^-1 Z u, so that the
 *      condition number kappa = |v| |l| / |l^T v| = |D Z x| |D^-1 Z u| / |u^T x|.
 * The left vectors replace inv(V): kappa needs only each eigenvalue's own pair, and a
 * Jordan block (a free coordinate's double zero) shows as u^T x = 0 in its own rows only.
 */
#include <float.h>
#include <stdlib.h>
#include <string.h>

#include "internal.h" /* before complex.h: its I would clash with the headers' names */
#include <complex.h>

#define MAX_ITERS_PER_ROW 40

/* Scales rows and columns of A (n x n, row-major, in place) by powers of 2 until their
 * off-diagonal 1-norms are within a factor 2 of each other: A <- D^-1 A D, D in d. */
static void balance(double *A, int64_t n, double *d) {
    for (int64_t i = 0; i < n; i++) d[i] = 1.0;
    for (int done = 0, sweeps = 0; !done && sweeps < 100; sweeps++) {
        done = 1;
        for (int64_t i = 0; i < n; i++) {
            double c = 0.0, r = 0.0;
            for (int64_t j = 0; j < n; j++)
                if (j != i) c += fabs(A[j * n + i]), r += fabs(A[i * n + j]);
            if (c == 0.0 || r == 0.0) continue;
            double g = r / 2.0, f = 1.0, s = c + r;
            while (c < g) f *= 2.0, c *= 4.0;
            g = r * 2.0;
            while (c > g) f /= 2.0, c /= 4.0;
            if ((c + r) / f < 0.95 * s) {
                done = 0;
                d[i] *= f;
                for (int64_t j = 0; j < n; j++) A[i * n + j] /= f, A[j * n + i] *= f;
            }
        }
    }
}

/* The Householder vector v (len, v[0] = 1 implied by storing the full vector) and factor
 * beta with (I - beta v v^T) x = (alpha, 0, ...): returns beta (0: nothing to do). */
static double householder(const double *x, int64_t len, double *v) {
    double s = 0.0;
    for (int64_t i = 1; i < len; i++) s += x[i] * x[i];
    for (int64_t i = 0; i < len; i++) v[i] = x[i];
    if (s == 0.0) return 0.0;
    double norm = sqrt(x[0] * x[0] + s);
    v[0] = x[0] >= 0.0 ? x[0] + norm : x[0] - norm;
    return 2.0 / (v[0] * v[0] + s);
}

/* reflect_rows for a long reflector (the Hessenberg reduction's), by whole rows: s (c1 -
 * c0 + 1 doubles) gathers v^T H row by row, each of its entries the same sum in the same
 * order as reflect_rows's (so the same numbers), reading memory in order. */
static void reflect_rows_long(double *H, int64_t n, const double *v, double beta, int64_t len,
                              int64_t r0, int64_t c0, int64_t c1, double *s) {
    int64_t w = c1 - c0 + 1;
    for (int64_t j = 0; j < w; j++) s[j] = 0.0;
    for (int64_t i = 0; i < len; i++) {
        const double *row = H + (r0 + i) * n + c0;
        double vi = v[i];
        for (int64_t j = 0; j < w; j++) s[j] += vi * row[j];
    }
    for (int64_t j = 0; j < w; j++) s[j] *= beta;
    for (int64_t i = 0; i < len; i++) {
        double *row = H + (r0 + i) * n + c0, vi = v[i];
        for (int64_t j = 0; j < w; j++) row[j] -= s[j] * vi;
    }
}

/* H[r0..r0+len-1, c0..c1] <- (I - beta v v^T) H[...] (rows), row-major n x n. */
static void reflect_rows(double *H, int64_t n, const double *v, double beta, int64_t len,
                         int64_t r0, int64_t c0, int64_t c1) {
    for (int64_t j = c0; j <= c1; j++) {
        double s = 0.0;
        for (int64_t i = 0; i < len; i++) s += v[i] * H[(r0 + i) * n + j];
        s *= beta;
        for (int64_t i = 0; i < len; i++) H[(r0 + i) * n + j] -= s * v[i];
    }
}

/* H[r0..r1, c0..c0+len-1] <- H[...] (I - beta v v^T) (columns). */
static void reflect_cols(double *H, int64_t n, const double *v, double beta, int64_t len,
                         int64_t c0, int64_t r0, int64_t r1) {
    for (int64_t i = r0; i <= r1; i++) {
        double *row = H + i * n + c0, s = 0.0;
        for (int64_t j = 0; j < len; j++) s += row[j] * v[j];
        s *= beta;
        for (int64_t j = 0; j < len; j++) row[j] -= s * v[j];
    }
}

/* H <- Z^T H Z upper Hessenberg, Z (n x n) orthogonal accumulated (x, v, s: n doubles of
 * scratch each). 0, or MB_STOPPED. */
static int hessenberg(double *H, int64_t n, double *Z, double *x, double *v, double *s,
                      const mb_progress *progress) {
    for (int64_t k = 0; k + 2 < n; k++) {
        if (mb_report(progress, MB_STAGE_HESSENBERG, k, n)) return MB_STOPPED;
        int64_t len = n - k - 1;
        for (int64_t i = 0; i < len; i++) x[i] = H[(k + 1 + i) * n + k];
        double beta = householder(x, len, v);
        if (beta == 0.0) continue;
        reflect_rows_long(H, n, v, beta, len, k + 1, k, n - 1, s);
        reflect_cols(H, n, v, beta, len, k + 1, 0, n - 1);
        reflect_cols(Z, n, v, beta, len, k + 1, 0, n - 1);
        for (int64_t i = k + 2; i < n; i++) H[i * n + k] = 0.0;
    }
    return 0;
}

/* One Francis double-shift step on the active window l..m of H (full Schur updates: the
 * rows to the right of the window and the columns above it, and Z), with the shifts the
 * roots of s^2 - tr s + det. */
static void francis_step(double *H, int64_t n, double *Z, int64_t l, int64_t m, double tr,
                         double det) {
    double v[3];
#define Hh(i, j) H[(i) * n + (j)]
    double x = Hh(l, l) * Hh(l, l) + Hh(l, l + 1) * Hh(l + 1, l) - tr * Hh(l, l) + det;
    double y = Hh(l + 1, l) * (Hh(l, l) + Hh(l + 1, l + 1) - tr);
    double z = l + 2 <= m ? Hh(l + 1, l) * Hh(l + 2, l + 1) : 0.0;
    for (int64_t k = l; k + 2 <= m; k++) {
        double xyz[3] = {x, y, z};
        double beta = householder(xyz, 3, v);
        if (beta != 0.0) {
            int64_t q = k > l ? k - 1 : l;
            reflect_rows(H, n, v, beta, 3, k, q, n - 1);
            int64_t r = k + 3 < m ? k + 3 : m;
            reflect_cols(H, n, v, beta, 3, k, 0, r);
            reflect_cols(Z, n, v, beta, 3, k, 0, n - 1);
            if (k > l) Hh(k + 1, k - 1) = Hh(k + 2, k - 1) = 0.0;
        }
        x = Hh(k + 1, k);
        y = Hh(k + 2, k);
        if (k + 3 <= m) z = Hh(k + 3, k);
    }
    double xy[2] = {x, y};
    double beta = householder(xy, 2, v);
    if (beta != 0.0) {
        int64_t q = m - 2 >= l ? m - 2 : l;
        reflect_rows(H, n, v, beta, 2, m - 1, q, n - 1);
        reflect_cols(H, n, v, beta, 2, m - 1, 0, m);
        reflect_cols(Z, n, v, beta, 2, m - 1, 0, n - 1);
        if (m - 2 >= l) Hh(m, m - 2) = 0.0;
    }
#undef Hh
}

/* The eigenvalues of the 2 x 2 block [[a, b], [c, d]]: (re0, im0), (re1, im1), the pair
 * with im0 > 0 first; two real ones by their size, the smaller from the product. */
static void block_eigenvalues(double a, double b, double c, double d, double *wr,
                              double *wi) {
    double mean = 0.5 * (a + d), half = 0.5 * (a - d), disc = half * half + b * c;
    if (disc >= 0.0) {
        double sq = sqrt(disc), big = mean >= 0.0 ? mean + sq : mean - sq;
        double small = big != 0.0 ? (a * d - b * c) / big : 0.0;
        wr[0] = big, wr[1] = small, wi[0] = wi[1] = 0.0;
    } else {
        double im = sqrt(-disc);
        wr[0] = wr[1] = mean, wi[0] = im, wi[1] = -im;
    }
}

/* Real Schur form by Francis steps: T in H, Z accumulated; the eigenvalues in wr, wi and
 * each row's block start in start (the row itself for a 1 x 1 block). 0, -1 when the
 * iteration did not converge, or MB_STOPPED. */
static int schur(double *H, int64_t n, double *Z, double *wr, double *wi, int64_t *start,
                 const mb_progress *progress) {
    double norm = 0.0;
    for (int64_t i = 0; i < n * n; i++) norm = fmax(norm, fabs(H[i]));
    int64_t m = n - 1, its = 0;
    while (m >= 0) {
        if (its == 0 && mb_report(progress, MB_STAGE_SCHUR, n - 1 - m, n)) return MB_STOPPED;
        int64_t l = m;
        for (; l > 0; l--) { /* a negligible subdiagonal splits the problem */
            double s = fabs(H[(l - 1) * n + l - 1]) + fabs(H[l * n + l]);
            if (s == 0.0) s = norm;
            if (fabs(H[l * n + l - 1]) <= DBL_EPSILON * s) {
                H[l * n + l - 1] = 0.0;
                break;
            }
        }
        if (l == m) { /* a real eigenvalue */
            wr[m] = H[m * n + m], wi[m] = 0.0, start[m] = m;
            m -= 1, its = 0;
            continue;
        }
        if (l == m - 1) { /* a 2 x 2 block: a pair, or two real eigenvalues */
            double w_r[2], w_i[2];
            block_eigenvalues(H[l * n + l], H[l * n + m], H[m * n + l], H[m * n + m], w_r,
                              w_i);
            wr[l] = w_r[0], wi[l] = w_i[0], wr[m] = w_r[1], wi[m] = w_i[1];
            start[l] = start[m] = l;
            m -= 2, its = 0;
            continue;
        }
        if (its >= MAX_ITERS_PER_ROW) return -1;
        double tr, det;
        if (its == 10 || its == 20) { /* an exceptional shift breaks a cycle */
            double s = fabs(H[m * n + m - 1]) + fabs(H[(m - 1) * n + m - 2]);
            double a = 0.75 * s + H[m * n + m];
            tr = 2.0 * a, det = a * a + 0.4375 * s * s;
        } else {
            double a = H[(m - 1) * n + m - 1], b = H[(m - 1) * n + m];
            double c = H[m * n + m - 1], d = H[m * n + m];
            tr = a + d, det = a * d - b * c;
        }
        francis_step(H, n, Z, l, m, tr, det);
        its++;
    }
    return 0;
}

/* a / b, with |b| raised to at least smin (a repeated eigenvalue's zero pivot). */
static double complex guarded_div(double complex a, double complex b, double smin) {
    if (cabs(b) < smin) b = smin;
    return a / b;
}

/* Solves [[a, b], [c, d]] [p, q] = [e, f] (complex), the determinant guarded. */
static void solve2(double complex a, double complex b, double complex c, double complex d,
                   double complex e, double complex f, double smin, double complex *p,
                   double complex *q) {
    double complex det = a * d - b * c;
    if (cabs(det) < smin * smin) det = smin * smin;
    *p = (e * d - b * f) / det;
    *q = (a * f - c * e) / det;
}

/* Scales x (n) down when its entries grow past 1e150 (a chain of guarded pivots). */
static void rescale(double complex *x, int64_t n) {
    double big = 0.0; /* |re| + |im|: within a factor sqrt(2) of |x|, without hypot */
    for (int64_t i = 0; i < n; i++) big = fmax(big, fabs(creal(x[i])) + fabs(cimag(x[i])));
    if (big > 1e150)
        for (int64_t i = 0; i < n; i++) x[i] /= big;
}

/* x with T x = lam x (x zero below the block starting at k) and u with u^T T = lam u^T
 * (u zero above it), T quasi-triangular with blocks given by start; TT its transpose (u's
 * sums run down T's columns: along TT's rows, in memory order). */
static void vectors(const double *T, const double *TT, int64_t n, const int64_t *start,
                    int64_t k, double complex lam, double smin, double complex *x,
                    double complex *u) {
#define Tt(i, j) T[(i) * n + (j)]
#define TTt(i, j) TT[(j) * n + (i)]
    int64_t ks = start[k], size = (ks + 1 < n && start[ks + 1] == ks) ? 2 : 1;
    for (int64_t i = 0; i < n; i++) x[i] = u[i] = 0.0;
    if (size == 1) {
        x[ks] = u[ks] = 1.0;
    } else { /* from the block's row (column) of the larger entries: a nearly triangular
              * block's other one is two roundings over each other */
        double complex a = Tt(ks, ks) - lam, b = Tt(ks, ks + 1), c = Tt(ks + 1, ks);
        double complex d = Tt(ks + 1, ks + 1) - lam;
        if (cabs(a) + cabs(b) >= cabs(c) + cabs(d))
            x[ks] = b, x[ks + 1] = -a;
        else
            x[ks] = -d, x[ks + 1] = c;
        if (cabs(a) + cabs(c) >= cabs(b) + cabs(d))
            u[ks] = c, u[ks + 1] = -a;
        else
            u[ks] = -d, u[ks + 1] = b;
    }
    for (int64_t i = ks - 1; i >= 0;) { /* back substitution, block by block */
        if (start[i] == i - 1) {
            double complex e = 0.0, f = 0.0;
            for (int64_t j = i + 1; j < n; j++) e -= Tt(i - 1, j) * x[j], f -= Tt(i, j) * x[j];
            solve2(Tt(i - 1, i - 1) - lam, Tt(i - 1, i), Tt(i, i - 1), Tt(i, i) - lam, e, f,
                   smin, &x[i - 1], &x[i]);
            i -= 2;
        } else {
            double complex e = 0.0;
            for (int64_t j = i + 1; j < n; j++) e -= Tt(i, j) * x[j];
            x[i] = guarded_div(e, Tt(i, i) - lam, smin);
            i -= 1;
        }
        rescale(x, n);
    }
    for (int64_t j = ks + size; j < n;) { /* forward substitution for the left vector */
        if (j + 1 < n && start[j + 1] == j) {
            double complex e = 0.0, f = 0.0;
            for (int64_t i = ks; i < j; i++) e -= u[i] * TTt(i, j), f -= u[i] * TTt(i, j + 1);
            solve2(Tt(j, j) - lam, Tt(j + 1, j), Tt(j, j + 1), Tt(j + 1, j + 1) - lam, e, f,
                   smin, &u[j], &u[j + 1]);
            j += 2;
        } else {
            double complex e = 0.0;
            for (int64_t i = ks; i < j; i++) e -= u[i] * TTt(i, j);
            u[j] = guarded_div(e, Tt(j, j) - lam, smin);
            j += 1;
        }
        rescale(u, n);
    }
#undef Tt
#undef TTt
}

/* order (n) <- the indices sorted by first, then by second (NULL: none), equal keys kept
 * in index order (insertion sort: n is a few dozen). */
static void stable_order(int64_t n, const double *first, const double *second,
                         int64_t *order) {
    for (int64_t i = 0; i < n; i++) order[i] = i;
    for (int64_t i = 1; i < n; i++) {
        int64_t o = order[i], j = i;
        while (j > 0) {
            int64_t p = order[j - 1];
            int after = first[p] > first[o] ||
                        (second != NULL && first[p] == first[o] && second[p] > second[o]);
            if (!after) break;
            order[j] = p;
            j--;
        }
        order[j] = o;
    }
}

int mb_spectrum(const double *A, int64_t n, double dA, double tol,
                const mb_progress *progress, double *out) {
    double complex *w_out = (double complex *)out, *V_out = w_out + n;
    double *err_out = out + 2 * (n + n * n);
    if (n == 0) return 0;
    double *buf = malloc(sizeof(double) * (size_t)(3 * n * n + 7 * n) +
                         sizeof(double complex) * (size_t)(4 * n) +
                         sizeof(int64_t) * (size_t)(2 * n));
    if (buf == NULL) return -1;
    double *H = buf, *Z = H + n * n, *HT = Z + n * n, *d = HT + n * n, *wr = d + n;
    double *wi = wr + n, *kappa = wi + n, *tmp = kappa + n, *tmp2 = tmp + n, *tmp3 = tmp2 + n;
    double complex *x = (double complex *)(tmp3 + n), *u = x + n, *v = u + n, *l = v + n;
    int64_t *start = (int64_t *)(l + n), *order = start + n;
    /* the floor of every bound: rounding of A itself (1e3 eps |A|_inf) */
    double normA = 0.0;
    for (int64_t i = 0; i < n; i++) {
        double s = 0.0;
        for (int64_t j = 0; j < n; j++) s += fabs(A[i * n + j]);
        normA = fmax(normA, s);
    }
    double floor_ = 1e3 * DBL_EPSILON * normA;
    memcpy(H, A, sizeof(double) * n * n);
    balance(H, n, d);
    for (int64_t i = 0; i < n * n; i++) Z[i] = 0.0;
    for (int64_t i = 0; i < n; i++) Z[i * n + i] = 1.0;
    int status = hessenberg(H, n, Z, tmp, tmp2, tmp3, progress);
    if (status == 0) status = schur(H, n, Z, wr, wi, start, progress);
    if (status != 0) {
        free(buf);
        return status == MB_STOPPED ? MB_STOPPED : 1;
    }
    double normT = 0.0;
    for (int64_t i = 0; i < n * n; i++) normT = fmax(normT, fabs(H[i]));
    for (int64_t i = 0; i < n; i++)
        for (int64_t j = 0; j < n; j++) HT[j * n + i] = H[i * n + j];
    for (int64_t k = 0; k < n; k++) {
        if (mb_report(progress, MB_STAGE_VECTORS, k, n)) {
            free(buf);
            return MB_STOPPED;
        }
        if (wi[k] < 0.0) continue; /* the conjugate of the one before it */
        double complex lam = wr[k] + wi[k] * _Complex_I;
        double smin = fmax(DBL_EPSILON * fmax(cabs(lam), normT), DBL_MIN);
        vectors(H, HT, n, start, k, lam, smin, x, u);
        double complex ux = 0.0;
        double nv = 0.0, nl = 0.0, big = 0.0;
        int64_t at = 0;
        for (int64_t i = 0; i < n; i++) ux += u[i] * x[i];
        for (int64_t i = 0; i < n; i++) { /* v = D Z x, l = D^-1 Z u */
            double complex sv = 0.0, sl = 0.0;
            for (int64_t j = 0; j < n; j++) sv += Z[i * n + j] * x[j], sl += Z[i * n + j] * u[j];
            v[i] = d[i] * sv, l[i] = sl / d[i];
            nv += creal(v[i] * conj(v[i])), nl += creal(l[i] * conj(l[i]));
            if (cabs(v[i]) > big) big = cabs(v[i]), at = i;
        }
        nv = sqrt(nv), nl = sqrt(nl);
        kappa[k] = cabs(ux) > 0.0 ? nv * nl / cabs(ux) : INFINITY;
        /* |v| = 1, its largest entry real and positive (as LAPACK's dgeev) */
        double complex phase = big > 0.0 ? conj(v[at]) / big : 1.0;
        for (int64_t i = 0; i < n; i++) V_out[i * n + k] = v[i] * phase / nv;
        if (wi[k] > 0.0) { /* its conjugate, the next eigenvalue of the block */
            kappa[k + 1] = kappa[k];
            for (int64_t i = 0; i < n; i++) V_out[i * n + k + 1] = conj(V_out[i * n + k]);
        }
    }
    stable_order(n, wr, wi, order); /* by real part, then imaginary part */
    /* V's columns in that order, row by row through x */
    for (int64_t i = 0; i < n; i++) {
        for (int64_t c = 0; c < n; c++) x[c] = V_out[i * n + order[c]];
        for (int64_t c = 0; c < n; c++) V_out[i * n + c] = x[c];
    }
    for (int64_t c = 0; c < n; c++) {
        int64_t o = order[c];
        w_out[c] = wr[o] + wi[o] * _Complex_I;
        double first = kappa[o] * dA;
        double e = isfinite(first) ? fmin(first, tol) : tol;
        err_out[c] = fmax(e, floor_);
    }
    free(buf);
    return 0;
}

int64_t mb_modes(int64_t n, const double *spectrum, int64_t k, int64_t nk,
                 const int64_t *kept, double *out) {
    const double complex *w = (const double complex *)spectrum, *V = w + n;
    const double *tol = spectrum + 2 * (n + n * n);
    double complex *shapes = (double complex *)(out + MB_MODE_W * n);
    double *key = malloc(sizeof(double) * (size_t)(n > 0 ? n : 1));
    double complex *row = malloc(sizeof(double complex) * (size_t)(n * (k > 0 ? k : 1) + 1));
    int64_t *order = malloc(sizeof(int64_t) * (size_t)(n > 0 ? n : 1));
    if (key == NULL || row == NULL || order == NULL) {
        free(key), free(row), free(order);
        return -1;
    }
    int64_t m = 0;
    for (int64_t i = 0; i < n; i++) {
        double complex lam = w[i];
        double t = tol[i], mag = cabs(lam);
        int neutral = mag <= t, osc = !neutral && fabs(cimag(lam)) > t;
        if (osc && cimag(lam) < 0.0) continue; /* one of each conjugate pair */
        double *mode = out + MB_MODE_W * m;
        double re = fabs(creal(lam)) > t ? creal(lam) : 0.0;
        double im = fabs(cimag(lam)) > t ? cimag(lam) : 0.0;
        mode[MB_MODE_INDEX] = (double)i;
        mode[MB_MODE_KIND] = neutral ? MB_MODE_NEUTRAL
                                     : osc ? MB_MODE_OSCILLATION
                                           : creal(lam) > 0.0 ? MB_MODE_GROWTH : MB_MODE_DECAY;
        mode[MB_MODE_RE] = re, mode[MB_MODE_IM] = im;
        mode[MB_MODE_FREQUENCY] = osc ? mag : NAN;
        double zeta = neutral ? NAN : -re / mag;
        mode[MB_MODE_DAMPING] = zeta == 0.0 ? 0.0 : zeta; /* not -0 */
        key[m] = neutral ? -INFINITY : mag;
        /* the shape: delta q = delta q' / lambda; a neutral mode's delta q if it has one
         * (kept coordinates), else its rate */
        double complex *s = row + k * m;
        int positions = 0;
        if (neutral) {
            double top = 0.0, big = 0.0;
            for (int64_t r = 0; r < n; r++) big = fmax(big, cabs(V[r * n + i]));
            for (int64_t r = 0; r < k; r++) s[r] = 0.0;
            for (int64_t j = 0; j < nk; j++) {
                s[kept[j]] = V[j * n + i];
                top = fmax(top, cabs(V[j * n + i]));
            }
            positions = top > 1e-12 * big;
        }
        if (!positions)
            for (int64_t r = 0; r < k; r++) s[r] = V[(nk + r) * n + i] / (neutral ? 1.0 : lam);
        int64_t at = 0; /* the largest entry (the first of equals) becomes 1 */
        for (int64_t r = 1; r < k; r++)
            if (cabs(s[r]) > cabs(s[at])) at = r;
        double complex pivot = k > 0 ? s[at] : 1.0;
        double imag = 0.0;
        for (int64_t r = 0; r < k; r++) {
            s[r] /= pivot;
            if (cabs(s[r]) < 1e-14) s[r] = 0.0;
            imag = fmax(imag, fabs(cimag(s[r])));
        }
        if (imag <= 1e-12) /* undamped: the coordinates move in phase */
            for (int64_t r = 0; r < k; r++) s[r] = creal(s[r]);
        m++;
    }
    stable_order(m, key, NULL, order); /* neutral first, then by |lambda| */
    double *sorted = malloc(sizeof(double) * (size_t)(MB_MODE_W * (m > 0 ? m : 1)));
    if (sorted == NULL) {
        free(key), free(row), free(order);
        return -1;
    }
    for (int64_t c = 0; c < m; c++) {
        memcpy(sorted + MB_MODE_W * c, out + MB_MODE_W * order[c], sizeof(double) * MB_MODE_W);
        memcpy(shapes + k * c, row + k * order[c], sizeof(double complex) * (size_t)k);
    }
    memcpy(out, sorted, sizeof(double) * (size_t)(MB_MODE_W * m));
    free(sorted), free(key), free(row), free(order);
    return m;
}
