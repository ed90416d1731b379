/* A run's figures at its output samples (mechanism.h: mb_samples): the reactions, the
 * springs' lengths and the joints' drift, one pass over the samples in C. */
#include <math.h>
#include <stdlib.h>

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
        }
        if (m > 0) {
            mb_columns(md, w, t[k], y, c6, p6, We, WP, gamma, phi, gtv);
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
