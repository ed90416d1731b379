/* Views of the packed model and unknowns (every size and index checked once, so that
 * the evaluations never read or write out of bounds), and the scratch memory of one
 * (model, unknowns): allocated once, reused by every call; the dense buffers of the two
 * robust routes only when first needed. */
#include <stdlib.h>
#include <string.h>

#include "internal.h"

static int bad_index(int64_t i, int64_t lo, int64_t hi) { return i < lo || i >= hi; }

/* The stack depth a postfix program reaches, or -1 when it is malformed. */
static int64_t program_depth(const int64_t *codes, int64_t start, int64_t end) {
    int64_t top = 0, deepest = 0;
    for (int64_t p = start; p < end; p++) {
        int64_t c = codes[p];
        if (c == MB_OP_NUM || c == MB_OP_T) top++;
        else if (c == MB_OP_NEG || (c >= MB_OP_SIN && c <= MB_OP_ABS)) {
            if (top < 1) return -1;
        } else if (c >= MB_OP_ADD && c <= MB_OP_POW) {
            if (top < 2) return -1;
            top--;
        } else return -1;
        if (top > deepest) deepest = top;
    }
    return top == 1 ? deepest : -1;
}

int mb_model_view(mb_model *md, const double *F, int64_t nF, const int64_t *I, int64_t nI,
                  int planar) {
    if (nI < MB_I_HEADER) return -1;
    for (int a = 0; a < MB_I_HEADER; a++)
        if (I[a] < 0 || I[a] > ((int64_t)1 << 40)) return -1;
    md->n = I[0], md->k = I[1], md->s = I[2], md->nj = I[3], md->m = I[4];
    md->n_expr = I[5], md->n_code = I[6], md->n_varying = I[7], md->n_laws = I[8];
    md->n_known = I[9];
    md->planar = planar ? 1 : 0;
    int64_t wantI = MB_I_HEADER + 3 * md->k + 2 * md->s + 3 * md->nj + 4 * md->m +
                    3 * md->n_varying + 3 * md->n_laws + 2 * md->n_known +
                    (md->n_expr + 1) + md->n_code;
    int64_t wantF = 3 + MB_BODY_W * md->n + MB_LOAD_W * md->k + MB_SPRING_W * md->s +
                    MB_JOINT_W * md->nj + MB_COMP_W * md->m + md->n_code;
    if (nI != wantI || nF != wantF) return -1;
    const double *f = F;
    md->gravity = f, f += 3;
    md->bodies = f, f += MB_BODY_W * md->n;
    md->loads = f, f += MB_LOAD_W * md->k;
    md->springs = f, f += MB_SPRING_W * md->s;
    md->joints = f, f += MB_JOINT_W * md->nj;
    md->comps_f = f, f += MB_COMP_W * md->m;
    md->numbers = f;
    const int64_t *i = I + MB_I_HEADER;
    md->loads_i = i, i += 3 * md->k;
    md->springs_i = i, i += 2 * md->s;
    md->joints_i = i, i += 3 * md->nj;
    md->comps_i = i, i += 4 * md->m;
    md->varying = i, i += 3 * md->n_varying;
    md->laws = i, i += 3 * md->n_laws;
    md->known = i, i += 2 * md->n_known;
    md->starts = i, i += md->n_expr + 1;
    md->codes = i;
    /* every index in range */
    for (int64_t j = 0; j < md->k; j++)
        if (bad_index(md->loads_i[3 * j], 0, md->n)) return -1;
    for (int64_t j = 0; j < md->s; j++)
        if (bad_index(md->springs_i[2 * j], -1, md->n) ||
            bad_index(md->springs_i[2 * j + 1], -1, md->n))
            return -1;
    for (int64_t j = 0; j < md->nj; j++)
        if (bad_index(md->joints_i[3 * j], -1, md->n) ||
            bad_index(md->joints_i[3 * j + 1], 0, md->n))
            return -1;
    for (int64_t c = 0; c < md->m; c++) {
        const int64_t *ci = md->comps_i + 4 * c;
        if (bad_index(ci[0], 0, md->nj) || bad_index(ci[1], 0, MB_KINDS) ||
            bad_index(ci[2], 0, 3) || bad_index(ci[3], -1, md->n_laws))
            return -1;
    }
    for (int64_t j = 0; j < md->n_varying; j++)
        if (bad_index(md->varying[3 * j], 0, md->k) ||
            bad_index(md->varying[3 * j + 1], 0, 3) ||
            bad_index(md->varying[3 * j + 2], 0, md->n_expr))
            return -1;
    for (int64_t j = 0; j < 3 * md->n_laws; j++)
        if (bad_index(md->laws[j], 0, md->n_expr)) return -1;
    for (int64_t j = 0; j < md->n_known; j++)
        if (bad_index(md->known[2 * j], 0, md->m) ||
            bad_index(md->known[2 * j + 1], 0, md->n_expr))
            return -1;
    if (md->starts[0] != 0 || md->starts[md->n_expr] != md->n_code) return -1;
    for (int64_t e = 0; e < md->n_expr; e++) {
        if (md->starts[e + 1] <= md->starts[e]) return -1;
        if (program_depth(md->codes, md->starts[e], md->starts[e + 1]) < 0) return -1;
    }
    return 0;
}

void mb_model_rebase(mb_model *out, const mb_model *md, const double *F0, const double *F) {
    *out = *md;
    out->gravity = F + (md->gravity - F0);
    out->bodies = F + (md->bodies - F0);
    out->loads = F + (md->loads - F0);
    out->springs = F + (md->springs - F0);
    out->joints = F + (md->joints - F0);
    out->comps_f = F + (md->comps_f - F0);
    out->numbers = F + (md->numbers - F0);
}

int mb_unknowns_view(mb_unknowns *u, const mb_model *md, const int64_t *Iu, int64_t nIu) {
    if (nIu < 3) return -1;
    u->mu = Iu[0], u->bw = Iu[1], u->nnz = Iu[2];
    u->generic_rank = u->mu;
    if (u->mu < 0 || u->mu > md->m || u->bw < 0 || u->nnz < 0 || u->nnz > 2 * u->mu)
        return -1;
    if (nIu != 3 + u->mu + md->n + 1 + 2 * u->nnz) return -1;
    u->U = Iu + 3;
    u->inc_ptr = u->U + u->mu;
    u->inc = u->inc_ptr + md->n + 1;
    if (u->bw >= (u->mu > 0 ? u->mu : 1)) return -1;
    for (int64_t k = 0; k < u->mu; k++)
        if (bad_index(u->U[k], 0, md->m)) return -1;
    if (u->inc_ptr[0] != 0 || u->inc_ptr[md->n] != u->nnz) return -1;
    for (int64_t b = 0; b < md->n; b++) {
        if (u->inc_ptr[b + 1] < u->inc_ptr[b]) return -1;
        int64_t lo = u->mu, hi = -1;
        for (int64_t x = u->inc_ptr[b]; x < u->inc_ptr[b + 1]; x++) {
            int64_t k = u->inc[2 * x], side = u->inc[2 * x + 1];
            if (bad_index(k, 0, u->mu) || bad_index(side, 0, 2)) return -1;
            const int64_t *ji = md->joints_i + 3 * md->comps_i[4 * u->U[k]];
            if (ji[side == 0 ? 1 : 0] != b) return -1; /* the component acts on b */
            if (k < lo) lo = k;
            if (k > hi) hi = k;
        }
        if (hi >= 0 && hi - lo > u->bw) return -1; /* S's band holds every pair */
    }
    return 0;
}

int64_t mb_pack_unknowns(const int64_t *child, const int64_t *parent, int64_t m, int64_t n,
                         const int64_t *U, int64_t mu, int64_t *out) {
    if (mu < 0 || n < 0) return -1;
    int64_t *Uo = out + 3, *inc_ptr = Uo + mu, *inc = inc_ptr + n + 1;
    for (int64_t b = 0; b <= n; b++) inc_ptr[b] = 0;
    for (int64_t k = 0; k < mu; k++) { /* count each body's entries */
        if (bad_index(U[k], 0, m)) return -1;
        const int64_t ends[2] = {child[U[k]], parent[U[k]]};
        for (int side = 0; side < 2; side++) {
            if (bad_index(ends[side], -1, n)) return -1;
            if (ends[side] >= 0) inc_ptr[ends[side] + 1]++;
        }
        Uo[k] = U[k];
    }
    for (int64_t b = 0; b < n; b++) inc_ptr[b + 1] += inc_ptr[b];
    int64_t *next = malloc((size_t)(n > 0 ? n : 1) * sizeof(int64_t)); /* each body's fill */
    if (next == NULL) return -2;
    memcpy(next, inc_ptr, (size_t)n * sizeof(int64_t));
    int64_t bw = 0;
    for (int64_t k = 0; k < mu; k++) { /* in U's order: each body's positions ascending */
        const int64_t ends[2] = {child[U[k]], parent[U[k]]};
        for (int side = 0; side < 2; side++) {
            int64_t b = ends[side];
            if (b < 0) continue;
            int64_t x = next[b]++;
            inc[2 * x] = k, inc[2 * x + 1] = side;
            int64_t spread = k - inc[2 * inc_ptr[b]]; /* from the body's first position */
            if (spread > bw) bw = spread;
        }
    }
    free(next);
    out[0] = mu, out[1] = bw, out[2] = inc_ptr[n];
    return 3 + mu + n + 1 + 2 * inc_ptr[n];
}

#define ALLOC(ptr, count)                                                               \
    do {                                                                                \
        size_t c_ = (size_t)(count);                                                    \
        (ptr) = calloc(c_ ? c_ : 1, sizeof(*(ptr)));                                    \
        if ((ptr) == NULL) goto fail;                                                   \
    } while (0)

mb_work *mb_work_new(const mb_model *md, const mb_unknowns *u) {
    mb_work *w = calloc(1, sizeof(mb_work));
    if (w == NULL) return NULL;
    int64_t n = md->n, m = md->m, nj = md->nj;
    int64_t mu = u ? u->mu : 0, bw = u ? u->bw : 0;
    w->n = n, w->m = m, w->nj = nj, w->k = md->k, w->s = md->s, w->mu = mu, w->bw = bw;
    w->n_expr = md->n_expr;
    ALLOC(w->R, 9 * n);
    ALLOC(w->r6, 6 * n);
    ALLOC(w->acc, 6 * n);
    ALLOC(w->rhs, 6 * n);
    ALLOC(w->r1, 6 * n);
    ALLOC(w->dacc, 6 * n);
    ALLOC(w->child6, 6 * m);
    ALLOC(w->parent6, 6 * m);
    ALLOC(w->W_e, 3 * m);
    ALLOC(w->W_P, 3 * m);
    ALLOC(w->gamma, m);
    ALLOC(w->phi, m);
    ALLOC(w->gtv, m);
    ALLOC(w->lam, m);
    ALLOC(w->jWE, 9 * nj);
    ALLOC(w->jRrel, 9 * nj);
    ALLOC(w->jP, 3 * nj);
    ALLOC(w->jBrp, 3 * nj);
    ALLOC(w->jd, 3 * nj);
    ALLOC(w->jT, 3 * nj);
    ALLOC(w->jwc, 3 * nj);
    ALLOC(w->jwp, 3 * nj);
    ALLOC(w->loads, 3 * md->k);
    ALLOC(w->evals, md->n_expr);
    ALLOC(w->stack, md->n_code);
    ALLOC(w->gam, mu);
    ALLOC(w->stab, mu);
    ALLOC(w->lamU, mu);
    ALLOC(w->r2, mu);
    ALLOC(w->dlam, mu);
    ALLOC(w->nonunique, mu);
    ALLOC(w->Sb, mu * (bw + 1));
    ALLOC(w->S0, mu * (bw + 1));
    ALLOC(w->unit, MB_BODY_W * n);
    return w;
fail:
    mb_work_free(w);
    return NULL;
}

static void free_dense(mb_dense *d) {
    if (d == NULL) return;
    free(d->S), free(d->X), free(d->Nn), free(d->Q), free(d->diag), free(d->coef);
    free(d->res), free(d->rhs), free(d->rhs6), free(d->perm);
    free(d);
}

static void free_ns(mb_ns *s) {
    if (s == NULL) return;
    double *bufs[] = {s->A, s->T, s->C, s->B, s->Uf, s->sv, s->V, s->Vc, s->Mb, s->MU2,
                      s->red, s->Lr, s->rh, s->gh, s->sh, s->ah, s->lamh, s->r1, s->r2,
                      s->da, s->dl, s->rest, s->t2, s->cvec, s->tmp, s->Nn, s->Q, s->hh,
                      s->eig};
    for (size_t i = 0; i < sizeof(bufs) / sizeof(bufs[0]); i++) free(bufs[i]);
    free(s->order);
    free(s);
}

void mb_work_free(mb_work *w) {
    if (w == NULL) return;
    double *bufs[] = {w->R, w->r6, w->acc, w->rhs, w->r1, w->dacc, w->child6, w->parent6,
                      w->W_e, w->W_P, w->gamma, w->phi, w->gtv, w->lam, w->jWE, w->jRrel,
                      w->jP, w->jBrp, w->jd, w->jT, w->jwc, w->jwp, w->loads, w->evals,
                      w->stack, w->gam, w->stab, w->lamU, w->r2, w->dlam, w->Sb, w->S0,
                      w->unit};
    for (size_t i = 0; i < sizeof(bufs) / sizeof(bufs[0]); i++) free(bufs[i]);
    free(w->nonunique);
    free_dense(w->dense);
    free_ns(w->ns);
    free(w);
}

int mb_ensure_dense(mb_work *w) {
    if (w->dense != NULL) return 0;
    mb_dense *d = calloc(1, sizeof(mb_dense));
    if (d == NULL) return -1;
    int64_t mu = w->mu, n = w->n;
    w->dense = d;
    ALLOC(d->S, mu * mu);
    ALLOC(d->X, mu * mu);
    ALLOC(d->Nn, mu * mu);
    ALLOC(d->Q, mu * mu);
    ALLOC(d->diag, mu);
    ALLOC(d->coef, mu);
    ALLOC(d->rhs, mu);
    ALLOC(d->res, 6 * n);
    ALLOC(d->rhs6, 6 * n);
    ALLOC(d->perm, mu);
    return 0;
fail:
    free_dense(d);
    w->dense = NULL;
    return -1;
}

int mb_ensure_ns(mb_work *w, int64_t nr, int64_t mu) {
    mb_ns *s = w->ns;
    if (s != NULL && nr <= s->cap_nr && mu <= s->cap_mu) {
        s->nr = nr, s->mu = mu;
        return 0;
    }
    free_ns(s);
    s = calloc(1, sizeof(mb_ns));
    w->ns = s;
    if (s == NULL) return -1;
    s->nr = s->cap_nr = nr, s->mu = s->cap_mu = mu;
    int64_t big = nr > mu ? nr : mu, n = w->n;
    ALLOC(s->A, nr * mu);
    ALLOC(s->T, nr);
    ALLOC(s->C, mu);
    ALLOC(s->B, nr * nr);
    ALLOC(s->Uf, nr * nr);
    ALLOC(s->sv, big);
    ALLOC(s->V, big * big);
    ALLOC(s->Vc, mu * mu);
    ALLOC(s->Mb, 36 * n);
    ALLOC(s->MU2, nr * nr);
    ALLOC(s->red, nr * nr);
    ALLOC(s->Lr, nr * nr);
    ALLOC(s->rh, nr);
    ALLOC(s->gh, mu);
    ALLOC(s->sh, mu);
    ALLOC(s->ah, nr);
    ALLOC(s->lamh, mu);
    ALLOC(s->r1, nr);
    ALLOC(s->r2, mu);
    ALLOC(s->da, nr);
    ALLOC(s->dl, mu);
    ALLOC(s->rest, nr);
    ALLOC(s->t2, nr);
    ALLOC(s->cvec, big);
    ALLOC(s->tmp, 2 * big * big + 4 * big);
    ALLOC(s->Nn, mu * mu);
    ALLOC(s->Q, mu * mu);
    ALLOC(s->hh, big * big + big);
    ALLOC(s->eig, 2 * nr * nr + nr);
    ALLOC(s->order, big);
    return 0;
fail:
    free_ns(s);
    w->ns = NULL;
    return -1;
}
