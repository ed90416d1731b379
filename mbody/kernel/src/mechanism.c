/* A simulation's problem as DOP853's callbacks (mechanism.h): mb_derivative and
 * mb_project bound to the integrator, so that a whole run steps in C. */
#include "mechanism.h"

#include <string.h>

#include "internal.h"

int64_t mb_mechanism_scratch(const mb_model *md) {
    return MB_STATE_SIZE(md->n, md->planar) + md->n;
}

int mb_mechanism_rhs(void *ctx, double t, const double *y, double *ydot) {
    const mb_mechanism *c = ctx;
    return mb_derivative(c->md, c->u, c->w, t, y, c->lam, c->params[MB_MECH_RATE], ydot);
}

int mb_mechanism_project(void *ctx, double t, double *y, double *info) {
    const mb_mechanism *c = ctx;
    double pinfo[MB_PROJECT_INFO];
    const double robust = c->params[MB_MECH_ROBUST];
    mb_project(c->md, c->u, c->w, t, y, (int)c->params[MB_MECH_ITERS], robust, 0, pinfo);
    if (pinfo[MB_PR_SINGULAR] != 0.0) return (int)pinfo[MB_PR_SINGULAR];
    const double step = pinfo[MB_PR_STEP], change = pinfo[MB_PR_VELOCITY];
    info[0] = step > change ? step : change;
    info[1] = pinfo[MB_PR_RATIO] < robust ? 1.0 : 0.0;
    info[2] = pinfo[MB_PR_RATIO];
    info[3] = 0.0;
    return 0;
}

int mb_mechanism_stage(void *ctx, double t, double *y) {
    const mb_mechanism *c = ctx;
    double pinfo[MB_PROJECT_INFO];
    mb_project(c->md, c->u, c->w, t, y, (int)c->params[MB_MECH_STAGE_ITERS],
               c->params[MB_MECH_ROBUST], 0, pinfo);
    return (int)pinfo[MB_PR_SINGULAR];
}

/* z's velocity blocks projected onto G^T dv = 0 at z's positions (no position step). */
static int tangent_velocities(const mb_mechanism *c, double *z) {
    double pinfo[MB_PROJECT_INFO];
    mb_project(c->md, c->u, c->w, 0.0, z, 0, c->params[MB_MECH_ROBUST], 1, pinfo);
    return (int)pinfo[MB_PR_SINGULAR];
}

int mb_mechanism_tangent(void *ctx, double t, const double *y, double *e) {
    const mb_mechanism *c = ctx;
    const int64_t n = c->md->n, size = MB_STATE_SIZE(n, c->md->planar);
    double *z = c->scratch, *radial = c->scratch + size;
    /* the velocity block: dv, dw projected as they are */
    memcpy(z, y, (size_t)size * sizeof(double));
    memcpy(z + 7 * n, e + 7 * n, (size_t)(6 * n) * sizeof(double));
    int code = tangent_velocities(c, z);
    if (code) return code;
    memcpy(e + 7 * n, z + 7 * n, (size_t)(6 * n) * sizeof(double));
    /* the position block as a motion: dx, and dq = q (x) (0, dphi) / 2 + radial q ->
     * dphi = 2 vec(conj(q) (x) (dq - radial q)) / |q|^2 (body axes, as w) */
    memcpy(z, y, (size_t)size * sizeof(double));
    memcpy(z + 7 * n, e, (size_t)(3 * n) * sizeof(double));
    for (int64_t i = 0; i < n; i++) {
        const double *q = y + 3 * n + 4 * i, *dq = e + 3 * n + 4 * i;
        const double norm2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
        const double r = (q[0] * dq[0] + q[1] * dq[1] + q[2] * dq[2] + q[3] * dq[3]) / norm2;
        const double rw = dq[0] - r * q[0];
        const double rv[3] = {dq[1] - r * q[1], dq[2] - r * q[2], dq[3] - r * q[3]};
        double ux[3];
        mb_cross(q + 1, rv, ux);
        double *dphi = z + 10 * n + 3 * i;
        for (int a = 0; a < 3; a++)
            dphi[a] = 2.0 * (q[0] * rv[a] - rw * q[1 + a] - ux[a]) / norm2;
        radial[i] = r;
    }
    code = tangent_velocities(c, z);
    if (code) return code;
    memcpy(e, z + 7 * n, (size_t)(3 * n) * sizeof(double));
    for (int64_t i = 0; i < n; i++) {
        const double *q = y + 3 * n + 4 * i, *p = z + 10 * n + 3 * i;
        double *o = e + 3 * n + 4 * i;
        const double r = radial[i];
        /* 1/2 q (x) (0, dphi) + radial q */
        o[0] = -0.5 * (q[1] * p[0] + q[2] * p[1] + q[3] * p[2]) + r * q[0];
        o[1] = 0.5 * (q[0] * p[0] + (q[2] * p[2] - q[3] * p[1])) + r * q[1];
        o[2] = 0.5 * (q[0] * p[1] + (q[3] * p[0] - q[1] * p[2])) + r * q[2];
        o[3] = 0.5 * (q[0] * p[2] + (q[1] * p[1] - q[2] * p[0])) + r * q[3];
        if (c->md->planar) e[13 * n + i] = p[2];
    }
    (void)t;
    return 0;
}
