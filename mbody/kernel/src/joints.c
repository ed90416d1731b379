/* The joints: per joint, its frame and the kinematics its components share; per
 * component, one function per constraint primitive (MB_KIND_*, kernel.h) giving its
 * columns of G (child6, parent6), gamma = -G'^T v, phi and its direction e.
 * A law (driven component) then shifts phi, G^T v and gamma by f, f', f'' at t. */
#include "internal.h"

#define TWO_PI 6.283185307179586
#define PI 3.141592653589793

static const double IDENTITY[9] = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};

/* What one joint's components share, at one state (world axes unless said). */
typedef struct {
    const double *row;      /* the joint's packed row */
    int64_t p, c;           /* parent (-1 ground), child */
    const double *Rc;       /* the child's W_R_B */
    const double *Rp;       /* the parent's (identity for ground) */
    const double *WE;       /* (R_p P_E3), row-major: WE[3 a + b] */
    const double *Rrel;     /* A = (R_p P_E3)^T (R_c C_E3) */
    const double *P, *Brp, *d, *T, *wc, *wp;
} joint_state;

/* One component's output. */
typedef struct {
    double *child6, *parent6, gamma, phi, e[3];
} column;

/* The joint's velocity data at y (w_c, w_p and T = the relative acceleration's velocity
 * part), from its points (P, the parent's point of it) already in w. */
static void joint_velocities(const mb_model *md, mb_work *w, const double *y, int64_t j) {
    int64_t n = md->n;
    const double *x = y, *v = y + 7 * n, *om = y + 10 * n;
    int64_t p = md->joints_i[3 * j], c = md->joints_i[3 * j + 1];
    const double *Rp = p >= 0 ? w->R + 9 * p : IDENTITY, *Rc = w->R + 9 * c;
    const double *P = w->jP + 3 * j;
    double *T = w->jT + 3 * j, *wc = w->jwc + 3 * j, *wp = w->jwp + 3 * j;
    double xp[3] = {0.0, 0.0, 0.0}, vp[3] = {0.0, 0.0, 0.0};
    if (p >= 0)
        for (int a = 0; a < 3; a++) xp[a] = x[3 * p + a], vp[a] = v[3 * p + a];
    double s[3] = {P[0] - xp[0], P[1] - xp[1], P[2] - xp[2]};
    for (int a = 0; a < 3; a++) {
        wc[a] = Rc[3 * a] * om[3 * c] + Rc[3 * a + 1] * om[3 * c + 1] + Rc[3 * a + 2] * om[3 * c + 2];
        wp[a] = 0.0;
        if (p >= 0)
            wp[a] = Rp[3 * a] * om[3 * p] + Rp[3 * a + 1] * om[3 * p + 1] + Rp[3 * a + 2] * om[3 * p + 2];
    }
    double rho[3] = {P[0] - x[3 * c], P[1] - x[3 * c + 1], P[2] - x[3 * c + 2]};
    double cr[3], e[3], t[3], aa[3], bb[3], Vc[3], D[3], Vr[3];
    mb_cross(wc, rho, cr);
    for (int a = 0; a < 3; a++) Vc[a] = v[3 * c + a] + cr[a];
    mb_cross(wp, s, e);
    for (int a = 0; a < 3; a++) D[a] = Vc[a] - vp[a] - e[a], Vr[a] = Vc[a] - vp[a];
    mb_cross(D, wp, t);
    mb_cross(wc, cr, aa);
    mb_cross(wp, Vr, bb);
    for (int a = 0; a < 3; a++) T[a] = t[a] + aa[a] - bb[a];
}

static void joint_geometry(const mb_model *md, mb_work *w, const double *y, int64_t j) {
    const double *x = y;
    const double *row = md->joints + MB_JOINT_W * j;
    int64_t p = md->joints_i[3 * j], c = md->joints_i[3 * j + 1];
    const double *Rp = p >= 0 ? w->R + 9 * p : IDENTITY, *Rc = w->R + 9 * c;
    const double *PE = row + J_PE3, *CE = row + J_CE3;
    double *WE = w->jWE + 9 * j, *P = w->jP + 3 * j, *Brp = w->jBrp + 3 * j;
    double *d = w->jd + 3 * j, *Rrel = w->jRrel + 9 * j;
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++)
            WE[3 * a + b] = Rp[3 * a] * PE[b] + Rp[3 * a + 1] * PE[3 + b] + Rp[3 * a + 2] * PE[6 + b];
    for (int a = 0; a < 3; a++)
        P[a] = x[3 * c + a] + Rc[3 * a] * row[J_BRC] + Rc[3 * a + 1] * row[J_BRC + 1] +
               Rc[3 * a + 2] * row[J_BRC + 2];
    double xp[3] = {0.0, 0.0, 0.0};
    if (p >= 0)
        for (int a = 0; a < 3; a++) xp[a] = x[3 * p + a];
    double s[3] = {P[0] - xp[0], P[1] - xp[1], P[2] - xp[2]};
    for (int a = 0; a < 3; a++) {
        Brp[a] = Rp[a] * s[0] + Rp[3 + a] * s[1] + Rp[6 + a] * s[2];
        d[a] = P[a] - (xp[a] + Rp[3 * a] * row[J_BRP] + Rp[3 * a + 1] * row[J_BRP + 1] +
                       Rp[3 * a + 2] * row[J_BRP + 2]);
    }
    joint_velocities(md, w, y, j);
    /* R_rel = (R_p P_E3)^T (R_c C_E3), for the moment components' phi; R_c C_E3 made
     * once (each entry the same sum as when it was made per entry of R_rel) */
    double RC[9];
    for (int k = 0; k < 3; k++)
        for (int b = 0; b < 3; b++)
            RC[3 * k + b] = Rc[3 * k] * CE[b] + Rc[3 * k + 1] * CE[3 + b] + Rc[3 * k + 2] * CE[6 + b];
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) {
            double acc = 0.0;
            for (int k = 0; k < 3; k++) acc += WE[3 * k + a] * RC[3 * k + b];
            Rrel[3 * a + b] = acc;
        }
}

static void load_joint(const mb_model *md, const mb_work *w, int64_t j, joint_state *js) {
    js->row = md->joints + MB_JOINT_W * j;
    js->p = md->joints_i[3 * j], js->c = md->joints_i[3 * j + 1];
    js->Rc = w->R + 9 * js->c;
    js->Rp = js->p >= 0 ? w->R + 9 * js->p : IDENTITY;
    js->WE = w->jWE + 9 * j, js->Rrel = w->jRrel + 9 * j;
    js->P = w->jP + 3 * j, js->Brp = w->jBrp + 3 * j, js->d = w->jd + 3 * j;
    js->T = w->jT + 3 * j, js->wc = w->jwc + 3 * j, js->wp = w->jwp + 3 * j;
}

/* R^T e */
static void to_body(const double *R, const double *e, double *B) {
    for (int a = 0; a < 3; a++) B[a] = R[a] * e[0] + R[3 + a] * e[1] + R[6 + a] * e[2];
}

/* The moment column about e: child6 = [0; R_c^T e], parent6 = [-0; -Bp]. */
static void moment_column(const joint_state *js, const double *Bp, column *col) {
    double Bc[3];
    to_body(js->Rc, col->e, Bc);
    for (int a = 0; a < 3; a++) {
        col->child6[a] = 0.0;
        col->child6[3 + a] = Bc[a];
        col->parent6[3 + a] = -Bp[a];
    }
}

/* -e . (w_c x w_p): gamma of a moment about an axis fixed in the parent. */
static double moment_gamma(const joint_state *js, const double *e) {
    double k[3];
    mb_cross(js->wc, js->wp, k);
    return -(e[0] * k[0] + e[1] * k[1] + e[2] * k[2]);
}

/* The joint frame's column `axis`, in world axes (e) and fixed in the parent (Bp:
 * parent axes; world for ground). */
static void frame_axis(const joint_state *js, int64_t axis, double *e, double *Bp) {
    const double *PE = js->row + J_PE3;
    for (int a = 0; a < 3; a++) e[a] = js->WE[3 * a + axis], Bp[a] = PE[3 * a + axis];
}

/* The relative turn about the joint frame's axis `axis`: atan2(A[j][i], A[i][i]). */
static double turn_angle(const joint_state *js, int64_t axis) {
    int i = (int)((axis + 1) % 3), j = (int)((axis + 2) % 3);
    return atan2(js->Rrel[3 * j + i], js->Rrel[3 * i + i]);
}

static double wrap(double a) { return a - TWO_PI * ceil((a - PI) / TWO_PI); }

/* -e . T: gamma of a force along e (T: the joint's relative acceleration's velocity
 * part). */
static double force_gamma(const joint_state *js, const double *e) {
    return -(e[0] * js->T[0] + e[1] * js->T[1] + e[2] * js->T[2]);
}

/* G_i^T v for a component's columns c6 (on body c) and p6 (on body p, -1: ground). */
static double column_dot_v(const double *c6, const double *p6, int64_t c, int64_t p,
                           const double *v, const double *om) {
    double s = 0.0;
    for (int a = 0; a < 3; a++) s += c6[a] * v[3 * c + a] + c6[3 + a] * om[3 * c + a];
    if (p >= 0)
        for (int a = 0; a < 3; a++) s += p6[a] * v[3 * p + a] + p6[3 + a] * om[3 * p + a];
    return s;
}

/* Component i's joint, kind, axis, offset and lead (h); its law's f, f', f'' at w's time
 * into f when `laws` and it has one (returns whether it does). */
static int component(const mb_model *md, const mb_work *w, int64_t i, int laws, int64_t *j,
                     int64_t *kind, int64_t *axis, double *off, double *h, double *f) {
    const int64_t *ci = md->comps_i + 4 * i;
    *j = ci[0], *kind = ci[1], *axis = ci[2];
    *off = md->comps_f[MB_COMP_W * i], *h = md->comps_f[MB_COMP_W * i + 1];
    f[0] = f[1] = f[2] = 0.0;
    int driven = laws && ci[3] >= 0;
    if (driven) mb_law(md, w, i, f);
    return driven;
}

/* MB_KIND_FORCE: child6 = [e; B_r_c x R_c^T e], parent6 = [-e; -(B_r_p x Bp)],
 * phi = e . d, gamma = -e . T. */
static void force(const joint_state *js, int64_t axis, column *col) {
    double Bp[3], Bc[3], mc[3], mp[3];
    frame_axis(js, axis, col->e, Bp);
    to_body(js->Rc, col->e, Bc);
    mb_cross(js->row + J_BRC, Bc, mc);
    mb_cross(js->Brp, Bp, mp);
    const double *e = col->e;
    for (int a = 0; a < 3; a++) {
        col->child6[a] = e[a];
        col->child6[3 + a] = mc[a];
        col->parent6[3 + a] = -mp[a];
    }
    col->gamma = force_gamma(js, e);
    col->phi = e[0] * js->d[0] + e[1] * js->d[1] + e[2] * js->d[2];
}

/* MB_KIND_TILT and MB_KIND_LOCK: a moment about the frame's axis. */
static void tilt(const joint_state *js, int64_t axis, int locked, column *col) {
    double Bp[3];
    frame_axis(js, axis, col->e, Bp);
    moment_column(js, Bp, col);
    col->gamma = moment_gamma(js, col->e);
    const double *A = js->Rrel;
    if (!locked) /* tilt of the child's joint z axis in the parent's frame */
        col->phi = axis == 0 ? -A[5] : A[2];
    else if (axis == 0) /* small-rotation vector 1/2 vee(A - A^T) */
        col->phi = 0.5 * (A[7] - A[5]);
    else if (axis == 1)
        col->phi = 0.5 * (A[2] - A[6]);
    else
        col->phi = 0.5 * (A[3] - A[1]);
}

/* MB_KIND_RIGHT_ANGLE: the universal joint's moment about e = a x b / |a x b|. */
static void right_angle(const joint_state *js, column *col) {
    double a[3] = {js->WE[2], js->WE[5], js->WE[8]}, b[3], Bp[3];
    const double *cx = js->row + J_CAX2, *Rc = js->Rc;
    for (int r = 0; r < 3; r++) b[r] = Rc[3 * r] * cx[0] + Rc[3 * r + 1] * cx[1] + Rc[3 * r + 2] * cx[2];
    double *e = col->e;
    mb_cross(a, b, e);
    double nrm = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    e[0] = e[0] / nrm, e[1] = e[1] / nrm, e[2] = e[2] / nrm;
    if (js->p >= 0) to_body(js->Rp, e, Bp);
    else Bp[0] = e[0], Bp[1] = e[1], Bp[2] = e[2];
    double pa[3], q[3], cb[3], r[3];
    const double *wc = js->wc, *wp = js->wp;
    mb_cross(wp, a, pa);
    mb_cross(pa, b, q);
    mb_cross(wc, b, cb);
    mb_cross(a, cb, r);
    col->gamma = -((q[0] + r[0]) * (wc[0] - wp[0]) + (q[1] + r[1]) * (wc[1] - wp[1]) +
                   (q[2] + r[2]) * (wc[2] - wp[2]));
    col->phi = -(a[0] * b[0] + a[1] * b[1] + a[2] * b[2]);
    moment_column(js, Bp, col);
}

/* MB_KIND_LINK: a particle link's tension, e = -u, u = d / |d|, phi = L - |d|,
 * gamma = u . (w_c x (w_c x rho_c) - w_p x (w_p x rho_p)) + (|d'|^2 - (u . d')^2) / |d|. */
static void link(const mb_model *md, const double *y, const joint_state *js, column *col) {
    int64_t n = md->n, p = js->p, c = js->c;
    const double *v = y + 7 * n, *row = js->row, *dj = js->d, *Rc = js->Rc;
    double dist = sqrt(dj[0] * dj[0] + dj[1] * dj[1] + dj[2] * dj[2]);
    double u[3] = {dj[0] / dist, dj[1] / dist, dj[2] / dist};
    double *e = col->e;
    e[0] = -u[0], e[1] = -u[1], e[2] = -u[2];
    double Bc[3], rc[3], rp[3] = {row[J_BRP], row[J_BRP + 1], row[J_BRP + 2]};
    double vp[3] = {0.0, 0.0, 0.0};
    to_body(Rc, e, Bc);
    col->child6[0] = e[0], col->child6[1] = e[1], col->child6[2] = e[2];
    mb_cross(row + J_BRC, Bc, col->child6 + 3);
    for (int a = 0; a < 3; a++)
        rc[a] = Rc[3 * a] * row[J_BRC] + Rc[3 * a + 1] * row[J_BRC + 1] + Rc[3 * a + 2] * row[J_BRC + 2];
    if (p >= 0) {
        const double *Rp = js->Rp;
        double Bp[3], mp[3];
        to_body(Rp, e, Bp);
        mb_cross(row + J_BRP, Bp, mp);
        col->parent6[3] = -mp[0], col->parent6[4] = -mp[1], col->parent6[5] = -mp[2];
        for (int a = 0; a < 3; a++)
            rp[a] = Rp[3 * a] * row[J_BRP] + Rp[3 * a + 1] * row[J_BRP + 1] + Rp[3 * a + 2] * row[J_BRP + 2];
        vp[0] = v[3 * p], vp[1] = v[3 * p + 1], vp[2] = v[3 * p + 2];
    } else {
        col->parent6[3] = col->parent6[4] = col->parent6[5] = 0.0;
        rp[0] = rp[1] = rp[2] = 0.0; /* ground: P_p is a world point at rest, w_p = 0 */
    }
    double k[3], f[3], dd[3], a[3], b[3];
    mb_cross(js->wc, rc, k);
    mb_cross(js->wp, rp, f);
    for (int r = 0; r < 3; r++) dd[r] = v[3 * c + r] + k[r] - vp[r] - f[r];
    mb_cross(js->wc, k, a);
    mb_cross(js->wp, f, b);
    double ud = u[0] * dd[0] + u[1] * dd[1] + u[2] * dd[2];
    col->gamma = (u[0] * (a[0] - b[0]) + u[1] * (a[1] - b[1]) + u[2] * (a[2] - b[2]) +
                  (dd[0] * dd[0] + dd[1] * dd[1] + dd[2] * dd[2] - ud * ud) / dist);
    col->phi = row[J_LLEN] - dist;
}

/* MB_KIND_TURN: a moment about the frame's axis, phi = the relative turn about it
 * (+ off - f, wrapped to (-pi, pi]). */
static void turn(const joint_state *js, int64_t axis, double off, double f, column *col) {
    double Bp[3];
    frame_axis(js, axis, col->e, Bp);
    moment_column(js, Bp, col);
    col->gamma = moment_gamma(js, col->e);
    col->phi = wrap(turn_angle(js, axis) + off - f);
}

/* MB_KIND_SCREW: the FORCE column minus h times the moment column about e;
 * phi = e . d + off - h theta~, theta~ the turn on the branch nearest (e . d + off) / h. */
static void screw(const joint_state *js, int64_t axis, double off, double h, column *col) {
    double Bp[3], Bc[3];
    force(js, axis, col);
    double gamma_force = col->gamma, along = col->phi + off;
    frame_axis(js, axis, col->e, Bp);
    to_body(js->Rc, col->e, Bc);
    for (int a = 0; a < 3; a++) {
        col->child6[3 + a] -= h * Bc[a];
        col->parent6[3 + a] += h * Bp[a];
    }
    col->gamma = gamma_force - h * moment_gamma(js, col->e);
    double theta = turn_angle(js, axis);
    if (h != 0.0) theta += TWO_PI * round((along / h - theta) / TWO_PI);
    col->phi = along - h * theta;
}

void mb_columns_at(const mb_model *md, mb_work *w, const double *y, int laws,
                   double *child6, double *parent6, double *W_e, double *W_P,
                   double *gamma, double *phi, double *gtv) {
    int64_t n = md->n;
    const double *v = y + 7 * n, *om = y + 10 * n;
    for (int64_t j = 0; j < md->nj; j++) joint_geometry(md, w, y, j);
    joint_state js;
    for (int64_t i = 0; i < md->m; i++) {
        int64_t j, kind, axis;
        double off, h, f[3];
        int driven = component(md, w, i, laws, &j, &kind, &axis, &off, &h, f);
        load_joint(md, w, j, &js);
        column col = {child6 + 6 * i, parent6 + 6 * i, 0.0, 0.0, {0.0, 0.0, 0.0}};
        switch (kind) {
        case MB_KIND_FORCE:
            force(&js, axis, &col);
            if (off != 0.0) col.phi += off;
            break;
        case MB_KIND_TILT: tilt(&js, axis, 0, &col); break;
        case MB_KIND_LOCK: tilt(&js, axis, 1, &col); break;
        case MB_KIND_RIGHT_ANGLE: right_angle(&js, &col); break;
        case MB_KIND_LINK: link(md, y, &js, &col); break;
        case MB_KIND_TURN: turn(&js, axis, off, f[0], &col); break;
        default: screw(&js, axis, off, h, &col); break;
        }
        if (driven && kind != MB_KIND_TURN) col.phi -= f[0]; /* TURN: inside its wrap */
        double *c6 = col.child6, *p6 = col.parent6;
        p6[0] = -c6[0], p6[1] = -c6[1], p6[2] = -c6[2];
        if (md->joints_i[3 * j + 2] & MB_J_PARTICLE_PARENT) /* forces act at the particle */
            p6[3] = p6[4] = p6[5] = 0.0;
        double s = column_dot_v(c6, p6, js.c, js.p, v, om);
        if (js.p < 0)
            for (int a = 0; a < 6; a++) p6[a] = 0.0;
        gamma[i] = driven ? col.gamma + f[2] : col.gamma;
        phi[i] = col.phi;
        gtv[i] = driven ? s - f[1] : s;
        if (W_e != NULL)
            for (int a = 0; a < 3; a++) W_e[3 * i + a] = col.e[a];
        if (W_P != NULL)
            for (int a = 0; a < 3; a++) W_P[3 * i + a] = js.P[a];
    }
}

void mb_gammas_at(const mb_model *md, mb_work *w, const double *y, int laws,
                  const double *child6, const double *parent6, double *gamma, double *gtv) {
    int64_t n = md->n;
    const double *v = y + 7 * n, *om = y + 10 * n;
    for (int64_t j = 0; j < md->nj; j++) joint_velocities(md, w, y, j);
    joint_state js;
    for (int64_t i = 0; i < md->m; i++) {
        int64_t j, kind, axis;
        double off, h, f[3];
        int driven = component(md, w, i, laws, &j, &kind, &axis, &off, &h, f);
        load_joint(md, w, j, &js);
        double e[3], Bp[3], g;
        switch (kind) { /* each kind's gamma as its column function writes it */
        case MB_KIND_FORCE:
            frame_axis(&js, axis, e, Bp);
            g = force_gamma(&js, e);
            break;
        case MB_KIND_TILT:
        case MB_KIND_LOCK:
        case MB_KIND_TURN:
            frame_axis(&js, axis, e, Bp);
            g = moment_gamma(&js, e);
            break;
        case MB_KIND_RIGHT_ANGLE:
        case MB_KIND_LINK: { /* their gammas need the whole column's geometry */
            double c6[6], p6[6];
            column col = {c6, p6, 0.0, 0.0, {0.0, 0.0, 0.0}};
            if (kind == MB_KIND_LINK) link(md, y, &js, &col);
            else right_angle(&js, &col);
            g = col.gamma;
            break;
        }
        default: /* SCREW: the FORCE gamma less h times the moment's */
            frame_axis(&js, axis, e, Bp);
            g = force_gamma(&js, e) - h * moment_gamma(&js, e);
            break;
        }
        (void)off;
        double s = column_dot_v(child6 + 6 * i, parent6 + 6 * i, js.c, js.p, v, om);
        gamma[i] = driven ? g + f[2] : g;
        gtv[i] = driven ? s - f[1] : s;
    }
}

void mb_columns(const mb_model *md, mb_work *w, double t, const double *y, double *child6,
                double *parent6, double *W_e, double *W_P, double *gamma, double *phi,
                double *gtv) {
    mb_rotations(md->n, y + 3 * md->n, w->R);
    mb_eval_all(md, w, t);
    mb_columns_at(md, w, y, 1, child6, parent6, W_e, W_P, gamma, phi, gtv);
}
