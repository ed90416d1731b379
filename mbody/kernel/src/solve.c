/* The constrained solve  M a - G_U lam = r6,  G_U^T a = gam  through the Schur
 * complement S = G_U^T M^-1 G_U: banded Cholesky with one round of iterative refinement;
 * when S's pivots are not trusted, the pivoted route for exactly redundant joints, else
 * the null-space route (nullspace.c). The backward error is measured on residuals
 * r1 = r6 - (M a - G_U lam), r2 = gam - G_U^T a. */
#include <string.h>

#include "internal.h"

static int64_t parent_of(const mb_model *md, int64_t comp) {
    return md->joints_i[3 * md->comps_i[4 * comp]];
}

static int64_t child_of(const mb_model *md, int64_t comp) {
    return md->joints_i[3 * md->comps_i[4 * comp] + 1];
}

/* out (mu) = G_U^T a for per-body rows a (n x 6). */
static void gt(const mb_model *md, const mb_unknowns *u, const double *child6,
               const double *parent6, const double *a6, double *out) {
    for (int64_t k = 0; k < u->mu; k++) {
        int64_t i = u->U[k], p = parent_of(md, i), c = child_of(md, i);
        double s = 0.0;
        for (int r = 0; r < 6; r++) s += child6[6 * i + r] * a6[6 * c + r];
        if (p >= 0)
            for (int r = 0; r < 6; r++) s += parent6[6 * i + r] * a6[6 * p + r];
        out[k] = s;
    }
}

void mb_add_g(const mb_model *md, const mb_unknowns *u, const double *child6,
              const double *parent6, const double *lam, double *out, double sign) {
    for (int64_t k = 0; k < u->mu; k++) {
        int64_t i = u->U[k], p = parent_of(md, i), c = child_of(md, i);
        double f = sign * lam[k];
        for (int r = 0; r < 6; r++) out[6 * c + r] += child6[6 * i + r] * f;
        if (p >= 0)
            for (int r = 0; r < 6; r++) out[6 * p + r] += parent6[6 * i + r] * f;
    }
}

double mb_band_cholesky(double *Sb, int64_t mu, int64_t bw, double rtol, int stop) {
    /* In place: lower banded S (Sb[i (bw+1) + i - j] = S_ij) -> its Cholesky factor. A
     * squared pivot keeping no more than rtol of its diagonal entry stops (returns -1) or
     * leaves its column out (a pivoted Cholesky's). Returns the smallest kept ratio. */
    int64_t W = bw + 1;
    double worst = 1.0;
    for (int64_t i = 0; i < mu; i++) {
        int64_t lo = i - bw > 0 ? i - bw : 0;
        for (int64_t j = lo; j <= i; j++) {
            double s = Sb[i * W + i - j];
            for (int64_t k = lo; k < j; k++) s -= Sb[i * W + i - k] * Sb[j * W + j - k];
            if (i == j) {
                if (!(s > rtol * Sb[i * W])) {
                    if (stop) return -1.0;
                    Sb[i * W] = 0.0;
                } else {
                    if (s / Sb[i * W] < worst) worst = s / Sb[i * W];
                    Sb[i * W] = sqrt(s);
                }
            } else {
                Sb[i * W + i - j] = Sb[j * W] > 0.0 ? s / Sb[j * W] : 0.0;
            }
        }
    }
    return worst;
}

static void cho_solve_band(const double *Lb, int64_t mu, int64_t bw, double *r) {
    int64_t W = bw + 1;
    for (int64_t i = 0; i < mu; i++) {
        double s = r[i];
        for (int64_t k = i - bw > 0 ? i - bw : 0; k < i; k++) s -= Lb[i * W + i - k] * r[k];
        r[i] = s / Lb[i * W];
    }
    for (int64_t i = mu - 1; i >= 0; i--) {
        double s = r[i];
        int64_t hi = i + bw + 1 < mu ? i + bw + 1 : mu;
        for (int64_t k = i + 1; k < hi; k++) s -= Lb[k * W + k - i] * r[k];
        r[i] = s / Lb[i * W];
    }
}

void mb_schur(const mb_model *md, const mb_unknowns *u, const double *bodies,
              const double *child6, const double *parent6, double *S, int banded) {
    /* S = G_U^T M^-1 G_U summed body by body over the components acting on it: the lower
     * triangle in banded storage, or (banded 0) all of it, mu x mu. */
    double h[6];
    int64_t W = u->bw + 1;
    for (int64_t b = 0; b < md->n; b++) {
        for (int64_t x = u->inc_ptr[b]; x < u->inc_ptr[b + 1]; x++) {
            int64_t kx = u->inc[2 * x], sx = u->inc[2 * x + 1];
            const double *gx = (sx == 0 ? child6 : parent6) + 6 * u->U[kx];
            mb_minv(bodies + MB_BODY_W * b, gx, h);
            for (int64_t yy = u->inc_ptr[b]; yy < u->inc_ptr[b + 1]; yy++) {
                int64_t ky = u->inc[2 * yy], sy = u->inc[2 * yy + 1];
                if (ky > kx) continue;
                const double *gy = (sy == 0 ? child6 : parent6) + 6 * u->U[ky];
                double s = 0.0;
                for (int r = 0; r < 6; r++) s += gy[r] * h[r];
                if (banded) {
                    S[kx * W + kx - ky] += s;
                } else {
                    S[kx * u->mu + ky] += s;
                    if (ky != kx) S[ky * u->mu + kx] += s;
                }
            }
        }
    }
}

void mb_cho_solve_dense(const double *L, int64_t ld, int64_t r, double *x) {
    for (int64_t i = 0; i < r; i++) {
        double xi = x[i];
        for (int64_t k = 0; k < i; k++) xi -= L[i * ld + k] * x[k];
        x[i] = xi / L[i * ld + i];
    }
    for (int64_t i = r - 1; i >= 0; i--) {
        double xi = x[i];
        for (int64_t k = i + 1; k < r; k++) xi -= L[k * ld + i] * x[k];
        x[i] = xi / L[i * ld + i];
    }
}

double mb_inv_length(const mb_model *md, const mb_unknowns *u, const double *child6,
                     const double *parent6) {
    /* 1 / the model's length scale: the rms moment arm |r x e| / |e| of the unknown
     * components' force columns, both sides (mbody.solve.nullspace.length_scale). */
    double num = 0.0;
    int64_t cnt = 0;
    for (int64_t k = 0; k < u->mu; k++) {
        int64_t i = u->U[k];
        int sides = parent_of(md, i) >= 0 ? 2 : 1;
        for (int side = 0; side < sides; side++) {
            const double *g = (side == 0 ? child6 : parent6) + 6 * i;
            double f = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
            double m = g[3] * g[3] + g[4] * g[4] + g[5] * g[5];
            if (f > 0.0 && m > 0.0) num += m / f, cnt++;
        }
    }
    return cnt ? 1.0 / sqrt(num / (double)cnt) : 1.0;
}

void mb_orthonormal(double *Q, int64_t rows, int64_t cols) {
    /* In place: an orthonormal basis of Q's columns (rows x cols, row-major, full column
     * rank): modified Gram-Schmidt, each column orthogonalised twice ("twice is enough"). */
    for (int64_t a = 0; a < cols; a++) {
        for (int pass = 0; pass < 2; pass++)
            for (int64_t b = 0; b < a; b++) {
                double d = 0.0;
                for (int64_t i = 0; i < rows; i++) d += Q[i * cols + b] * Q[i * cols + a];
                for (int64_t i = 0; i < rows; i++) Q[i * cols + a] -= d * Q[i * cols + b];
            }
        double norm = 0.0;
        for (int64_t i = 0; i < rows; i++) norm += Q[i * cols + a] * Q[i * cols + a];
        norm = sqrt(norm);
        for (int64_t i = 0; i < rows; i++) Q[i * cols + a] /= norm;
    }
}

void mb_dot_add(double *s, double *c, double a, double b) {
    /* (s, c) += a b, compensated (TwoProduct by Dekker's split, TwoSum): Ogita, Rump and
     * Oishi's Dot2, residuals as if computed in twice the working precision. */
    double p = a * b, f = SPLIT * a;
    double ah = f - (f - a), al = a - ah;
    f = SPLIT * b;
    double bh = f - (f - b), bl = b - bh;
    double ep = al * bl - (((p - ah * bh) - al * bh) - ah * bl);
    double total = *s + p, z = total - *s;
    double es = (*s - (total - z)) + (p - z);
    *s = total;
    *c = *c + ep + es;
}

/* r1 = r6 - (M a - G_U lam), r2 = gam - G_U^T a; returns the backward error. */
static double residual(const mb_model *md, const mb_unknowns *u, mb_work *w, double normK,
                       double *r1, double *r2) {
    int64_t n = md->n, mu = u->mu;
    const double *r6 = w->r6, *acc = w->acc, *lam = w->lamU, *gam = w->gam;
    for (int64_t i = 0; i < n; i++) {
        const double *body = md->bodies + MB_BODY_W * i, *J = body + B_J;
        double m = body[B_MASS];
        const double *a6 = acc + 6 * i;
        for (int a = 0; a < 3; a++) {
            r1[6 * i + a] = r6[6 * i + a] - m * a6[a];
            r1[6 * i + 3 + a] = r6[6 * i + 3 + a] -
                                (J[3 * a] * a6[3] + J[3 * a + 1] * a6[4] + J[3 * a + 2] * a6[5]);
        }
    }
    mb_add_g(md, u, w->child6, w->parent6, lam, r1, 1.0);
    gt(md, u, w->child6, w->parent6, acc, r2);
    double res = 0.0, normx = 0.0, normf = 0.0;
    for (int64_t k = 0; k < mu; k++) {
        r2[k] = gam[k] - r2[k];
        res += r2[k] * r2[k];
        normx += lam[k] * lam[k];
        normf += gam[k] * gam[k];
    }
    for (int64_t i = 0; i < 6 * n; i++) {
        res += r1[i] * r1[i];
        normx += acc[i] * acc[i];
        normf += r6[i] * r6[i];
    }
    double denom = normK * sqrt(normx) + sqrt(normf);
    return denom > 0 ? sqrt(res) / denom : sqrt(res);
}

/* acc = M^-1 (rhs), per body. */
static void minv_all(const mb_model *md, const double *rhs, double *acc) {
    for (int64_t i = 0; i < md->n; i++) mb_minv(md->bodies + MB_BODY_W * i, rhs + 6 * i, acc + 6 * i);
}

/* The same solve with the factor in hand (refinement): rhs r6 -> acc, gam -> lam. */
static void solve_again(const mb_model *md, const mb_unknowns *u, mb_work *w,
                        const double *r6, const double *gam, double *acc, double *lam) {
    minv_all(md, r6, acc);
    gt(md, u, w->child6, w->parent6, acc, lam);
    for (int64_t k = 0; k < u->mu; k++) lam[k] = gam[k] - lam[k];
    cho_solve_band(w->Sb, u->mu, u->bw, lam);
    memcpy(w->rhs, r6, sizeof(double) * 6 * md->n);
    mb_add_g(md, u, w->child6, w->parent6, lam, w->rhs, 1.0);
    minv_all(md, w->rhs, acc);
}

/* S's pivoted Cholesky factor, from its lower band S0 (mu x (bw + 1)): symmetric
 * pivoting on each pivot's share of its diagonal entry (diag), columns whose share is
 * PIVOT_RTOL or less left out; the factor's columns in pivot order (perm) in the lower
 * triangle of S (mu x mu): L11 (r x r), then L21 in the rows of the columns left out.
 * Left-looking: each step forms only the pivot's column, from S0 and the columns before
 * it, and the remaining diagonal entries (rem) are updated by its squares; only the
 * factor's rows move with a pivot. Every entry is the same sum, in the same order, as the
 * outer-product factor of the whole symmetric matrix (the route's first version), so the
 * numbers are those, for about half its instructions (no trailing update of both
 * triangles, no swap of whole rows and columns). Returns the rank r. */
static int64_t pivoted_cholesky(const mb_unknowns *u, const double *S0, double *S,
                                const double *diag, double *rem, int64_t *perm) {
    int64_t mu = u->mu, bw = u->bw, W = bw + 1;
    for (int64_t k = 0; k < mu; k++) perm[k] = k, rem[k] = diag[k];
    int64_t r = 0;
    for (int64_t k = 0; k < mu; k++) {
        int64_t jb = -1;
        double best = PIVOT_RTOL;
        for (int64_t j = k; j < mu; j++) {
            double dj = diag[perm[j]];
            if (dj > 0.0 && rem[j] > best * dj) jb = j, best = rem[j] / dj;
        }
        if (jb < 0) break;
        if (jb != k) {
            for (int64_t c = 0; c < k; c++) {
                double t = S[k * mu + c];
                S[k * mu + c] = S[jb * mu + c], S[jb * mu + c] = t;
            }
            int64_t t = perm[k];
            perm[k] = perm[jb], perm[jb] = t;
            double tr = rem[k];
            rem[k] = rem[jb], rem[jb] = tr;
        }
        double d = sqrt(rem[k]);
        S[k * mu + k] = d;
        int64_t p = perm[k];
        const double *Lk = S + k * mu;
        for (int64_t i = k + 1; i < mu; i++) {
            int64_t a = perm[i], hi = a > p ? a : p, lo = a > p ? p : a;
            double s = hi - lo <= bw ? S0[hi * W + hi - lo] : 0.0;
            double *Li = S + i * mu;
            for (int64_t c = 0; c < k; c++) s -= Li[c] * Lk[c];
            Li[k] = s / d;
            rem[i] -= Li[k] * Li[k];
        }
        r++;
    }
    return r;
}

/* Exactly redundant joints, fast: S factorised with symmetric pivoting
 * (pivoted_cholesky); the columns left with less than PIVOT_RTOL are redundant
 * if G_U's columns themselves are combinations x_j of the kept ones. Then lam on the
 * kept columns, the minimum-norm lam through the null space [-X; I], and the not-unique
 * flags. w->lamU holds gam - G_U^T M^-1 r on entry. Returns the rank, or -1 (the
 * null-space route takes over). S0: S's lower band before factorisation. */
static int64_t redundant(const mb_model *md, const mb_unknowns *u, mb_work *w) {
    int64_t n = md->n, mu = u->mu, W = u->bw + 1;
    if (mb_ensure_dense(w)) return -1;
    mb_dense *dn = w->dense;
    double *S = dn->S, *diag = dn->diag, *X = dn->X;
    int64_t *perm = dn->perm;
    for (int64_t k = 0; k < mu; k++) diag[k] = w->S0[k * W];
    int64_t r = pivoted_cholesky(u, w->S0, S, diag, dn->rhs, perm); /* rhs: scratch here */
    if (r == mu || r == 0) return -1;
    int64_t nd = mu - r;
    /* X (r x nd): L11^T X = L21^T, the kept columns' combinations for the dropped ones */
    for (int64_t a = 0; a < nd; a++) {
        for (int64_t i = 0; i < r; i++) X[i * nd + a] = S[(r + a) * mu + i];
        for (int64_t i = r - 1; i >= 0; i--) {
            double xia = X[i * nd + a];
            for (int64_t k = i + 1; k < r; k++) xia -= S[k * mu + i] * X[k * nd + a];
            X[i * nd + a] = xia / S[i * mu + i];
        }
    }
    double inv_l = mb_inv_length(md, u, w->child6, w->parent6);
    double *res = dn->res, *coef = dn->coef;
    for (int64_t a = 0; a < nd; a++) { /* G_j - G_I x_j = 0 for every dropped column j? */
        memset(coef, 0, sizeof(double) * mu);
        coef[perm[r + a]] = 1.0;
        for (int64_t i = 0; i < r; i++) coef[perm[i]] = -X[i * nd + a];
        memset(res, 0, sizeof(double) * 6 * n);
        mb_add_g(md, u, w->child6, w->parent6, coef, res, 1.0);
        double big = 0.0, small = 0.0;
        for (int64_t k = 0; k < mu; k++) {
            if (coef[k] == 0.0) continue;
            int64_t i = u->U[k];
            int has_p = parent_of(md, i) >= 0;
            double g2 = 0.0;
            for (int c = 0; c < 6; c++) {
                double wt = c < 3 ? 1.0 : inv_l, gc = w->child6[6 * i + c] * wt;
                g2 += gc * gc;
                if (has_p) {
                    double gp = w->parent6[6 * i + c] * wt;
                    g2 += gp * gp;
                }
            }
            big += fabs(coef[k]) * sqrt(g2);
        }
        for (int64_t b = 0; b < n; b++)
            for (int c = 0; c < 6; c++) {
                double rc = res[6 * b + c] * (c < 3 ? 1.0 : inv_l);
                small += rc * rc;
            }
        if (!(sqrt(small) <= DEPENDENT_RTOL * big)) return -1;
    }
    /* lam on the kept columns (the dropped ones 0), then the minimum-norm lam */
    double *rhs = dn->rhs, *lamU = w->lamU;
    for (int64_t i = 0; i < r; i++) rhs[i] = lamU[perm[i]];
    mb_cho_solve_dense(S, mu, r, rhs);
    memset(lamU, 0, sizeof(double) * mu);
    for (int64_t i = 0; i < r; i++) lamU[perm[i]] = rhs[i];
    double *Q = dn->Q;
    memset(Q, 0, sizeof(double) * mu * nd);
    for (int64_t a = 0; a < nd; a++) {
        Q[perm[r + a] * nd + a] = 1.0;
        for (int64_t i = 0; i < r; i++) Q[perm[i] * nd + a] = -X[i * nd + a];
    }
    mb_orthonormal(Q, mu, nd);
    for (int64_t a = 0; a < nd; a++) { /* lam minus its part in the null space */
        double s2 = 0.0;
        for (int64_t k = 0; k < mu; k++) s2 += Q[k * nd + a] * lamU[k];
        for (int64_t k = 0; k < mu; k++) lamU[k] -= s2 * Q[k * nd + a];
    }
    for (int64_t k = 0; k < mu; k++) {
        double s2 = 0.0;
        for (int64_t a = 0; a < nd; a++) s2 += Q[k * nd + a] * Q[k * nd + a];
        w->nonunique[k] = sqrt(s2) > 1e-8;
    }
    memcpy(dn->rhs6, w->r6, sizeof(double) * 6 * n);
    mb_add_g(md, u, w->child6, w->parent6, lamU, dn->rhs6, 1.0);
    minv_all(md, dn->rhs6, w->acc);
    return r;
}

/* |K|_F = sqrt(|M|_F^2 + 2 |G_U|_F^2), the scale of the backward error (`residual`). */
static double norm_k(const mb_model *md, const mb_unknowns *u, const mb_work *w) {
    double nk = 0.0;
    for (int64_t i = 0; i < md->n; i++) {
        const double *body = md->bodies + MB_BODY_W * i;
        nk += 3.0 * body[B_MASS] * body[B_MASS];
        for (int a = 0; a < 9; a++) nk += body[B_J + a] * body[B_J + a];
    }
    for (int64_t k = 0; k < u->mu; k++) {
        int64_t i = u->U[k];
        int has_p = parent_of(md, i) >= 0;
        for (int r = 0; r < 6; r++) {
            nk += 2.0 * w->child6[6 * i + r] * w->child6[6 * i + r];
            if (has_p) nk += 2.0 * w->parent6[6 * i + r] * w->parent6[6 * i + r];
        }
    }
    return sqrt(nk);
}

int mb_constrained(const mb_model *md, const mb_unknowns *u, mb_work *w, int refine,
                   int64_t *rank_out, double *berr_out, int *path_out) {
    int64_t n = md->n, mu = u->mu, bw = u->bw, W = bw + 1;
    double *acc = w->acc, *lamU = w->lamU;
    minv_all(md, w->r6, acc);
    memset(w->nonunique, 0, (size_t)mu);
    *rank_out = 0, *path_out = 0;
    if (berr_out != NULL) *berr_out = 0.0;
    if (mu == 0) return 0;
    memset(w->Sb, 0, sizeof(double) * mu * W);
    mb_schur(md, u, md->bodies, w->child6, w->parent6, w->Sb, 1);
    /* lam = S^-1 (gam - G_U^T M^-1 r), a = M^-1 (r + G_U lam) */
    gt(md, u, w->child6, w->parent6, acc, lamU);
    for (int64_t k = 0; k < mu; k++) lamU[k] = w->gam[k] - lamU[k];
    int64_t rank = mu;
    int path = 0;
    memcpy(w->S0, w->Sb, sizeof(double) * mu * W);
    /* a mechanism redundant at its generic configurations never has a trusted S */
    if (u->generic_rank == mu && mb_band_cholesky(w->Sb, mu, bw, PIVOT_RTOL, 1) >= 0.0) {
        cho_solve_band(w->Sb, mu, bw, lamU);
        memcpy(w->rhs, w->r6, sizeof(double) * 6 * n);
        mb_add_g(md, u, w->child6, w->parent6, lamU, w->rhs, 1.0);
        minv_all(md, w->rhs, acc);
    } else {
        /* exactly redundant joints (the usual reason) are solved on S with pivoting;
         * anything else, or an inconsistent answer, goes to the null-space solve (spatial
         * models only: a planar one's robust solve keeps the in-plane rows, and the
         * pivoted route would answer its out-of-plane rows too, differently) */
        path = 2;
        rank = md->planar ? -1 : redundant(md, u, w);
        if (rank >= 0) {
            double berr = residual(md, u, w, norm_k(md, u, w), w->r1, w->r2);
            if (berr > REDUNDANT_BERR) {
                rank = -1;
            } else {
                *rank_out = rank, *path_out = path;
                if (berr_out != NULL) *berr_out = berr;
                return 0;
            }
        }
        path = 1;
        int singular = mb_null_space(md, u, w, refine, &rank);
        if (singular) {
            *rank_out = rank, *path_out = path;
            return singular;
        }
    }
    *rank_out = rank, *path_out = path;
    /* the backward error, and the refinement it decides, only for a caller that asks
     * (a simulation's right-hand side does not: a sixth of a small model's evaluation) */
    if (!refine && berr_out == NULL) return 0;
    double normK = norm_k(md, u, w);
    double berr = residual(md, u, w, normK, w->r1, w->r2);
    if (refine && path == 0 && berr > 1e-15) {
        solve_again(md, u, w, w->r1, w->r2, w->dacc, w->dlam);
        for (int64_t i = 0; i < 6 * n; i++) acc[i] += w->dacc[i];
        for (int64_t k = 0; k < mu; k++) lamU[k] += w->dlam[k];
        berr = residual(md, u, w, normK, w->r1, w->r2);
    }
    if (berr_out != NULL) *berr_out = berr;
    return 0;
}
