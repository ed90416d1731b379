/* The robust solve on G_U's geometry (what mbody.solve.nullspace did in numpy before
 * 0.3): G^ = T G_U C^-1 (rows scaled to one length,
 * columns to unit norm), its SVD G^ = U1 s1 V1^T with the rank decided at G_RANK_RTOL,
 * the allowed motions U2 (the complement of U1), their reduced mass matrix
 * U2^T M^ U2 (a motion without mass: the singular code), REFINE_STEPS rounds of
 * refinement with compensated residuals, the minimum-norm lam and the not-unique flags.
 * Reads w->r6, w->gam, w->stab; writes w->acc, w->lamU, w->nonunique. */
#include <string.h>

#include "internal.h"

typedef struct {
    int64_t n, npr, nr, mu, rank, dof;
    const int *per;
    const double *U1, *U2, *V1, *s1, *Mb, *Lr; /* U1: Uf (nr x p) with stride p */
    int64_t p;
} ns_system;

/* One solve of M^ a^ - G^ lam^ = rh, G^T a^ = gh + sh with the SVD in hand; the
 * stabilisation sh through s^3 / (s^4 + reg^4) instead of 1 / s. */
static void ns_inner(const ns_system *sy, const double *rh, const double *gh, const double *sh,
                     double reg, double *ah, double *lamh, double *cvec, double *u1c,
                     double *rest, double *z, double *t2) {
    int64_t nr = sy->nr, rank = sy->rank, dof = sy->dof, npr = sy->npr, mu = sy->mu, p = sy->p;
    double reg4 = reg * reg * reg * reg;
    for (int64_t a = 0; a < rank; a++) {
        double vg = 0.0, vs = 0.0, s = sy->s1[a], s3 = s * s * s;
        for (int64_t k = 0; k < mu; k++) {
            vg += sy->V1[k * p + a] * gh[k];
            vs += sy->V1[k * p + a] * sh[k];
        }
        cvec[a] = vg / s + vs * s3 / (s3 * s + reg4);
    }
    for (int64_t r = 0; r < nr; r++) {
        double s = 0.0;
        for (int64_t a = 0; a < rank; a++) s += sy->U1[r * p + a] * cvec[a];
        u1c[r] = s;
    }
    for (int64_t r = 0; r < nr; r++) rest[r] = rh[r]; /* rh - M^ U1 c */
    for (int64_t b = 0; b < sy->n; b++)
        for (int64_t a = 0; a < npr; a++)
            for (int64_t e = 0; e < npr; e++)
                rest[b * npr + a] -= sy->Mb[(b * npr + a) * npr + e] * u1c[b * npr + e];
    for (int64_t d = 0; d < dof; d++) {
        double s = 0.0;
        for (int64_t r = 0; r < nr; r++) s += sy->U2[r * dof + d] * rest[r];
        z[d] = s;
    }
    mb_cho_solve_dense(sy->Lr, dof, dof, z); /* Lr Lr^T z = U2^T rest */
    for (int64_t r = 0; r < nr; r++) {
        double s = 0.0;
        for (int64_t d = 0; d < dof; d++) s += sy->U2[r * dof + d] * z[d];
        ah[r] = u1c[r] + s;
    }
    for (int64_t b = 0; b < sy->n; b++)
        for (int64_t a = 0; a < npr; a++) {
            double s = -rh[b * npr + a];
            for (int64_t e = 0; e < npr; e++) s += sy->Mb[(b * npr + a) * npr + e] * ah[b * npr + e];
            t2[b * npr + a] = s;
        }
    for (int64_t a = 0; a < rank; a++) {
        double s = 0.0;
        for (int64_t r = 0; r < nr; r++) s += sy->U1[r * p + a] * t2[r];
        cvec[a] = s / sy->s1[a];
    }
    for (int64_t k = 0; k < mu; k++) {
        double s = 0.0;
        for (int64_t a = 0; a < rank; a++) s += sy->V1[k * p + a] * cvec[a];
        lamh[k] = rank ? s : 0.0;
    }
}

int mb_null_space(const mb_model *md, const mb_unknowns *u, mb_work *w, int refine,
                  int64_t *rank_out) {
    static const int per_planar[3] = {0, 1, 5}, per_spatial[6] = {0, 1, 2, 3, 4, 5};
    int64_t n = md->n, mu = u->mu;
    const int *per = md->planar ? per_planar : per_spatial;
    int64_t npr = md->planar ? 3 : 6, nr = n * npr;
    memset(w->nonunique, 0, (size_t)mu);
    *rank_out = 0;
    if (mb_ensure_ns(w, nr, mu)) return -1;
    mb_ns *s = w->ns;
    double inv_l = mb_inv_length(md, u, w->child6, w->parent6);
    double *T = s->T, *A = s->A, *C = s->C;
    for (int64_t b = 0; b < n; b++)
        for (int64_t a = 0; a < npr; a++) T[b * npr + a] = per[a] < 3 ? 1.0 : inv_l;
    memset(A, 0, sizeof(double) * nr * mu);
    for (int64_t k = 0; k < mu; k++) {
        int64_t i = u->U[k], j = md->comps_i[4 * i];
        int64_t p = md->joints_i[3 * j], c = md->joints_i[3 * j + 1];
        C[k] = 1.0;
        for (int64_t a = 0; a < npr; a++) {
            A[(c * npr + a) * mu + k] += w->child6[6 * i + per[a]] * T[c * npr + a];
            if (p >= 0) A[(p * npr + a) * mu + k] += w->parent6[6 * i + per[a]] * T[p * npr + a];
        }
        double s2 = 0.0;
        for (int64_t r = 0; r < nr; r++) s2 += A[r * mu + k] * A[r * mu + k];
        if (s2 > 0.0) {
            C[k] = sqrt(s2);
            for (int64_t r = 0; r < nr; r++) A[r * mu + k] /= C[k];
        }
    }
    int64_t pmin = nr < mu ? nr : mu;
    mb_svd(A, nr, mu, s->sv, s->Uf, s->V, s->tmp);
    int64_t rank = 0;
    for (int64_t a = 0; a < pmin; a++)
        if (s->sv[a] > G_RANK_RTOL * s->sv[0]) rank++;
    /* a redundant mechanism off its manifold: the extra singular values are the
     * distance, not constraints (mb_unknowns.generic_rank) */
    if (rank > u->generic_rank && s->sv[u->generic_rank] <= MB_GENERIC_GAP * s->sv[0])
        rank = u->generic_rank;
    int64_t dof = nr - rank;
    *rank_out = rank;
    /* U1 = Uf[:, :rank] (stride pmin); U2 (nr x dof) its complement. U1 is copied to a
     * contiguous block first (mb_complete reads nr x rank). */
    double *U1c = s->tmp;
    for (int64_t r = 0; r < nr; r++)
        for (int64_t a = 0; a < rank; a++) U1c[r * rank + a] = s->Uf[r * pmin + a];
    double *U2 = s->B;
    mb_complete(U1c, nr, rank, U2, s->hh);
    /* M^ = T M T per body (npr x npr blocks) */
    double *Mb = s->Mb;
    for (int64_t b = 0; b < n; b++) {
        const double *body = md->bodies + MB_BODY_W * b;
        for (int64_t a = 0; a < npr; a++)
            for (int64_t e = 0; e < npr; e++) {
                int ra = per[a], re = per[e];
                double v = 0.0;
                if (ra < 3 && re < 3) v = ra == re ? body[B_MASS] : 0.0;
                else if (ra >= 3 && re >= 3) v = body[B_J + 3 * (ra - 3) + (re - 3)] * inv_l * inv_l;
                Mb[(b * npr + a) * npr + e] = v;
            }
    }
    double *MU2 = s->MU2, *red = s->red, *Lr = s->Lr;
    memset(MU2, 0, sizeof(double) * nr * dof);
    for (int64_t b = 0; b < n; b++)
        for (int64_t a = 0; a < npr; a++)
            for (int64_t e = 0; e < npr; e++) {
                double mbe = Mb[(b * npr + a) * npr + e];
                if (mbe != 0.0)
                    for (int64_t d = 0; d < dof; d++)
                        MU2[(b * npr + a) * dof + d] += mbe * U2[(b * npr + e) * dof + d];
            }
    for (int64_t i = 0; i < dof; i++)
        for (int64_t j = 0; j < dof; j++) {
            double acc = 0.0;
            for (int64_t r = 0; r < nr; r++) acc += U2[r * dof + i] * MU2[r * dof + j];
            red[i * dof + j] = acc;
        }
    memset(Lr, 0, sizeof(double) * dof * dof);
    for (int64_t i = 0; i < dof; i++) /* Cholesky, pivots against their diagonal entries */
        for (int64_t j = 0; j <= i; j++) {
            double sij = 0.5 * (red[i * dof + j] + red[j * dof + i]);
            for (int64_t k = 0; k < j; k++) sij -= Lr[i * dof + k] * Lr[j * dof + k];
            if (i == j) {
                if (!(sij > SINGULAR_RTOL * red[i * dof + i])) {
                    /* a motion the joints allow without mass: the largest entry of the
                     * reduced mass matrix's softest mode names it */
                    double *vec = s->cvec, *motion = s->t2;
                    mb_eig_smallest(red, dof, vec, s->eig);
                    int64_t kmax = 0;
                    for (int64_t r = 0; r < nr; r++) {
                        double m = 0.0;
                        for (int64_t d = 0; d < dof; d++) m += U2[r * dof + d] * vec[d];
                        motion[r] = m;
                        if (fabs(m) > fabs(motion[kmax])) kmax = r;
                    }
                    return (int)(1 + 6 * (kmax / npr) + per[kmax % npr]);
                }
                Lr[i * dof + i] = sqrt(sij);
            } else {
                Lr[i * dof + j] = sij / Lr[j * dof + j];
            }
        }
    double *rh = s->rh, *gh = s->gh, *sh = s->sh, *ah = s->ah, *lamh = s->lamh;
    for (int64_t b = 0; b < n; b++)
        for (int64_t a = 0; a < npr; a++) rh[b * npr + a] = w->r6[6 * b + per[a]] * T[b * npr + a];
    for (int64_t k = 0; k < mu; k++) { /* gamma's physical part exactly, Baumgarte's regularised */
        gh[k] = (w->gam[k] - w->stab[k]) / C[k];
        sh[k] = w->stab[k] / C[k];
    }
    double reg = pmin ? STAB_RTOL * s->sv[0] : 0.0;
    ns_system sy = {n, npr, nr, mu, rank, dof, per, s->Uf, U2, s->V, s->sv, Mb, Lr, pmin};
    double *u1c = s->tmp, *z = s->tmp + nr;
    ns_inner(&sy, rh, gh, sh, reg, ah, lamh, s->cvec, u1c, s->rest, z, s->t2);
    if (refine) {
        double *r1 = s->r1, *r2 = s->r2, *da = s->da, *dl = s->dl;
        for (int step = 0; step < REFINE_STEPS; step++) {
            for (int64_t b = 0; b < n; b++) /* r^ - M^ a^ + G^ lam^, compensated */
                for (int64_t a = 0; a < npr; a++) {
                    int64_t row = b * npr + a;
                    double sm = rh[row], cm = 0.0;
                    for (int64_t e = 0; e < npr; e++)
                        mb_dot_add(&sm, &cm, -Mb[(b * npr + a) * npr + e], ah[b * npr + e]);
                    for (int64_t k = 0; k < mu; k++)
                        if (A[row * mu + k] != 0.0) mb_dot_add(&sm, &cm, A[row * mu + k], lamh[k]);
                    r1[row] = sm + cm;
                }
            for (int64_t k = 0; k < mu; k++) { /* gamma^ - G^T a^ */
                double sm = gh[k], cm = 0.0;
                for (int64_t row = 0; row < nr; row++)
                    if (A[row * mu + k] != 0.0) mb_dot_add(&sm, &cm, -A[row * mu + k], ah[row]);
                r2[k] = sm + cm;
            }
            memset(sh, 0, sizeof(double) * mu);
            ns_inner(&sy, r1, r2, sh, 0.0, da, dl, s->cvec, u1c, s->rest, z, s->t2);
            for (int64_t r = 0; r < nr; r++) ah[r] += da[r];
            for (int64_t k = 0; k < mu; k++) lamh[k] += dl[k];
        }
    }
    double *lamU = w->lamU;
    for (int64_t k = 0; k < mu; k++) lamU[k] = lamh[k] / C[k];
    if (rank < mu) { /* minimum-norm lam in the model's units; name what the null space touches */
        int64_t nd = mu - rank;
        double *V1c = s->tmp, *Q = s->Q;
        for (int64_t k = 0; k < mu; k++)
            for (int64_t a = 0; a < rank; a++) V1c[k * rank + a] = s->V[k * pmin + a];
        mb_complete(V1c, mu, rank, Q, s->hh); /* the null space of G^, unit columns */
        for (int64_t k = 0; k < mu; k++)
            for (int64_t a = 0; a < nd; a++) Q[k * nd + a] /= C[k];
        mb_orthonormal(Q, mu, nd);
        for (int64_t a = 0; a < nd; a++) {
            double pr = 0.0;
            for (int64_t k = 0; k < mu; k++) pr += Q[k * nd + a] * lamU[k];
            s->cvec[a] = pr;
        }
        for (int64_t k = 0; k < mu; k++) {
            double s2 = 0.0, q2 = 0.0;
            for (int64_t a = 0; a < nd; a++) {
                s2 += Q[k * nd + a] * s->cvec[a];
                q2 += Q[k * nd + a] * Q[k * nd + a];
            }
            lamU[k] -= s2;
            w->nonunique[k] = sqrt(q2) > 1e-8;
        }
    }
    memset(w->acc, 0, sizeof(double) * 6 * n);
    for (int64_t b = 0; b < n; b++)
        for (int64_t a = 0; a < npr; a++) w->acc[6 * b + per[a]] = ah[b * npr + a] * T[b * npr + a];
    return 0;
}
