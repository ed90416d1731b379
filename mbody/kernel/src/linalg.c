/* The small dense factorisations the null-space route needs, without LAPACK:
 * a one-sided Jacobi SVD (Hestenes: high relative accuracy for the small singular values
 * that decide a rank), the completion of orthonormal columns to a basis of the whole
 * space (Householder QR), and the eigenvector of a symmetric matrix's smallest
 * eigenvalue (cyclic Jacobi). Matrices are row-major. */
#include <float.h>
#include <string.h>

#include "internal.h"

#define MAX_SWEEPS 60

/* One-sided Jacobi on the columns of B (cols vectors of length len, column c at
 * B + c len): rotate pairs until every pair is orthogonal to rounding; the rotations
 * are applied to the columns of V (cols vectors of length cols, V = I on entry). */
static void jacobi_columns(double *B, int64_t len, int64_t cols, double *V) {
    double tol = DBL_EPSILON * sqrt((double)len);
    /* A column whose norm is rounding beside the largest (a rank-deficient A's) has no
     * direction to make orthogonal: rotating it against the others only stirs rounding,
     * for every sweep up to MAX_SWEEPS. Such pairs count as done. */
    double top = 0.0;
    for (int64_t c = 0; c < cols; c++) {
        double s2 = 0.0;
        for (int64_t i = 0; i < len; i++) s2 += B[c * len + i] * B[c * len + i];
        if (s2 > top) top = s2;
    }
    double negligible = DBL_EPSILON * DBL_EPSILON * top;
    for (int sweep = 0; sweep < MAX_SWEEPS; sweep++) {
        int rotated = 0;
        for (int64_t p = 0; p < cols - 1; p++) {
            for (int64_t q = p + 1; q < cols; q++) {
                double *bp = B + p * len, *bq = B + q * len;
                double alpha = 0.0, beta = 0.0, gamma = 0.0;
                for (int64_t i = 0; i < len; i++) {
                    alpha += bp[i] * bp[i];
                    beta += bq[i] * bq[i];
                    gamma += bp[i] * bq[i];
                }
                if (gamma == 0.0 || fabs(gamma) <= tol * sqrt(alpha) * sqrt(beta)) continue;
                if (alpha <= negligible || beta <= negligible) continue;
                rotated = 1;
                double zeta = (beta - alpha) / (2.0 * gamma);
                double t = (zeta >= 0.0 ? 1.0 : -1.0) / (fabs(zeta) + sqrt(1.0 + zeta * zeta));
                double c = 1.0 / sqrt(1.0 + t * t), s = c * t;
                for (int64_t i = 0; i < len; i++) {
                    double x = bp[i], y = bq[i];
                    bp[i] = c * x - s * y;
                    bq[i] = s * x + c * y;
                }
                double *vp = V + p * cols, *vq = V + q * cols;
                for (int64_t i = 0; i < cols; i++) {
                    double x = vp[i], y = vq[i];
                    vp[i] = c * x - s * y;
                    vq[i] = s * x + c * y;
                }
            }
        }
        if (!rotated) break;
    }
}

/* The thin SVD of A (m x n): A = U diag(sv) V^T with p = min(m, n) singular values
 * in descending order, U (m x p), V (n x p), each with orthonormal columns where sv > 0
 * (a zero singular value's columns are 0). work: (m n + p p + 2 p) doubles and the
 * order in the tail. */
void mb_svd(const double *A, int64_t m, int64_t n, double *sv, double *U, double *V,
            double *work) {
    int64_t p = m < n ? m : n, len = m < n ? n : m;
    double *B = work, *R = work + m * n, *norms = R + p * p, *order_d = norms + p;
    /* columns of B: those of A (m >= n), or those of A^T (the rows of A) */
    if (m >= n) {
        for (int64_t i = 0; i < m; i++)
            for (int64_t j = 0; j < n; j++) B[j * m + i] = A[i * n + j];
    } else {
        memcpy(B, A, sizeof(double) * m * n);
    }
    memset(R, 0, sizeof(double) * p * p);
    for (int64_t i = 0; i < p; i++) R[i * p + i] = 1.0;
    jacobi_columns(B, len, p, R);
    for (int64_t j = 0; j < p; j++) {
        double s = 0.0;
        for (int64_t i = 0; i < len; i++) s += B[j * len + i] * B[j * len + i];
        norms[j] = sqrt(s);
        order_d[j] = (double)j;
    }
    for (int64_t a = 1; a < p; a++) { /* insertion sort, descending: p is small */
        double key = norms[a], idx = order_d[a];
        int64_t b = a - 1;
        while (b >= 0 && norms[b] < key) {
            norms[b + 1] = norms[b], order_d[b + 1] = order_d[b];
            b--;
        }
        norms[b + 1] = key, order_d[b + 1] = idx;
    }
    /* the long side's vectors: B's columns normalised; the short side's: R's columns */
    double *Long = m >= n ? U : V, *Short = m >= n ? V : U;
    for (int64_t a = 0; a < p; a++) {
        int64_t j = (int64_t)order_d[a];
        sv[a] = norms[a];
        double inv = norms[a] > 0.0 ? 1.0 / norms[a] : 0.0;
        for (int64_t i = 0; i < len; i++) Long[i * p + a] = B[j * len + i] * inv;
        for (int64_t i = 0; i < p; i++) Short[i * p + a] = R[j * p + i];
    }
}

/* Q2 (m x (m - r)): an orthonormal basis of the complement of the span of Q1's r
 * orthonormal columns (m x r): the last m - r columns of Q from Q1 = Q R (Householder).
 * hh: (m r + r) doubles. */
void mb_complete(const double *Q1, int64_t m, int64_t r, double *Q2, double *hh) {
    double *H = hh, *beta = hh + m * r; /* H: Q1, then the reflectors' vectors below */
    memcpy(H, Q1, sizeof(double) * m * r);
    for (int64_t k = 0; k < r; k++) {
        double norm = 0.0;
        for (int64_t i = k; i < m; i++) norm += H[i * r + k] * H[i * r + k];
        norm = sqrt(norm);
        double x0 = H[k * r + k];
        double alpha = x0 >= 0.0 ? -norm : norm;
        H[k * r + k] = x0 - alpha; /* v = x - alpha e_k */
        double vv = 0.0;
        for (int64_t i = k; i < m; i++) vv += H[i * r + k] * H[i * r + k];
        beta[k] = vv > 0.0 ? 2.0 / vv : 0.0;
        for (int64_t c = k + 1; c < r; c++) { /* apply I - beta v v^T to the rest */
            double s = 0.0;
            for (int64_t i = k; i < m; i++) s += H[i * r + k] * H[i * r + c];
            s *= beta[k];
            for (int64_t i = k; i < m; i++) H[i * r + c] -= s * H[i * r + k];
        }
    }
    int64_t cols = m - r;
    for (int64_t a = 0; a < cols; a++) {
        for (int64_t i = 0; i < m; i++) Q2[i * cols + a] = i == r + a ? 1.0 : 0.0;
        for (int64_t k = r - 1; k >= 0; k--) { /* Q e_j = H_0 (H_1 (... H_{r-1} e_j)) */
            double s = 0.0;
            for (int64_t i = k; i < m; i++) s += H[i * r + k] * Q2[i * cols + a];
            s *= beta[k];
            for (int64_t i = k; i < m; i++) Q2[i * cols + a] -= s * H[i * r + k];
        }
    }
}

/* vec (n): a unit eigenvector of the symmetric S's smallest eigenvalue (cyclic Jacobi).
 * work: (2 n n + n) doubles. */
void mb_eig_smallest(const double *S, int64_t n, double *vec, double *work) {
    double *A = work, *V = work + n * n;
    for (int64_t i = 0; i < n; i++)
        for (int64_t j = 0; j < n; j++) {
            A[i * n + j] = 0.5 * (S[i * n + j] + S[j * n + i]);
            V[i * n + j] = i == j ? 1.0 : 0.0;
        }
    for (int sweep = 0; sweep < MAX_SWEEPS; sweep++) {
        double off = 0.0, diag = 0.0;
        for (int64_t i = 0; i < n; i++)
            for (int64_t j = 0; j < n; j++) {
                if (i != j) off += A[i * n + j] * A[i * n + j];
                else diag += A[i * n + j] * A[i * n + j];
            }
        if (off <= DBL_EPSILON * DBL_EPSILON * diag || off == 0.0) break;
        for (int64_t p = 0; p < n - 1; p++)
            for (int64_t q = p + 1; q < n; q++) {
                double apq = A[p * n + q];
                if (apq == 0.0) continue;
                double theta = (A[q * n + q] - A[p * n + p]) / (2.0 * apq);
                double t = (theta >= 0.0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
                double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
                for (int64_t k = 0; k < n; k++) { /* A <- A J (columns p, q) */
                    double akp = A[k * n + p], akq = A[k * n + q];
                    A[k * n + p] = c * akp - s * akq;
                    A[k * n + q] = s * akp + c * akq;
                }
                for (int64_t k = 0; k < n; k++) { /* A <- J^T A (rows p, q) */
                    double apk = A[p * n + k], aqk = A[q * n + k];
                    A[p * n + k] = c * apk - s * aqk;
                    A[q * n + k] = s * apk + c * aqk;
                }
                for (int64_t k = 0; k < n; k++) {
                    double vkp = V[k * n + p], vkq = V[k * n + q];
                    V[k * n + p] = c * vkp - s * vkq;
                    V[k * n + q] = s * vkp + c * vkq;
                }
            }
    }
    int64_t best = 0;
    for (int64_t i = 1; i < n; i++)
        if (A[i * n + i] < A[best * n + best]) best = i;
    for (int64_t i = 0; i < n; i++) vec[i] = V[i * n + best];
}
