/* Generalized coordinates: the velocity transformation v = T q' + v_e, the generalized
 * mass M_q = T^T M T and forces f_q = T^T (Q - b + G_K lam_K - M a0) (kernel.h).
 *
 * Each coordinate is a rate row a_k^T v (MB_GQ_*): a turn about a joint-frame axis
 * (a revolute's angle, the rate MB_KIND_TURN measures), a turn about an axis fixed in the
 * child (a ball's quasi-velocities about the child's body axes, a universal joint's
 * second angle), a slide along a joint-frame axis (MB_KIND_FORCE's rate), or one of a
 * body's own velocity components. With C = [G_U^T; A^T] (the held components, then the
 * coordinates; r x N over the model's velocity columns):
 *
 *     C T = [0; I],    C v_e = [f'; 0],    C a0 = [gamma_U; gamma_A]
 *
 * (f' the drivers' rates; gamma the acceleration terms at v' = 0, so that
 * v' = T q'' + a0). C has full column rank when the coordinates determine the motion;
 * redundant joints make it taller than wide, and the system stays consistent on the
 * configuration manifold (the least-squares solution is then the exact one). One
 * Householder QR of C (columns scaled to unit length) serves every right-hand side. */
#include <stdlib.h>
#include <string.h>

#include "internal.h"

#define TWO_PI 6.283185307179586
#define PI 3.141592653589793

static double wrap_angle(double a) { return a - TWO_PI * ceil((a - PI) / TWO_PI); }

int mb_coordinates_check(const mb_model *md, int64_t nq, const int64_t *Iq, int64_t nc,
                         const int64_t *cols) {
    if (nq < 0 || nc < 0 || nc > 6 * md->n) return -1;
    for (int64_t k = 0; k < nq; k++) {
        const int64_t *c = Iq + MB_GQ_W * k;
        int64_t kind = c[0], index = c[1], axis = c[2], rule = c[3];
        if (rule < 0 || rule > 2) return -1;
        switch (kind) {
        case MB_GQ_TURN:
        case MB_GQ_SLIDE:
            if (index < 0 || index >= md->nj || axis < 0 || axis > 2) return -1;
            break;
        case MB_GQ_CHILD_TURN:
            if (index < 0 || index >= md->nj || axis < 0 || axis > 3) return -1;
            break;
        case MB_GQ_BODY:
            if (index < 0 || index >= md->n || axis < 0 || axis > 5) return -1;
            break;
        default: return -1;
        }
    }
    for (int64_t j = 0; j < nc; j++)
        if (cols[j] < 0 || cols[j] >= 6 * md->n || (j > 0 && cols[j] <= cols[j - 1]))
            return -1;
    return 0;
}

/* Columns of T and M_q are solved for one at a time and written BLOCK at a time across
 * their rows (row-major outputs: a column's entries are nq apart, a cache line each). */
#define BLOCK 8

/* The scratch of one evaluation (allocated per call). C = [G_U^T; A^T] (r x N) is kept by
 * columns, its rows in the order of their first column (`pos`: an original row's place), so
 * that the Householder QR below works only within the band that the bodies' order leaves
 * (a chain in file order: a few columns wide); the columns' touched rows [clo, chi] are
 * what the next factorisation clears. */
typedef struct {
    int64_t n, N, nq, mu, r;
    double *C, *B, *fp, *scale, *beta, *rdiag, *y, *arow, *agam, *r6, *Ma, *lam, *tmp;
    double *block; /* BLOCK (N + nq): a few columns of T or M_q gathered before they are
                    * written across their rows */
    int64_t *col_of;       /* 6 n: active column index, or -1 */
    int64_t *bfirst, *blast; /* n: a body's first and last column (-1: none) */
    int64_t *pos, *first, *last; /* r: a row's place; by place, its first and last column */
    int64_t *rlo, *rhi;          /* r: a row's first and last column (original order) */
    int64_t *vend, *rend, *rbeg; /* N: reflector k's last row, R's row k's last column,
                                  * R's column k's first row */
    int64_t *clo, *chi, *count; /* N: the rows of column j written; N + 2: the sort's */
    int64_t *off, W; /* N: column j holds rows off_j .. off_j + W - 1 (`band`), at C + j W */
    double *dbuf;    /* the doubles above but C */
    int64_t *ibuf;   /* the indices above */
} gen_scratch;

static void scratch_free(gen_scratch *s) { free(s->C), free(s->dbuf), free(s->ibuf); }

/* The scratch's arrays, carved from two allocations (one of doubles, one of indices: a
 * small model's evaluation costs a few microseconds, and each allocation a little of it);
 * C is made by `band` on the first factorisation. 0, or -1 when memory ran out. */
static int scratch_new(gen_scratch *s, const mb_model *md, const mb_unknowns *u, int64_t nq,
                       int64_t nc, const int64_t *cols) {
    memset(s, 0, sizeof(*s));
    s->n = md->n, s->N = nc, s->nq = nq, s->mu = u->mu, s->r = u->mu + nq;
    int64_t r = s->r > 0 ? s->r : 1, N = nc > 0 ? nc : 1, n = md->n > 0 ? md->n : 1;
    int64_t q1 = nq > 0 ? nq : 1, m1 = md->m > 0 ? md->m : 1;
    int64_t nd = (3 * r + N) + r + 3 * N + 13 * n + 13 * q1 + 12 * n + m1 + r +
                 BLOCK * (N + q1);
    int64_t ni = 8 * n + 5 * r + 7 * N + 2;
    s->dbuf = calloc((size_t)nd, sizeof(double));
    s->ibuf = calloc((size_t)ni, sizeof(int64_t));
    if (s->dbuf == NULL || s->ibuf == NULL) {
        scratch_free(s);
        return -1;
    }
    double *d = s->dbuf;
    s->B = d, d += 3 * r + N;
    s->fp = d, d += r;
    s->scale = d, d += N;
    s->beta = d, d += N;
    s->rdiag = d, d += N;
    s->y = d, d += 13 * n;
    s->arow = d, d += 12 * q1;
    s->agam = d, d += q1;
    s->r6 = d, d += 6 * n;
    s->Ma = d, d += 6 * n;
    s->lam = d, d += m1;
    s->tmp = d, d += r;
    s->block = d;
    int64_t *i = s->ibuf;
    s->col_of = i, i += 6 * n;
    s->bfirst = i, i += n;
    s->blast = i, i += n;
    s->pos = i, i += r;
    s->first = i, i += r;
    s->last = i, i += r;
    s->rlo = i, i += r;
    s->rhi = i, i += r;
    s->vend = i, i += N;
    s->rend = i, i += N;
    s->rbeg = i, i += N;
    s->clo = i, i += N;
    s->chi = i, i += N;
    s->count = i, i += N + 2;
    s->off = i;
    for (int64_t k = 0; k < 6 * md->n; k++) s->col_of[k] = -1;
    for (int64_t j = 0; j < nc; j++) s->col_of[cols[j]] = j;
    for (int64_t b = 0; b < md->n; b++) {
        s->bfirst[b] = s->blast[b] = -1;
        for (int a = 0; a < 6; a++) {
            int64_t j = s->col_of[6 * b + a];
            if (j < 0) continue;
            if (s->bfirst[b] < 0) s->bfirst[b] = j;
            s->blast[b] = j;
        }
    }
    for (int64_t j = 0; j < nc; j++) s->clo[j] = 0, s->chi[j] = -1; /* nothing written */
    for (int64_t k = 0; k < nc; k++) /* no factors yet: every solve gives 0 */
        s->vend[k] = k - 1, s->rend[k] = k, s->rbeg[k] = k;
    return 0;
}

/* R^T e */
static void to_body(const double *R, const double *e, double *B) {
    for (int a = 0; a < 3; a++) B[a] = R[a] * e[0] + R[3 + a] * e[1] + R[6 + a] * e[2];
}

/* Coordinate k's rate row (child side row[0..5], parent side row[6..11]; its bodies in
 * *c, *p), its acceleration term gamma (at the velocities w's joint data were made with)
 * and, unless value is NULL, its value (rad, m; NaN for a quasi-velocity). Needs w->R and
 * the joint data of mb_columns_at at the same y. */
static void coordinate_row(const mb_model *md, const mb_work *w, const double *y,
                           const int64_t *c, double *row, int64_t *child, int64_t *parent,
                           double *gamma, double *value) {
    int64_t kind = c[0], index = c[1], axis = c[2], rule = c[3];
    double unused;
    if (value == NULL) value = &unused;
    int values = value != &unused;
    memset(row, 0, 12 * sizeof(double));
    *gamma = 0.0;
    *value = NAN;
    if (kind == MB_GQ_BODY) {
        int64_t n = md->n;
        *child = index, *parent = -1;
        row[axis] = 1.0;
        if (axis < 3) *value = y[3 * index + axis];
        else if (md->planar && axis == 5) {
            const double *q = y + 3 * n + 4 * index;
            *value = wrap_angle(2.0 * atan2(q[3], q[0]));
        }
        return;
    }
    int64_t j = index;
    const double *jrow = md->joints + MB_JOINT_W * j;
    int64_t p = md->joints_i[3 * j], ch = md->joints_i[3 * j + 1];
    int particle_parent = (md->joints_i[3 * j + 2] & MB_J_PARTICLE_PARENT) != 0;
    *child = ch, *parent = p;
    const double *Rc = w->R + 9 * ch, *WE = w->jWE + 9 * j, *A = w->jRrel + 9 * j;
    const double *wc = w->jwc + 3 * j, *wp = w->jwp + 3 * j;
    static const double identity[9] = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
    const double *Rp = p >= 0 ? w->R + 9 * p : identity;
    double e[3], Bc[3], Bp[3], k[3];
    mb_cross(wc, wp, k);
    if (kind == MB_GQ_CHILD_TURN) {
        double bB[3] = {0.0, 0.0, 0.0};
        if (axis < 3) bB[axis] = 1.0;
        else for (int a = 0; a < 3; a++) bB[a] = jrow[J_CAX2 + a];
        for (int a = 0; a < 3; a++) e[a] = Rc[3 * a] * bB[0] + Rc[3 * a + 1] * bB[1] + Rc[3 * a + 2] * bB[2];
        to_body(Rp, e, Bp);
        for (int a = 0; a < 3; a++) row[3 + a] = bB[a], row[9 + a] = -Bp[a];
        *gamma = -(e[0] * k[0] + e[1] * k[1] + e[2] * k[2]);
    } else {
        for (int a = 0; a < 3; a++) e[a] = WE[3 * a + axis], Bp[a] = jrow[J_PE3 + 3 * a + axis];
        to_body(Rc, e, Bc);
        if (kind == MB_GQ_TURN) {
            for (int a = 0; a < 3; a++) row[3 + a] = Bc[a], row[9 + a] = -Bp[a];
            *gamma = -(e[0] * k[0] + e[1] * k[1] + e[2] * k[2]);
        } else { /* MB_GQ_SLIDE: the FORCE primitive's row */
            double mc[3], mp[3];
            const double *T = w->jT + 3 * j, *d = w->jd + 3 * j;
            mb_cross(jrow + J_BRC, Bc, mc);
            mb_cross(w->jBrp + 3 * j, Bp, mp);
            for (int a = 0; a < 3; a++) {
                row[a] = e[a], row[3 + a] = mc[a];
                row[6 + a] = -e[a], row[9 + a] = particle_parent ? 0.0 : -mp[a];
            }
            *gamma = -(e[0] * T[0] + e[1] * T[1] + e[2] * T[2]);
            *value = e[0] * d[0] + e[1] * d[1] + e[2] * d[2];
        }
    }
    if (particle_parent)
        for (int a = 9; a < 12; a++) row[a] = 0.0;
    if (kind == MB_GQ_SLIDE || !values) return;
    /* values: rule 0 the turn about the frame's axis; 1, 2 a universal joint's first and
     * second angle (R_rel = Rz(q1) R_b0(q2), b0 = axis2 in the joint frame at the file's
     * pose); a child-fixed body axis has none (a quasi-velocity) */
    if (rule == 0 && kind == MB_GQ_TURN) {
        int i1 = (int)((axis + 1) % 3), i2 = (int)((axis + 2) % 3);
        *value = atan2(A[3 * i2 + i1], A[3 * i1 + i1]);
    } else if (rule == 1 || rule == 2) {
        const double *CE = jrow + J_CE3, *ax2 = jrow + J_CAX2;
        double b0[3], b[3];
        for (int a = 0; a < 3; a++) /* C_E3^T axis2: axis2 in the child's joint frame */
            b0[a] = CE[a] * ax2[0] + CE[3 + a] * ax2[1] + CE[6 + a] * ax2[2];
        for (int a = 0; a < 3; a++) b[a] = A[3 * a] * b0[0] + A[3 * a + 1] * b0[1] + A[3 * a + 2] * b0[2];
        double q1 = wrap_angle(atan2(b[1], b[0]) - atan2(b0[1], b0[0]));
        if (rule == 1) {
            *value = q1;
        } else {
            double c1 = cos(q1), s1 = sin(q1);
            double z0 = A[2], z1 = A[5], z2 = A[8]; /* A z */
            double r0 = c1 * z0 + s1 * z1, r1 = -s1 * z0 + c1 * z1; /* Rz(-q1) A z */
            *value = atan2(b0[1] * r0 - b0[0] * r1, z2);
        }
    }
}

/* C (r x N) is kept by columns, each in W doubles: column j's rows off_j .. off_j + W - 1
 * (`band`: every row it holds from its first entry to the last the QR's fill reaches), so
 * that a banded C takes N W doubles, a chain's a few columns wide, and the QR below runs
 * down short columns that sit side by side in memory. */

/* Row i of C (original order: the held components, then the coordinates) touches the
 * columns of bodies c and p (p < 0: none): its first and last column (first N: none). */
static void row_span(gen_scratch *s, int64_t i, int64_t c, int64_t p) {
    int64_t a = s->bfirst[c], b = s->blast[c];
    if (p >= 0 && s->bfirst[p] >= 0) {
        if (a < 0 || s->bfirst[p] < a) a = s->bfirst[p];
        if (s->blast[p] > b) b = s->blast[p];
    }
    s->rlo[i] = a >= 0 ? a : s->N, s->rhi[i] = b;
}

/* The rows' places by their first column (a stable counting sort: rows without columns
 * last), with each place's first and last column. */
static void sort_rows(gen_scratch *s) {
    int64_t r = s->r, N = s->N, *count = s->count;
    const int64_t *lo = s->rlo, *hi = s->rhi;
    for (int64_t j = 0; j <= N + 1; j++) count[j] = 0;
    for (int64_t i = 0; i < r; i++) count[lo[i] + 1]++;
    for (int64_t j = 0; j <= N; j++) count[j + 1] += count[j];
    for (int64_t i = 0; i < r; i++) {
        int64_t p = count[lo[i]]++;
        s->pos[i] = p, s->first[p] = lo[i], s->last[p] = hi[i];
    }
}

/* The rows each column of C holds while it is factored, from the rows' spans alone (their
 * places and first and last columns, sort_rows's): a row's entries from its first column
 * to its last, and each QR step's rows in the columns it reaches (the fill): off and W,
 * then C of N W doubles. Once per scratch: the spans are those of the bodies, whatever
 * the positions. Returns 0, or -1 when memory ran out. */
static int band(gen_scratch *s) {
    int64_t r = s->r, N = s->N, *off = s->off, *top = s->clo, *last = s->rhi;
    for (int64_t j = 0; j < N; j++) off[j] = INT64_MAX, top[j] = -1;
    for (int64_t p = 0; p < r; p++)
        for (int64_t c = s->first[p]; c <= s->last[p] && c < N; c++) {
            if (p < off[c]) off[c] = p;
            if (p > top[c]) top[c] = p;
        }
    if (r >= N) { /* qr_factor's steps, without the arithmetic (rhi: free until row_span) */
        memcpy(last, s->last, sizeof(int64_t) * (size_t)r);
        for (int64_t k = 0, e = -1; k < N; k++) {
            while (e + 1 < r && s->first[e + 1] <= k) e++;
            int64_t hi = e > k ? e : k, L = k;
            for (int64_t p = k; p <= hi; p++) L = last[p] > L ? last[p] : L;
            for (int64_t c = k; c <= L; c++) {
                if (k < off[c]) off[c] = k;
                if (hi > top[c]) top[c] = hi;
            }
            for (int64_t p = k; p <= hi; p++) last[p] = L;
        }
    }
    int64_t W = 1;
    for (int64_t j = 0; j < N; j++) {
        if (top[j] < 0) off[j] = 0, top[j] = 0; /* holds nothing */
        if (top[j] - off[j] + 1 > W) W = top[j] - off[j] + 1;
    }
    s->W = W;
    for (int64_t j = 0; j < N; j++) s->clo[j] = 0, s->chi[j] = -1; /* nothing written */
    s->C = calloc((size_t)(N > 0 ? N : 1) * (size_t)W, sizeof(double));
    return s->C != NULL ? 0 : -1;
}

/* Adds a row (child side [0..5] on body c, parent side [6..11] on body p) into C's row at
 * place `at`, noting the rows each column holds. */
static void put_c_row(gen_scratch *s, int64_t at, const double *row, int64_t c, int64_t p) {
    for (int side = 0; side < 2; side++) {
        int64_t b = side ? p : c;
        if (b < 0) continue;
        for (int a = 0; a < 6; a++) {
            int64_t j = s->col_of[6 * b + a];
            if (j < 0) continue;
            s->C[j * s->W + at - s->off[j]] += row[6 * side + a];
            if (at < s->clo[j] || s->chi[j] < s->clo[j]) s->clo[j] = at;
            if (at > s->chi[j]) s->chi[j] = at;
        }
    }
}

/* Clears what the last factorisation wrote in C. */
static void clear_c(gen_scratch *s) {
    for (int64_t j = 0; j < s->N; j++) {
        if (s->chi[j] >= s->clo[j])
            memset(s->C + j * s->W + s->clo[j] - s->off[j], 0,
                   sizeof(double) * (size_t)(s->chi[j] - s->clo[j] + 1));
        s->clo[j] = 0, s->chi[j] = -1;
    }
}

/* Householder QR of C (in place) with its columns scaled to unit length first (scale: the
 * factors): the reflectors' vectors stay in C on and below the diagonal (beta their
 * factors, vend their last rows), R's strict upper triangle above it (rend: the last
 * column of each of its rows; rbeg: the first row of each of its columns), R's diagonal in
 * rdiag. Step k touches only the rows whose first column is at most k (the rows are in
 * that order: rows below them are still zero in column k) and the columns those rows
 * reach: the QR of a banded C costs its band's width squared per column, and gives the
 * numbers of the dense QR of C's rows in this order. Returns the smallest |R_kk| over the
 * largest (0 when r < N), which does not depend on the rows' order (R^T R = C^T C). */
static double qr_factor(gen_scratch *s) {
    int64_t r = s->r, N = s->N, W = s->W;
    const int64_t *off = s->off;
    double *C = s->C;
    for (int64_t j = 0; j < N; j++) {
        double sum = 0.0, *col = C + j * W;
        int64_t o = off[j];
        s->rdiag[j] = 0.0, s->beta[j] = 0.0;
        s->vend[j] = j - 1, s->rend[j] = j, s->rbeg[j] = j;
        for (int64_t i = s->clo[j]; i <= s->chi[j]; i++) sum += col[i - o] * col[i - o];
        sum = sum > 0.0 ? 1.0 / sqrt(sum) : 1.0;
        s->scale[j] = sum;
        for (int64_t i = s->clo[j]; i <= s->chi[j]; i++) col[i - o] *= sum;
    }
    if (r < N) return 0.0; /* fewer rows than columns: the motion is not determined */
    double big = 0.0, small = INFINITY;
    int64_t e = -1;
    for (int64_t k = 0; k < N; k++) {
        while (e + 1 < r && s->first[e + 1] <= k) e++;
        int64_t hi = e > k ? e : k, L = k;
        for (int64_t p = k; p <= hi; p++) L = s->last[p] > L ? s->last[p] : L;
        double *v = C + k * W + k - off[k], norm = 0.0; /* v[i - k]: row i */
        int64_t h = hi - k;
        for (int64_t i = 0; i <= h; i++) norm += v[i] * v[i];
        norm = sqrt(norm);
        double x0 = v[0];
        double alpha = x0 >= 0.0 ? -norm : norm;
        v[0] = x0 - alpha;
        double vv = 0.0;
        for (int64_t i = 0; i <= h; i++) vv += v[i] * v[i];
        double bk = vv > 0.0 ? 2.0 / vv : 0.0;
        for (int64_t c = k + 1; c <= L; c++) {
            double sum = 0.0, *col = C + c * W + k - off[c]; /* col[i - k]: row i */
            for (int64_t i = 0; i <= h; i++) sum += v[i] * col[i];
            sum *= bk;
            for (int64_t i = 0; i <= h; i++) col[i] -= sum * v[i];
            if (s->chi[c] < s->clo[c] || k < s->clo[c]) s->clo[c] = k;
            if (hi > s->chi[c]) s->chi[c] = hi;
            if (s->rbeg[c] == c) s->rbeg[c] = k; /* the first step to reach column c */
        }
        if (s->chi[k] < s->clo[k] || k < s->clo[k]) s->clo[k] = k;
        if (hi > s->chi[k]) s->chi[k] = hi;
        for (int64_t p = k; p <= hi; p++) s->last[p] = L; /* the rows now reach L */
        s->beta[k] = bk, s->vend[k] = hi, s->rend[k] = L, s->rdiag[k] = alpha;
        big = fmax(big, fabs(alpha));
        small = fmin(small, fabs(alpha));
    }
    return big > 0.0 ? small / big : 0.0;
}

/* b (r, the rows in their original order) <- the least-squares solution x (N) of C x = b
 * in its first N entries, with the factors of qr_factor. Returns the residual's norm (the
 * part of b outside C's range: 0 for a consistent system). */
static double qr_solve(const gen_scratch *s, double *b) {
    int64_t r = s->r, N = s->N, W = s->W;
    const int64_t *off = s->off;
    const double *C = s->C;
    double *t = s->tmp, resid = 0.0;
    for (int64_t i = 0; i < r; i++) t[s->pos[i]] = b[i];
    for (int64_t k = 0; k < N; k++) { /* Q^T b */
        int64_t h = s->vend[k] - k;
        if (h < 0) continue; /* no reflector (not factored) */
        const double *v = C + k * W + k - off[k];
        double sum = 0.0, *tk = t + k;
        for (int64_t i = 0; i <= h; i++) sum += v[i] * tk[i];
        sum *= s->beta[k];
        for (int64_t i = 0; i <= h; i++) tk[i] -= sum * v[i];
    }
    for (int64_t i = N; i < r; i++) resid += t[i] * t[i];
    for (int64_t k = N - 1; k >= 0; k--) {
        double sum = t[k];
        for (int64_t j = k + 1; j <= s->rend[k]; j++) sum -= C[j * W + k - off[j]] * b[j];
        b[k] = s->rdiag[k] != 0.0 ? sum / s->rdiag[k] : 0.0;
    }
    for (int64_t k = 0; k < N; k++) b[k] *= s->scale[k];
    return sqrt(resid);
}

/* out (nq) <- the coordinates' entries of Q1 R^-T D x (work: r + N doubles): (C^+)^T D x
 * restricted to the coordinates' rows, i.e. T^T x when T is C^+ [0; I] (the transposed
 * solve: one vector instead of nq columns of T). */
static void qr_transposed(const gen_scratch *s, const double *x, double *out, double *work) {
    int64_t r = s->r, N = s->N, W = s->W;
    const int64_t *off = s->off;
    const double *C = s->C;
    for (int64_t k = 0; k < N; k++) { /* R^T z = D x, forward */
        const double *col = C + k * W;
        int64_t o = off[k];
        double sum = s->scale[k] * x[k];
        for (int64_t j = s->rbeg[k]; j < k; j++) sum -= col[j - o] * work[j];
        work[k] = s->rdiag[k] != 0.0 ? sum / s->rdiag[k] : 0.0;
    }
    for (int64_t i = N; i < r; i++) work[i] = 0.0;
    for (int64_t k = N - 1; k >= 0; k--) { /* Q [z; 0] = H_0 ... H_{N-1} [z; 0] */
        int64_t h = s->vend[k] - k;
        if (h < 0) continue; /* no reflector (not factored) */
        const double *v = C + k * W + k - off[k];
        double sum = 0.0, *wk = work + k;
        for (int64_t i = 0; i <= h; i++) sum += v[i] * wk[i];
        sum *= s->beta[k];
        for (int64_t i = 0; i <= h; i++) wk[i] -= sum * v[i];
    }
    for (int64_t k = 0; k < s->nq; k++) out[k] = work[s->pos[s->mu + k]];
}

/* Adds row (child side [0..5] on body c, parent side [6..11] on body p) into a matrix row
 * whose column j is at[j * stride] (C's row i: C + i, stride r). */
static void put_row(const gen_scratch *s, double *at, int64_t stride, const double *row,
                    int64_t c, int64_t p) {
    for (int a = 0; a < 6; a++) {
        int64_t j = s->col_of[6 * c + a];
        if (j >= 0) at[j * stride] += row[a];
        if (p >= 0) {
            j = s->col_of[6 * p + a];
            if (j >= 0) at[j * stride] += row[6 + a];
        }
    }
}

/* row . v for a coordinate's row and the state's velocities (world v, body w). */
static double row_dot_v(const double *row, int64_t c, int64_t p, const double *y, int64_t n,
                        const int64_t *col_of) {
    const double *v = y + 7 * n, *om = y + 10 * n;
    double s = 0.0;
    for (int a = 0; a < 3; a++) {
        if (col_of[6 * c + a] >= 0) s += row[a] * v[3 * c + a];
        if (col_of[6 * c + 3 + a] >= 0) s += row[3 + a] * om[3 * c + a];
        if (p >= 0) {
            if (col_of[6 * p + a] >= 0) s += row[6 + a] * v[3 * p + a];
            if (col_of[6 * p + 3 + a] >= 0) s += row[9 + a] * om[3 * p + a];
        }
    }
    return s;
}

/* The columns of the held components and the coordinates' rows at s->y (positions; the
 * velocities only enter gamma): into w's columns, s->arow, s->agam, values. */
static void rows_at(const mb_model *md, mb_work *w, gen_scratch *s, int64_t nq,
                    const int64_t *Iq, int64_t *cc, int64_t *cp, double *values) {
    mb_columns_at(md, w, s->y, 1, w->child6, w->parent6, NULL, NULL, w->gamma, w->phi,
                  w->gtv);
    for (int64_t k = 0; k < nq; k++)
        coordinate_row(md, w, s->y, Iq + MB_GQ_W * k, s->arow + 12 * k, cc + k, cp + k,
                       s->agam + k, values ? values + k : NULL);
}

/* Stage 1 at positions s->y: rotations, the rows and C's QR (kept in s), the coordinates'
 * rows and bodies (cc, cp) and values; the drivers' rates f' of the held components into
 * s->fp. Returns the pivot ratio, or -1 when memory ran out (C is made on the first call:
 * after that, never). */
static double factor(const mb_model *md, const mb_unknowns *u, mb_work *w, gen_scratch *s,
                     int64_t nq, const int64_t *Iq, int64_t *cc, int64_t *cp, double *qval) {
    int64_t n = md->n, mu = s->mu;
    mb_rotations(n, s->y + 3 * n, w->R);
    rows_at(md, w, s, nq, Iq, cc, cp, qval);
    clear_c(s);
    for (int64_t k = 0; k < mu; k++) {
        int64_t j = md->comps_i[4 * u->U[k]];
        row_span(s, k, md->joints_i[3 * j + 1], md->joints_i[3 * j]);
    }
    for (int64_t k = 0; k < nq; k++) row_span(s, mu + k, cc[k], cp[k]);
    sort_rows(s);
    if (s->C == NULL && band(s) < 0) return -1.0; /* no memory: the caller's error */
    for (int64_t k = 0; k < mu; k++) {
        int64_t i = u->U[k], j = md->comps_i[4 * i];
        double row[12];
        memcpy(row, w->child6 + 6 * i, 6 * sizeof(double));
        memcpy(row + 6, w->parent6 + 6 * i, 6 * sizeof(double));
        put_c_row(s, s->pos[k], row, md->joints_i[3 * j + 1], md->joints_i[3 * j]);
        s->fp[k] = 0.0;
        if (md->comps_i[4 * i + 3] >= 0) {
            double f[3];
            mb_law(md, w, i, f);
            s->fp[k] = f[1];
        }
    }
    for (int64_t k = 0; k < nq; k++) put_c_row(s, s->pos[mu + k], s->arow + 12 * k, cc[k], cp[k]);
    return qr_factor(s);
}

/* Stage 2 with C factored at s->y's positions (the last mb_columns_at there): v = T q' +
 * v_e into s->y, a0, and
 * f_q = T^T (Q - b + G_K lam_K - M a0) (by the transposed solve); ve, a0 (N) written. */
static void forces(const mb_model *md, const mb_unknowns *u, mb_work *w, gen_scratch *s,
                   int64_t nq, const int64_t *Iq, const double *qd, const double *lam,
                   double *ve, double *a0, double *fq) {
    int64_t n = md->n, N = s->N, mu = s->mu, r = s->r;
    int64_t nq1 = nq > 0 ? nq : 1, cc[nq1], cp[nq1];
    double *g = s->B, *x = s->B + r, *work = s->B + 2 * r;
    /* v_e: C v_e = [f'; 0] (wanted by mb_generalized only: ve NULL skips it);
     * v = C^+ [f'; q'] = v_e + T q' */
    if (ve != NULL) {
        for (int64_t k = 0; k < mu; k++) g[k] = s->fp[k];
        for (int64_t k = 0; k < nq; k++) g[mu + k] = 0.0;
        qr_solve(s, g);
        for (int64_t i = 0; i < N; i++) ve[i] = g[i];
    }
    for (int64_t k = 0; k < mu; k++) g[k] = s->fp[k];
    for (int64_t k = 0; k < nq; k++) g[mu + k] = qd[k];
    qr_solve(s, g);
    double *v = s->y + 7 * n, *om = s->y + 10 * n;
    memset(v, 0, sizeof(double) * 6 * n);
    for (int64_t i = 0; i < 6 * n; i++) {
        int64_t j = s->col_of[i];
        if (j < 0) continue;
        if (i % 6 < 3) v[3 * (i / 6) + i % 6] = g[j];
        else om[3 * (i / 6) + i % 6 - 3] = g[j];
    }
    /* gamma at the velocities (the positions, so the columns, are factor's) */
    mb_gammas_at(md, w, s->y, 1, w->child6, w->parent6, w->gamma, w->gtv);
    for (int64_t k = 0; k < nq; k++)
        coordinate_row(md, w, s->y, Iq + MB_GQ_W * k, s->arow + 12 * k, cc + k, cp + k,
                       s->agam + k, NULL);
    for (int64_t k = 0; k < mu; k++) g[k] = w->gamma[u->U[k]];
    for (int64_t k = 0; k < nq; k++) g[mu + k] = s->agam[k];
    qr_solve(s, g);
    for (int64_t i = 0; i < N; i++) a0[i] = g[i];
    /* Q - b + G_K lam_K at the state */
    mb_loads_at(md, w);
    mb_net_wrench_at(md, w, s->y, s->r6);
    if (lam != NULL) {
        mb_known_at(md, w, lam, s->lam);
        for (int64_t i = 0; i < md->m; i++) {
            double li = s->lam[i];
            if (li == 0.0) continue;
            int64_t j = md->comps_i[4 * i];
            int64_t p = md->joints_i[3 * j], c = md->joints_i[3 * j + 1];
            for (int a = 0; a < 6; a++) s->r6[6 * c + a] += w->child6[6 * i + a] * li;
            if (p >= 0)
                for (int a = 0; a < 6; a++) s->r6[6 * p + a] += w->parent6[6 * i + a] * li;
        }
    }
    /* x = r6 - M a0 on the model's columns, then f = T^T x */
    for (int64_t b = 0; b < n; b++) {
        const double *body = md->bodies + MB_BODY_W * b, *J = body + B_J;
        double acc[6];
        for (int a = 0; a < 6; a++) {
            int64_t j = s->col_of[6 * b + a];
            acc[a] = j >= 0 ? a0[j] : 0.0;
        }
        for (int a = 0; a < 6; a++) {
            int64_t j = s->col_of[6 * b + a];
            if (j < 0) continue;
            double Ma = a < 3 ? body[B_MASS] * acc[a]
                              : J[3 * (a - 3)] * acc[3] + J[3 * (a - 3) + 1] * acc[4] +
                                    J[3 * (a - 3) + 2] * acc[5];
            x[j] = s->r6[6 * b + a] - Ma;
        }
    }
    qr_transposed(s, x, fq, work);
}

/* T (N x nq) from the factors: C T = [0; I], row-major (the output's layout), or
 * by_columns (T's column k at T + k N: what the perturbed states read); returns the
 * residual's norm (0 on the configuration manifold). */
static double transformation(gen_scratch *s, int64_t nq, double *T, int by_columns) {
    int64_t N = s->N, mu = s->mu, r = s->r;
    double *g = s->B, resid = 0.0;
    for (int64_t k0 = 0; k0 < nq; k0 += BLOCK) {
        int64_t w = nq - k0 < BLOCK ? nq - k0 : BLOCK;
        for (int64_t b = 0; b < w; b++) {
            memset(g, 0, sizeof(double) * r);
            g[mu + k0 + b] = 1.0;
            double e = qr_solve(s, g);
            resid += e * e;
            memcpy(by_columns ? T + (k0 + b) * N : s->block + b * N, g, sizeof(double) * N);
        }
        if (!by_columns)
            for (int64_t i = 0; i < N; i++)
                for (int64_t b = 0; b < w; b++) T[i * nq + k0 + b] = s->block[b * N + i];
    }
    return sqrt(resid);
}

/* M_q = T^T M T a column at a time: M_q e_l = T^T (M T e_l) by the transposed solve
 * (qr_transposed), at the band's cost per column rather than T's size (a chain's T is
 * half full); BLOCK columns read and written at a time. */
static void mass(const mb_model *md, gen_scratch *s, int64_t nq, const double *T, double *Mq) {
    int64_t N = s->N, r = s->r;
    double *work = s->B + 2 * r, *xs = s->block, *cols = s->block + BLOCK * N;
    for (int64_t l0 = 0; l0 < nq; l0 += BLOCK) {
        int64_t w = nq - l0 < BLOCK ? nq - l0 : BLOCK;
        for (int64_t b = 0; b < md->n; b++) { /* M T e_l for BLOCK columns l */
            const double *body = md->bodies + MB_BODY_W * b, *J = body + B_J;
            int64_t jc[6];
            for (int a = 0; a < 6; a++) jc[a] = s->col_of[6 * b + a];
            for (int64_t c = 0; c < w; c++) {
                double tc[6], *x = xs + c * N;
                for (int a = 0; a < 6; a++) tc[a] = jc[a] >= 0 ? T[jc[a] * nq + l0 + c] : 0.0;
                for (int a = 0; a < 3; a++) {
                    if (jc[a] >= 0) x[jc[a]] = body[B_MASS] * tc[a];
                    if (jc[3 + a] >= 0)
                        x[jc[3 + a]] = J[3 * a] * tc[3] + J[3 * a + 1] * tc[4] + J[3 * a + 2] * tc[5];
                }
            }
        }
        for (int64_t c = 0; c < w; c++) qr_transposed(s, xs + c * N, cols + c * nq, work);
        for (int64_t k = 0; k < nq; k++)
            for (int64_t c = 0; c < w; c++) Mq[k * nq + l0 + c] = cols[c * nq + k];
    }
    for (int64_t k = 0; k < nq; k++) /* symmetric in exact arithmetic: made so */
        for (int64_t l = k + 1; l < nq; l++) {
            double m = 0.5 * (Mq[k * nq + l] + Mq[l * nq + k]);
            Mq[k * nq + l] = Mq[l * nq + k] = m;
        }
}

int mb_generalized(const mb_model *md, const mb_unknowns *u, mb_work *w, double t,
                   const double *y, const double *lam, int64_t nq, const int64_t *Iq,
                   int64_t nc, const int64_t *cols, const double *qdot, double *out) {
    gen_scratch s;
    if (scratch_new(&s, md, u, nq, nc, cols) < 0) return -1;
    int64_t N = nc, n = md->n, nq1 = nq > 0 ? nq : 1, cc[nq1], cp[nq1];
    memcpy(s.y, y, sizeof(double) * 13 * n);
    mb_eval_all(md, w, t);
    double *T = out, *ve = T + N * nq, *a0 = ve + N, *Mq = a0 + N, *fq = Mq + nq * nq;
    double *qv = fq + nq, *qd = qv + nq, *scale = qd + nq, *info = scale + nq;
    double ratio = factor(md, u, w, &s, nq, Iq, cc, cp, qv);
    if (ratio < 0.0) {
        scratch_free(&s);
        return -1;
    }
    for (int64_t k = 0; k < nq; k++)
        qd[k] = qdot ? qdot[k] : row_dot_v(s.arow + 12 * k, cc[k], cp[k], y, n, s.col_of);
    double resid = transformation(&s, nq, T, 0);
    forces(md, u, w, &s, nq, Iq, qd, lam, ve, a0, fq);
    mass(md, &s, nq, T, Mq);
    info[MB_GI_RANK] = ratio;
    info[MB_GI_RESIDUAL] = resid;
    /* the magnitude of the terms that make each f_q (what its rounding is relative to):
     * per group of rows (translations, rotations) the largest entry of T's column times
     * the sum over the group's rows of |m g|, each load's and spring end's |share|,
     * |w| |J w|, |G_K lam_K| and |M a0| */
    int64_t nl = md->k + 2 * md->s;
    double *Q = malloc(sizeof(double) * (size_t)(12 * (n > 0 ? n : 1) + 7 * (nl > 0 ? nl : 1)));
    if (Q == NULL) {
        scratch_free(&s);
        return -1;
    }
    double *b = Q + 6 * n, *shares = b + 6 * n, sum[2] = {0.0, 0.0};
    mb_wrench_parts(md, w, t, s.y, Q, b);
    mb_load_wrenches_at(md, w, s.y, shares);
    for (int64_t l = 0; l < nl; l++) {
        int64_t body = (int64_t)shares[7 * l];
        if (body < 0) continue;
        for (int a = 0; a < 6; a++)
            if (s.col_of[6 * body + a] >= 0) sum[a >= 3] += fabs(shares[7 * l + 1 + a]);
    }
    for (int64_t c = 0; c < 6 * n; c++) {
        int64_t j = s.col_of[c];
        if (j < 0) continue;
        int64_t body = c / 6, a = c % 6;
        const double *bd = md->bodies + MB_BODY_W * body;
        double Ma = a < 3 ? bd[B_MASS] * fabs(a0[j]) : 0.0;
        if (a >= 3)
            for (int e = 0; e < 3; e++) {
                int64_t je = s.col_of[6 * body + 3 + e];
                if (je >= 0) Ma += fabs(bd[B_J + 3 * (a - 3) + e] * a0[je]);
            }
        double gravity = a < 3 ? bd[B_MASS] * fabs(md->gravity[a]) : 0.0;
        double known = fabs(s.r6[c] - (Q[c] - b[c]));
        /* the gyroscopic term's own size |w| |J w| (w x J w cancels about a principal axis) */
        double gyro = 0.0;
        if (a >= 3) {
            const double *om = s.y + 10 * n + 3 * body, *J = bd + B_J;
            double h0 = J[0] * om[0] + J[1] * om[1] + J[2] * om[2];
            double h1 = J[3] * om[0] + J[4] * om[1] + J[5] * om[2];
            double h2 = J[6] * om[0] + J[7] * om[1] + J[8] * om[2];
            gyro = sqrt(om[0] * om[0] + om[1] * om[1] + om[2] * om[2]) *
                   sqrt(h0 * h0 + h1 * h1 + h2 * h2);
        }
        sum[a >= 3] += gravity + fmax(fabs(b[c]), gyro) + known + Ma;
    }
    /* T's largest entries per column and group, row by row (Q's 12 n >= 2 nq doubles are
     * free now) */
    double *tau = Q;
    for (int64_t k = 0; k < 2 * nq; k++) tau[k] = 0.0;
    for (int64_t c = 0; c < 6 * n; c++) {
        int64_t j = s.col_of[c], g = c % 6 >= 3;
        if (j < 0) continue;
        const double *row = T + j * nq;
        for (int64_t k = 0; k < nq; k++) tau[2 * k + g] = fmax(tau[2 * k + g], fabs(row[k]));
    }
    for (int64_t k = 0; k < nq; k++)
        scale[k] = fmax(tau[2 * k] * sum[0] + tau[2 * k + 1] * sum[1], fabs(fq[k]));
    free(Q);
    scratch_free(&s);
    return 0;
}

/* y <- the state y0 moved by the velocity d (N, the model's columns) for a unit time:
 * positions x + d_v, orientations q (x) exp(d_w / 2) (body axes), exactly. */
static void move(const mb_model *md, const gen_scratch *s, const double *y0, const double *d,
                 double *y) {
    int64_t n = md->n;
    memcpy(y, y0, sizeof(double) * 13 * n);
    for (int64_t b = 0; b < n; b++) {
        double dv[6];
        for (int a = 0; a < 6; a++) {
            int64_t j = s->col_of[6 * b + a];
            dv[a] = j >= 0 ? d[j] : 0.0;
        }
        for (int a = 0; a < 3; a++) y[3 * b + a] += dv[a];
        double th = sqrt(dv[3] * dv[3] + dv[4] * dv[4] + dv[5] * dv[5]);
        if (th == 0.0) continue;
        double c = cos(0.5 * th), sn = sin(0.5 * th) / th;
        double p0 = sn * dv[3], p1 = sn * dv[4], p2 = sn * dv[5];
        double *q = y + 3 * n + 4 * b;
        double qw = q[0], qx = q[1], qy = q[2], qz = q[3];
        q[0] = qw * c - qx * p0 - qy * p1 - qz * p2;
        q[1] = qx * c + qw * p0 + qy * p2 - qz * p1;
        q[2] = qy * c + qw * p1 + qz * p0 - qx * p2;
        q[3] = qz * c + qw * p2 + qx * p1 - qy * p0;
    }
}

/* f_q at states near y0: its positions moved along v = T(y0) dq for a unit time, its rates
 * q0' + du. C is factored again only when the positions move (the rates alone reuse y0's
 * factors). */
typedef struct {
    gen_scratch s;
    double *T0, *a0, *d, *ystart, *qd;
    int64_t *cc, *cp;
    int factored; /* C's factors are those of y0's positions */
} perturber;

static void perturber_free(perturber *e) {
    free(e->T0), free(e->cc);
    scratch_free(&e->s);
}

static int perturber_new(perturber *e, const mb_model *md, const mb_unknowns *u, mb_work *w,
                         double t, const double *y0, int64_t nq, const int64_t *Iq, int64_t nc,
                         const int64_t *cols) {
    if (scratch_new(&e->s, md, u, nq, nc, cols) < 0) return -1;
    int64_t N = nc, n = md->n, nq1 = nq > 0 ? nq : 1, N1 = N > 0 ? N : 1;
    e->T0 = malloc(sizeof(double) * (size_t)(N * nq1 + 2 * N1 + 13 * (n > 0 ? n : 1) + nq1));
    e->cc = malloc(sizeof(int64_t) * (size_t)(2 * nq1));
    if (e->T0 == NULL || e->cc == NULL) {
        free(e->T0), free(e->cc);
        scratch_free(&e->s);
        return -1;
    }
    e->a0 = e->T0 + N * nq, e->d = e->a0 + N1, e->ystart = e->d + N1;
    e->qd = e->ystart + 13 * (n > 0 ? n : 1), e->cp = e->cc + nq1;
    mb_eval_all(md, w, t);
    memcpy(e->s.y, y0, sizeof(double) * 13 * n);
    memcpy(e->ystart, y0, sizeof(double) * 13 * n);
    if (factor(md, u, w, &e->s, nq, Iq, e->cc, e->cp, NULL) < 0.0) {
        perturber_free(e);
        return -1;
    }
    transformation(&e->s, nq, e->T0, 1); /* by columns */
    e->factored = 1;
    return 0;
}

/* f (nq) with the positions moved by dq and the rates by du (nq each), or, dq NULL, by hq
 * along coordinate j alone and the rate of j by hu (the same numbers as those vectors). */
static void perturbed_f(perturber *e, const mb_model *md, const mb_unknowns *u, mb_work *w,
                        const double *lam, const int64_t *Iq, const double *qdot0,
                        const double *dq, const double *du, int64_t j, double hq, double hu,
                        double *f) {
    gen_scratch *s = &e->s;
    int64_t N = s->N, nq = s->nq;
    int moved = 0;
    if (dq != NULL)
        for (int64_t k = 0; k < nq; k++) moved |= dq[k] != 0.0;
    else
        moved = hq != 0.0;
    if (moved || !e->factored) {
        /* d = T0 dq, T0 by columns: each d_i sums over k in order, as a row times dq */
        for (int64_t i = 0; i < N; i++) e->d[i] = 0.0;
        if (dq != NULL) {
            for (int64_t k = 0; k < nq; k++)
                for (int64_t i = 0; i < N; i++) e->d[i] += e->T0[k * N + i] * dq[k];
        } else if (moved) {
            for (int64_t i = 0; i < N; i++) e->d[i] += e->T0[j * N + i] * hq;
        }
        move(md, s, e->ystart, e->d, s->y);
        factor(md, u, w, s, nq, Iq, e->cc, e->cp, NULL);
        e->factored = !moved;
    }
    for (int64_t k = 0; k < nq; k++)
        e->qd[k] = qdot0[k] + (du != NULL ? du[k] : k == j ? hu : 0.0);
    forces(md, u, w, s, nq, Iq, e->qd, lam, NULL, e->a0, f);
}

int mb_generalized_perturbed(const mb_model *md, const mb_unknowns *u, mb_work *w, double t,
                             const double *y0, const double *lam, int64_t nq,
                             const int64_t *Iq, int64_t nc, const int64_t *cols,
                             const double *qdot0, int64_t np, const double *P, double *fout) {
    perturber e;
    if (perturber_new(&e, md, u, w, t, y0, nq, Iq, nc, cols) < 0) return -1;
    for (int64_t p = 0; p < np; p++) {
        const double *dq = P + 2 * nq * p, *du = dq + nq;
        perturbed_f(&e, md, u, w, lam, Iq, qdot0, dq, du, 0, 0.0, 0.0, fout + nq * p);
    }
    perturber_free(&e);
    return 0;
}

int mb_independence(const mb_model *md, const mb_unknowns *u, mb_work *w, double t,
                    const double *y, int64_t nq, const int64_t *Iq, int64_t nc,
                    const int64_t *cols, const double *colscale, double *out) {
    gen_scratch s;
    if (scratch_new(&s, md, u, nq, nc, cols) < 0) return -1;
    int64_t N = nc, n = md->n, r = s.r, nq1 = nq > 0 ? nq : 1, cc[nq1], cp[nq1];
    double *g = malloc(sizeof(double) * (size_t)((r > N ? r : N) + r + 1));
    if (g == NULL) {
        scratch_free(&s);
        return -1;
    }
    double *rownorm = g + (r > N ? r : N);
    memcpy(s.y, y, sizeof(double) * 13 * n);
    mb_eval_all(md, w, t);
    double ratio = factor(md, u, w, &s, nq, Iq, cc, cp, NULL);
    if (ratio < 0.0) {
        free(g);
        scratch_free(&s);
        return -1;
    }
    out[r] = r == N ? ratio : 0.0;
    for (int64_t i = 0; i < r; i++) out[i] = 0.0;
    if (r == N && ratio > 0.0) {
        /* |(C S)_i| from the rows as factor put them (C's columns are scaled since: undo) */
        for (int64_t i = 0; i < r; i++) rownorm[i] = 0.0;
        for (int64_t i = 0; i < r; i++) {
            double row[12];
            int64_t c, p;
            if (i < s.mu) {
                int64_t comp = u->U[i], j = md->comps_i[4 * comp];
                memcpy(row, w->child6 + 6 * comp, 6 * sizeof(double));
                memcpy(row + 6, w->parent6 + 6 * comp, 6 * sizeof(double));
                c = md->joints_i[3 * j + 1], p = md->joints_i[3 * j];
            } else {
                memcpy(row, s.arow + 12 * (i - s.mu), 12 * sizeof(double));
                c = cc[i - s.mu], p = cp[i - s.mu];
            }
            for (int side = 0; side < 2; side++) {
                int64_t b = side ? p : c;
                if (b < 0) continue;
                for (int a = 0; a < 6; a++) {
                    int64_t j = s.col_of[6 * b + a];
                    if (j >= 0) rownorm[i] += row[6 * side + a] * colscale[j] * row[6 * side + a] * colscale[j];
                }
            }
            rownorm[i] = sqrt(rownorm[i]);
        }
        for (int64_t i = 0; i < r; i++) { /* column i of C^-1, in the scaled units */
            for (int64_t k = 0; k < r; k++) g[k] = k == i;
            qr_solve(&s, g);
            double sum = 0.0;
            for (int64_t k = 0; k < N; k++) sum += (g[k] / colscale[k]) * (g[k] / colscale[k]);
            double norm = rownorm[i] * sqrt(sum);
            out[i] = norm > 0.0 ? 1.0 / norm : 0.0;
        }
    }
    free(g);
    scratch_free(&s);
    return 0;
}

int mb_coordinate_rows(const mb_model *md, mb_work *w, double t, const double *y, int64_t nq,
                       const int64_t *Iq, int64_t nc, const int64_t *cols, double *rows,
                       double *values) {
    int64_t n = md->n, *col_of = malloc(sizeof(int64_t) * (size_t)(6 * (n > 0 ? n : 1)));
    if (col_of == NULL) return -1;
    for (int64_t i = 0; i < 6 * n; i++) col_of[i] = -1;
    for (int64_t j = 0; j < nc; j++) col_of[cols[j]] = j;
    gen_scratch s;
    memset(&s, 0, sizeof(s));
    s.col_of = col_of;
    mb_rotations(n, y + 3 * n, w->R);
    mb_eval_all(md, w, t);
    mb_columns_at(md, w, y, 1, w->child6, w->parent6, NULL, NULL, w->gamma, w->phi, w->gtv);
    memset(rows, 0, sizeof(double) * nq * nc);
    for (int64_t k = 0; k < nq; k++) {
        double row[12], gamma;
        int64_t c, p;
        coordinate_row(md, w, y, Iq + MB_GQ_W * k, row, &c, &p, &gamma, values + k);
        put_row(&s, rows + k * nc, 1, row, c, p);
    }
    free(col_of);
    return 0;
}

int mb_differences(const mb_model *md, const mb_unknowns *u, mb_work *w, double t,
                   const double *y0, const double *lam, int64_t nq, const int64_t *Iq,
                   int64_t nc, const int64_t *cols, const double *qdot0, const double *h,
                   const double *hu, const double *fscale, const double *f0, double rounding,
                   const int64_t *skip, const mb_progress *progress, double *out) {
    /* a column at a time (memory: a few vectors of nq): the rates' first, all at y0's
     * positions (one factorisation); then each position's f at +-h, at +-h/2 unless the
     * +-h ones are flat, at +-h/4 where the differences at h and h/2 disagree */
    int64_t nq1 = nq > 0 ? nq : 1, kk = nq * nq;
    double *fl = malloc(sizeof(double) * (size_t)(6 * nq1));
    perturber e;
    if (fl == NULL) return -1;
    if (nq > 0 && perturber_new(&e, md, u, w, t, y0, nq, Iq, nc, cols) < 0) {
        free(fl);
        return -1;
    }
    double *K = out, *Kerr = K + kk, *D = Kerr + kk, *Derr = D + kk;
    int status = 0;
    for (int64_t j = 0; j < nq && status == 0; j++) { /* D = -df/dq', exact for quadratic f */
        if (mb_report(progress, MB_STAGE_DAMPING, j, nq)) {
            status = MB_STOPPED;
            break;
        }
        perturbed_f(&e, md, u, w, lam, Iq, qdot0, NULL, NULL, j, 0.0, hu[j], fl);
        perturbed_f(&e, md, u, w, lam, Iq, qdot0, NULL, NULL, j, 0.0, -hu[j], fl + nq);
        for (int64_t i = 0; i < nq; i++) {
            D[i * nq + j] = -(fl[i] - fl[nq + i]) / (2.0 * hu[j]);
            double big = fmax(fscale[i], fmax(fabs(fl[i]), fabs(fl[nq + i])));
            Derr[i * nq + j] = 4.0 * rounding * big / hu[j];
        }
    }
    for (int64_t j = 0; j < nq && status == 0; j++) {
        if (mb_report(progress, MB_STAGE_STIFFNESS, j, nq)) {
            status = MB_STOPPED;
            break;
        }
        if (skip[j]) {
            for (int64_t i = 0; i < nq; i++) K[i * nq + j] = Kerr[i * nq + j] = 0.0;
            continue;
        }
        /* fl: [f(+h), f(-h), f(+h/2), f(-h/2), f(+h/4), f(-h/4)] */
        for (int level = 0; level < 3; level++) {
            double step = h[j] / (double)(1 << level);
            perturbed_f(&e, md, u, w, lam, Iq, qdot0, NULL, NULL, j, step, 0.0,
                        fl + 2 * level * nq);
            perturbed_f(&e, md, u, w, lam, Iq, qdot0, NULL, NULL, j, -step, 0.0,
                        fl + (2 * level + 1) * nq);
            int more = 0;
            if (level == 0) {
                /* flat: f at +-h equals f at the state within one evaluation's rounding in
                 * every row (a coordinate the forces do not depend on: a body's position
                 * under uniform gravity, a cyclic spin); its column is its central
                 * difference */
                int same = f0 != NULL;
                for (int64_t i = 0; i < nq && same; i++) {
                    double tol = 4.0 * rounding * fscale[i];
                    same = fabs(fl[i] - f0[i]) <= tol && fabs(fl[nq + i] - f0[i]) <= tol;
                }
                more = !same;
            } else if (level == 1) {
                /* a column whose two differences agree within their rounding has nothing
                 * left for a third step to extrapolate away (a coordinate the forces
                 * depend on linearly): it stops at one extrapolation */
                for (int64_t i = 0; i < nq && !more; i++) {
                    double d0 = (fl[i] - fl[nq + i]) / (2.0 * h[j]);
                    double d1 = (fl[2 * nq + i] - fl[3 * nq + i]) / (1.0 * h[j]);
                    more = !(fabs(d0 - d1) <= 4.0 * rounding * fscale[i] / (0.25 * h[j]));
                }
            }
            for (int64_t i = 0; i < nq; i++) {
                double round_err = 4.0 * rounding * fscale[i] / (0.25 * h[j]);
                double d0 = (fl[i] - fl[nq + i]) / (2.0 * h[j]);
                if (level == 0 && !more) { /* flat */
                    K[i * nq + j] = -d0;
                    Kerr[i * nq + j] = fabs(d0) + round_err;
                    continue;
                }
                if (level == 0) continue;
                double d1 = (fl[2 * nq + i] - fl[3 * nq + i]) / (1.0 * h[j]);
                double r1 = (4.0 * d1 - d0) / 3.0;
                if (level == 2) {
                    double d2 = (fl[4 * nq + i] - fl[5 * nq + i]) / (0.5 * h[j]);
                    double r2 = (4.0 * d2 - d1) / 3.0;
                    K[i * nq + j] = -(16.0 * r2 - r1) / 15.0;
                    Kerr[i * nq + j] = fabs(r1 - r2) / 15.0 + round_err;
                } else if (!more) { /* |d0 - d1| within rounding: d1's truncation too */
                    K[i * nq + j] = -r1;
                    Kerr[i * nq + j] = fabs(d0 - d1) + round_err;
                }
            }
            if (!more) break;
        }
    }
    if (nq > 0) perturber_free(&e);
    free(fl);
    return status;
}
