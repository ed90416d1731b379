/* Rotations and rigid-body kinematics: W_R_B from quaternions, a body point's position
 * and velocity, and M^-1 applied to one body's six rows. */
#include "internal.h"

/* R (n x 9, row-major W_R_B) from q (n x 4) [w, x, y, z], each normalised first. */
void mb_rotations(int64_t n, const double *q, double *R) {
    for (int64_t i = 0; i < n; i++) {
        const double *qi = q + 4 * i;
        double s = 1.0 / sqrt(qi[0] * qi[0] + qi[1] * qi[1] + qi[2] * qi[2] + qi[3] * qi[3]);
        double w = qi[0] * s, x = qi[1] * s, y = qi[2] * s, z = qi[3] * s;
        double xx = x * x, yy = y * y, zz = z * z, xy = x * y, xz = x * z, yz = y * z;
        double wx = w * x, wy = w * y, wz = w * z;
        double *Ri = R + 9 * i;
        Ri[0] = 1 - 2 * (yy + zz);
        Ri[1] = 2 * (xy - wz);
        Ri[2] = 2 * (xz + wy);
        Ri[3] = 2 * (xy + wz);
        Ri[4] = 1 - 2 * (xx + zz);
        Ri[5] = 2 * (yz - wx);
        Ri[6] = 2 * (xz - wy);
        Ri[7] = 2 * (yz + wx);
        Ri[8] = 1 - 2 * (xx + yy);
    }
}

/* out (6) = M_i^-1 g (6): [g_N / m, J^-1 g_E]; body: the body's packed row. */
void mb_minv(const double *body, const double *g, double *out) {
    double m = body[B_MASS];
    const double *Ji = body + B_JINV;
    double g3 = g[3], g4 = g[4], g5 = g[5];
    out[0] = g[0] / m;
    out[1] = g[1] / m;
    out[2] = g[2] / m;
    for (int a = 0; a < 3; a++) out[3 + a] = Ji[3 * a] * g3 + Ji[3 * a + 1] * g4 + Ji[3 * a + 2] * g5;
}

/* World position P and velocity V of body point r (body axes): P = x + R r,
 * V = v + R (w x r); body -1: r is a world point at rest. x, v, w: the state's blocks. */
void mb_body_point(int64_t body, const double *r, const double *x, const double *R,
                   const double *v, const double *w, double *P, double *V) {
    if (body < 0) {
        P[0] = r[0], P[1] = r[1], P[2] = r[2];
        V[0] = V[1] = V[2] = 0.0;
        return;
    }
    double c[3];
    mb_cross(w + 3 * body, r, c);
    const double *Rb = R + 9 * body;
    for (int a = 0; a < 3; a++) {
        P[a] = x[3 * body + a] + Rb[3 * a] * r[0] + Rb[3 * a + 1] * r[1] + Rb[3 * a + 2] * r[2];
        V[a] = v[3 * body + a] + Rb[3 * a] * c[0] + Rb[3 * a + 1] * c[1] + Rb[3 * a + 2] * c[2];
    }
}

/* q <- q (x) (cos |th|/2, sin |th|/2 th/|th|), normalised: the body turned exactly by the
 * rotation vector th (body axes), not to first order. */
void mb_turn_exact(double *q, const double *th) {
    double ang = sqrt(th[0] * th[0] + th[1] * th[1] + th[2] * th[2]);
    double c = cos(0.5 * ang), f = ang > 0.0 ? sin(0.5 * ang) / ang : 0.5;
    double p0 = f * th[0], p1 = f * th[1], p2 = f * th[2];
    double qw = q[0], qx = q[1], qy = q[2], qz = q[3];
    double nw = c * qw - qx * p0 - qy * p1 - qz * p2;
    double nx = c * qx + qw * p0 + qy * p2 - qz * p1;
    double ny = c * qy + qw * p1 + qz * p0 - qx * p2;
    double nz = c * qz + qw * p2 + qx * p1 - qy * p0;
    double s = 1.0 / sqrt(nw * nw + nx * nx + ny * ny + nz * nz);
    q[0] = nw * s, q[1] = nx * s, q[2] = ny * s, q[3] = nz * s;
}
