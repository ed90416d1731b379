/* What the kernel's files share and Python does not see: the scratch memory (struct
 * mb_work), the tolerances of the solves, and the small helpers each file implements. */
#ifndef MBODY_INTERNAL_H
#define MBODY_INTERNAL_H

#include <math.h>

#include "kernel.h"

/* Column offsets of the packed per-item rows (kernel.h). */
enum { B_MASS = 0, B_J = 1, B_JINV = 10 };
enum { L_BR = 0, L_VALUE = 3 };
enum { S_RA = 0, S_RB = 3, S_STIFF = 6, S_REST = 7, S_DAMP = 8 };
enum { J_BRC = 0, J_BRP = 3, J_CAX2 = 6, J_PE3 = 9, J_CE3 = 18, J_LLEN = 27 };

/* The solves' tolerances, as mbody.solve.nullspace, kkt and mbody.simulate.mechanism. */
#define G_RANK_RTOL 1e-12   /* rank of G_U's scaled geometry: sigma > this * sigma_max */
#define PIVOT_RTOL 1e-6     /* a Cholesky pivot of S keeping less of its diagonal: untrusted */
#define SINGULAR_RTOL 1e-14 /* the reduced mass matrix's pivots: a motion without mass */
#define STAB_RTOL 1e-4      /* Baumgarte's part regularised below this * sigma_max */
#define REFINE_STEPS 2      /* refinement rounds of the null-space solve */
#define DEPENDENT_RTOL 1e-10 /* exactly redundant columns: G_j - G_I x_j below this */
#define REDUNDANT_BERR 1e-13 /* ... and a consistent answer */
#define DROPPED_RTOL 1e-13  /* an exactly redundant constraint's pivot ratio (projection) */
#define JOINT_TOL 1e-6      /* as mbody.equations.constraints.JOINT_TOL */
#define SPLIT 134217729.0   /* 2**27 + 1, Dekker's splitting constant */

/* The null-space route's buffers (allocated on its first use; B holds U2). */
typedef struct {
    int64_t nr, mu, cap_nr, cap_mu;
    double *A, *T, *C, *B, *Uf, *sv, *V, *Vc, *Mb, *MU2, *red, *Lr, *rh, *gh, *sh, *ah,
        *lamh, *r1, *r2, *da, *dl, *rest, *t2, *cvec, *tmp, *Nn, *Q, *hh, *eig;
    int64_t *order;
} mb_ns;

/* The exactly-redundant route's dense buffers (allocated on its first use). */
typedef struct {
    double *S, *X, *Nn, *Q, *diag, *coef, *res, *rhs, *rhs6;
    int64_t *perm;
} mb_dense;

struct mb_work {
    int64_t n, m, nj, k, s, mu, bw, n_expr;
    double *R;                       /* n x 9 W_R_B, row-major */
    double *r6, *acc, *rhs, *r1, *dacc; /* n x 6 */
    double *child6, *parent6;        /* m x 6 */
    double *W_e, *W_P;               /* m x 3 */
    double *gamma, *phi, *gtv, *lam; /* m */
    double *jWE, *jRrel;             /* nj x 9 */
    double *jP, *jBrp, *jd, *jT, *jwc, *jwp; /* nj x 3 */
    double *loads;                   /* k x 3 load values at t */
    double *evals, *stack;           /* n_expr values at t; n_code stack */
    double *gam, *stab, *lamU, *r2, *dlam; /* mu */
    unsigned char *nonunique;        /* mu */
    double *Sb, *S0;                 /* mu x (bw + 1) */
    double *unit;                    /* n x MB_BODY_W: unit masses (geometric ratio) */
    mb_dense *dense;
    mb_ns *ns;
};

/* Reports a step of a long call (kernel.h, mb_progress): nonzero means stop. */
static inline int mb_report(const mb_progress *p, int stage, int64_t done, int64_t total) {
    return p != NULL && p->report != NULL ? p->report(p->ctx, stage, done, total) : 0;
}

/* spatial.c */
void mb_rotations(int64_t n, const double *q, double *R);
void mb_minv(const double *body, const double *g, double *out);
void mb_body_point(int64_t body, const double *r, const double *x, const double *R,
                   const double *v, const double *w, double *P, double *V);
void mb_turn_exact(double *q, const double *th);

static inline void mb_cross(const double *a, const double *b, double *out) {
    double o0 = a[1] * b[2] - a[2] * b[1], o1 = a[2] * b[0] - a[0] * b[2],
           o2 = a[0] * b[1] - a[1] * b[0];
    out[0] = o0;
    out[1] = o1;
    out[2] = o2;
}

/* expressions.c: evaluations at t into w->evals and w->loads (and lam's varying
 * entries); the law of component i at t: f[0..2] = f, f', f'' (0 without a law). */
void mb_eval_all(const mb_model *md, mb_work *w, double t);
void mb_loads_at(const mb_model *md, mb_work *w);
void mb_law(const mb_model *md, const mb_work *w, int64_t comp, double *f);
void mb_known_at(const mb_model *md, const mb_work *w, const double *lam, double *out);

/* loads.c */
void mb_net_wrench_at(const mb_model *md, mb_work *w, const double *y, double *out);
void mb_load_wrenches_at(const mb_model *md, mb_work *w, const double *y, double *out);
void mb_springs_at(const mb_model *md, mb_work *w, const double *y, double *out);

/* joints.c: columns at y into the given buffers (W_e, W_P may be NULL); with `laws`
 * 0 the laws are left out (the homogeneous constraints). Needs w->R and w->evals. */
void mb_columns_at(const mb_model *md, mb_work *w, const double *y, int laws,
                   double *child6, double *parent6, double *W_e, double *W_P,
                   double *gamma, double *phi, double *gtv);
/* The velocity part of mb_columns_at at y, whose positions are those of the last
 * mb_columns_at (its columns child6, parent6 and the joints' frames and points still in
 * w): the joints' velocity data, gamma and G^T v, the same numbers as a whole call. */
void mb_gammas_at(const mb_model *md, mb_work *w, const double *y, int laws,
                  const double *child6, const double *parent6, double *gamma, double *gtv);

/* solve.c */
void mb_schur(const mb_model *md, const mb_unknowns *u, const double *bodies,
              const double *child6, const double *parent6, double *S, int banded);
double mb_band_cholesky(double *Sb, int64_t mu, int64_t bw, double rtol, int stop);
double mb_inv_length(const mb_model *md, const mb_unknowns *u, const double *child6,
                     const double *parent6);
void mb_add_g(const mb_model *md, const mb_unknowns *u, const double *child6,
              const double *parent6, const double *lam, double *out, double sign);
void mb_orthonormal(double *Q, int64_t rows, int64_t cols);
void mb_cho_solve_dense(const double *L, int64_t ld, int64_t r, double *x);
/* Solve M a - G_U lam = r6, G_U^T a = gam (gam includes stab); returns the singular
 * code, writes rank, berr, path. berr NULL with refine 0: no backward error is computed
 * (nor the refinement it would decide). */
int mb_constrained(const mb_model *md, const mb_unknowns *u, mb_work *w, int refine,
                   int64_t *rank, double *berr, int *path);
void mb_dot_add(double *s, double *c, double a, double b);

/* nullspace.c */
int mb_null_space(const mb_model *md, const mb_unknowns *u, mb_work *w, int refine,
                  int64_t *rank);
/* linalg.c */
void mb_svd(const double *A, int64_t m, int64_t n, double *sv, double *U, double *V,
            double *work);
void mb_complete(const double *Q1, int64_t m, int64_t r, double *Q2, double *hh);
void mb_eig_smallest(const double *S, int64_t n, double *vec, double *work);

/* work.c */
int mb_ensure_dense(mb_work *w);
int mb_ensure_ns(mb_work *w, int64_t nr, int64_t mu);

#endif
