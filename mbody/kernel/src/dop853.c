/* DOP853 (dop853.h): Dormand and Prince's 8(5,3) pair with step-size control and dense
 * output, from Hairer, Norsett and Wanner (the coefficients: their dop853.f, HNW I
 * section II.10; the control and the initial step: section II.4). */
#include "dop853.h"

#include <math.h>
#include <string.h>

/* ---------------------------------------------------------------------------------------
 * The tableau. Stages are numbered from 0 here: stage s is HNW's k_{s+1}; stage 12 is
 * f(t + h, y_new) (HNW's k_13, the first stage of the next step, which the error
 * estimators and the dense output use), stages 13 .. 15 the dense output's extra stages.
 * ------------------------------------------------------------------------------------- */
enum { STAGES = 12, EXTENDED = 16, DENSE_ROWS = 7 };

static const double C[EXTENDED] = {
    0.0,
    0.526001519587677318785587544488e-01,
    0.789002279381515978178381316732e-01,
    0.118350341907227396726757197510e+00,
    0.281649658092772603273242802490e+00,
    0.333333333333333333333333333333e+00,
    0.25e+00,
    0.307692307692307692307692307692e+00,
    0.651282051282051282051282051282e+00,
    0.6e+00,
    0.857142857142857142857142857142e+00,
    1.0,
    1.0,
    0.1e+00,
    0.2e+00,
    0.777777777777777777777777777778e+00,
};

static const double A[EXTENDED][EXTENDED] = {
    [1] = {5.26001519587677318785587544488e-2},
    [2] = {1.97250569845378994544595329183e-2, 5.91751709536136983633785987549e-2},
    [3] = {2.95875854768068491816892993775e-2, 0.0, 8.87627564304205475450678981324e-2},
    [4] = {2.41365134159266685502369798665e-1, 0.0, -8.84549479328286085344864962717e-1,
           9.24834003261792003115737966543e-1},
    [5] = {3.7037037037037037037037037037e-2, 0.0, 0.0, 1.70828608729473871279604482173e-1,
           1.25467687566822425016691814123e-1},
    [6] = {3.7109375e-2, 0.0, 0.0, 1.70252211019544039314978060272e-1,
           6.02165389804559606850219397283e-2, -1.7578125e-2},
    [7] = {3.70920001185047927108779319836e-2, 0.0, 0.0, 1.70383925712239993810214054705e-1,
           1.07262030446373284651809199168e-1, -1.53194377486244017527936158236e-2,
           8.27378916381402288758473766002e-3},
    [8] = {6.24110958716075717114429577812e-1, 0.0, 0.0, -3.36089262944694129406857109825e0,
           -8.68219346841726006818189891453e-1, 2.75920996994467083049415600797e1,
           2.01540675504778934086186788979e1, -4.34898841810699588477366255144e1},
    [9] = {4.77662536438264365890433908527e-1, 0.0, 0.0, -2.48811461997166764192642586468e0,
           -5.90290826836842996371446475743e-1, 2.12300514481811942347288949897e1,
           1.52792336328824235832596922938e1, -3.32882109689848629194453265587e1,
           -2.03312017085086261358222928593e-2},
    [10] = {-9.3714243008598732571704021658e-1, 0.0, 0.0, 5.18637242884406370830023853209e0,
            1.09143734899672957818500254654e0, -8.14978701074692612513997267357e0,
            -1.85200656599969598641566180701e1, 2.27394870993505042818970056734e1,
            2.49360555267965238987089396762e0, -3.0467644718982195003823669022e0},
    [11] = {2.27331014751653820792359768449e0, 0.0, 0.0, -1.05344954667372501984066689879e1,
            -2.00087205822486249909675718444e0, -1.79589318631187989172765950534e1,
            2.79488845294199600508499808837e1, -2.85899827713502369474065508674e0,
            -8.87285693353062954433549289258e0, 1.23605671757943030647266201528e1,
            6.43392746015763530355970484046e-1},
    /* [12]: y_new, by the weights B below */
    [13] = {[0] = 5.61675022830479523392909219681e-2, [6] = 2.53500210216624811088794765333e-1,
            [7] = -2.46239037470802489917441475441e-1, [8] = -1.24191423263816360469010140626e-1,
            [9] = 1.5329179827876569731206322685e-1, [10] = 8.20105229563468988491666602057e-3,
            [11] = 7.56789766054569976138603589584e-3, [12] = -8.298e-3},
    [14] = {[0] = 3.18346481635021405060768473261e-2, [5] = 2.83009096723667755288322961402e-2,
            [6] = 5.35419883074385676223797384372e-2, [7] = -5.49237485713909884646569340306e-2,
            [10] = -1.08347328697249322858509316994e-4, [11] = 3.82571090835658412954920192323e-4,
            [12] = -3.40465008687404560802977114492e-4, [13] = 1.41312443674632500278074618366e-1},
    [15] = {[0] = -4.28896301583791923408573538692e-1, [5] = -4.69762141536116384314449447206e0,
            [6] = 7.68342119606259904184240953878e0, [7] = 4.06898981839711007970213554331e0,
            [8] = 3.56727187455281109270669543021e-1, [12] = -1.39902416515901462129418009734e-3,
            [13] = 2.9475147891527723389556272149e0, [14] = -9.15095847217987001081870187138e0},
};

/* The weights of order 8 (b_1, b_6 .. b_12) and the third-order estimator's (bhh). */
#define B0 5.42937341165687622380535766363e-2
#define B5 4.45031289275240888144113950566e0
#define B6 1.89151789931450038304281599044e0
#define B7 -5.8012039600105847814672114227e0
#define B8 3.1116436695781989440891606237e-1
#define B9 -1.52160949662516078556178806805e-1
#define B10 2.01365400804030348374776537501e-1
#define B11 4.47106157277725905176885569043e-2
#define BHH0 0.244094488188976377952755905512e+00
#define BHH8 0.733846688281611857341361741547e+00
#define BHH11 0.220588235294117647058823529412e-01

static const double B[STAGES] = {B0, 0.0, 0.0, 0.0, 0.0, B5, B6, B7, B8, B9, B10, B11};

/* The error estimators over stages 0 .. 12: e5 = sum er_s k_s (order 5), e3 = y_new's
 * weights minus bhh (order 3). */
static const double E5[STAGES + 1] = {
    0.1312004499419488073250102996e-01, 0.0, 0.0, 0.0, 0.0,
    -0.1225156446376204440720569753e+01, -0.4957589496572501915214079952e+00,
    0.1664377182454986536961530415e+01, -0.3503288487499736816886487290e+00,
    0.3341791187130174790297318841e+00, 0.8192320648511571246570742613e-01,
    -0.2235530786388629525884427845e-01, 0.0};
static const double E3[STAGES + 1] = {B0 - BHH0, 0.0, 0.0, 0.0, 0.0, B5, B6, B7, B8 - BHH8,
                                      B9, B10, B11 - BHH11, 0.0};

/* The dense output's coefficients d_4 .. d_7 over stages 0 .. 15. */
static const double D[4][EXTENDED] = {
    {-0.84289382761090128651353491142e+01, 0.0, 0.0, 0.0, 0.0,
     0.56671495351937776962531783590e+00, -0.30689499459498916912797304727e+01,
     0.23846676565120698287728149680e+01, 0.21170345824450282767155149946e+01,
     -0.87139158377797299206789907490e+00, 0.22404374302607882758541771650e+01,
     0.63157877876946881815570249290e+00, -0.88990336451333310820698117400e-01,
     0.18148505520854727256656404962e+02, -0.91946323924783554000451984436e+01,
     -0.44360363875948939664310572000e+01},
    {0.10427508642579134603413151009e+02, 0.0, 0.0, 0.0, 0.0,
     0.24228349177525818288430175319e+03, 0.16520045171727028198505394887e+03,
     -0.37454675472269020279518312152e+03, -0.22113666853125306036270938578e+02,
     0.77334326684722638389603898808e+01, -0.30674084731089398182061213626e+02,
     -0.93321305264302278729567221706e+01, 0.15697238121770843886131091075e+02,
     -0.31139403219565177677282850411e+02, -0.93529243588444783865713862664e+01,
     0.35816841486394083752465898540e+02},
    {0.19985053242002433820987653617e+02, 0.0, 0.0, 0.0, 0.0,
     -0.38703730874935176555105901742e+03, -0.18917813819516756882830838328e+03,
     0.52780815920542364900561016686e+03, -0.11573902539959630126141871134e+02,
     0.68812326946963000169666922661e+01, -0.10006050966910838403183860980e+01,
     0.77771377980534432092869265740e+00, -0.27782057523535084065932004339e+01,
     -0.60196695231264120758267380846e+02, 0.84320405506677161018159903784e+02,
     0.11992291136182789328035130030e+02},
    {-0.25693933462703749003312586129e+02, 0.0, 0.0, 0.0, 0.0,
     -0.15418974869023643374053993627e+03, -0.23152937917604549567536039109e+03,
     0.35763911791061412378285349910e+03, 0.93405324183624310003907691704e+02,
     -0.37458323136451633156875139351e+02, 0.10409964950896230045147246184e+03,
     0.29840293426660503123344363579e+02, -0.43533456590011143754432175058e+02,
     0.96324553959188282948394950600e+02, -0.39177261675615439165231486172e+02,
     -0.14972683625798562581422125276e+03},
};

void mb_dop853_tableau(double *c, double *a, double *b, double *e5, double *e3, double *d) {
    memcpy(c, C, sizeof(C));
    memcpy(a, A, sizeof(A));
    memcpy(b, B, sizeof(B));
    memcpy(e5, E5, sizeof(E5));
    memcpy(e3, E3, sizeof(E3));
    memcpy(d, D, sizeof(D));
}

/* ------------------------------------------------------------------------------------- */

int64_t mb_dop853_work_size(int64_t n) { return MB_DOP_W_ROWS * n; }

void mb_dop853_settings(double *state, double rtol, double atol, double max_step,
                        double t_bound) {
    state[MB_DOP_RTOL] = rtol;
    state[MB_DOP_ATOL] = atol;
    state[MB_DOP_MAX_STEP] = max_step;
    state[MB_DOP_T_BOUND] = t_bound;
    state[MB_DOP_SAFETY] = 0.9;
    state[MB_DOP_FAC_MIN] = 0.2;
    state[MB_DOP_FAC_MAX] = 10.0;
    state[MB_DOP_REFRESH] = 0.0;
    state[MB_DOP_FILTER_NEXT] = 0.0;
}

static double atol_at(const mb_ode *p, const double *state, int64_t i) {
    return p->atol != NULL ? p->atol[i] : state[MB_DOP_ATOL];
}

/* Stops the run with a callback's code. */
static int stopped(double *state, int code) {
    state[MB_DOP_STATUS] = MB_DOP_STOPPED;
    state[MB_DOP_CODE] = code;
    return MB_DOP_STOPPED;
}

/* f(t, y) into out; in a filtered step at the stage callback's projection of a copy of
 * y (in the scratch row S). Counted in state[MB_DOP_NFEV]. */
static int evaluate(const mb_ode *p, int filtered, double t, const double *y, double *out,
                    double *work, double *state) {
    if (filtered && p->stage != NULL) {
        double *s = work + MB_DOP_W_S * p->n;
        memcpy(s, y, (size_t)p->n * sizeof(double));
        int code = p->stage(p->ctx, t, s);
        if (code) return code;
        y = s;
    }
    state[MB_DOP_NFEV] += 1.0;
    return p->rhs(p->ctx, t, y, out);
}

/* z <- base + (sum_j a_j k_j) h over the stages j < s with a_j != 0: the sum taken in the
 * order of j, from 0 (as a plain loop over all j would, the zeros adding nothing). */
static void combine(int64_t n, const double *base, const double *K, const double *a, int s,
                    double h, double *z) {
    for (int64_t i = 0; i < n; i++) z[i] = 0.0;
    for (int j = 0; j < s; j++) {
        const double aj = a[j];
        if (aj == 0.0) continue;
        const double *k = K + j * n;
        for (int64_t i = 0; i < n; i++) z[i] += k[i] * aj;
    }
    for (int64_t i = 0; i < n; i++) z[i] = base[i] + z[i] * h;
}

/* sqrt(sum_i (x_i / sc_i)^2 / n), sc_i = atol_i + rtol |y_i|: HNW's norm (II.4). */
static double rms(const mb_ode *p, const double *state, const double *x, const double *y) {
    const double rtol = state[MB_DOP_RTOL];
    double acc = 0.0;
    for (int64_t i = 0; i < p->n; i++) {
        const double r = x[i] / (atol_at(p, state, i) + fabs(y[i]) * rtol);
        acc += r * r;
    }
    return sqrt(acc) / sqrt((double)p->n);
}

/* HNW's initial step (II.4): h0 from |y0| and |f0|, one explicit Euler step to estimate
 * the second derivative, then h1 such that h1^8 max(|f0|, |y''|) = 0.01; both bounded by
 * the interval (the Euler step stays inside it) and by max_step. */
static int initial_step(const mb_ode *p, double t0, double *state, double *work,
                        double *h) {
    const int64_t n = p->n;
    const double direction = state[MB_DOP_DIRECTION];
    const double interval = fabs(state[MB_DOP_T_BOUND] - t0);
    const double *y0 = work + MB_DOP_W_Y * n, *f0 = work + MB_DOP_W_F * n;
    double *y1 = work + MB_DOP_W_Z * n, *f1 = work + MB_DOP_W_K * n + n, *d = y1;
    if (n == 0) {
        *h = INFINITY;
        return 0;
    }
    if (interval == 0.0) {
        *h = 0.0;
        return 0;
    }
    const double d0 = rms(p, state, y0, y0), d1 = rms(p, state, f0, y0);
    double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    if (h0 > interval) h0 = interval;
    for (int64_t i = 0; i < n; i++) y1[i] = y0[i] + h0 * direction * f0[i];
    int code = evaluate(p, state[MB_DOP_FILTER_NEXT] != 0.0, t0 + h0 * direction, y1, f1,
                        work, state);
    if (code) return code;
    for (int64_t i = 0; i < n; i++) d[i] = f1[i] - f0[i];
    const double d2 = rms(p, state, d, y0) / h0;
    const double big = d1 > d2 ? d1 : d2;
    double h1;
    if (d1 <= 1e-15 && d2 <= 1e-15) {
        h1 = h0 * 1e-3 > 1e-6 ? h0 * 1e-3 : 1e-6;
    } else {
        h1 = pow(0.01 / big, 1.0 / 8.0);
    }
    double out = 100.0 * h0;
    if (h1 < out) out = h1;
    if (interval < out) out = interval;
    if (state[MB_DOP_MAX_STEP] < out) out = state[MB_DOP_MAX_STEP];
    *h = out;
    return 0;
}

int mb_dop853_start(const mb_ode *p, double t0, const double *y0, double first_step,
                    double *state, double *work) {
    const int64_t n = p->n;
    const double t_bound = state[MB_DOP_T_BOUND];
    state[MB_DOP_T] = t0;
    state[MB_DOP_DIRECTION] = t_bound >= t0 ? 1.0 : -1.0;
    state[MB_DOP_T_OLD] = t0;
    state[MB_DOP_H_OLD] = 0.0;
    state[MB_DOP_STATUS] = MB_DOP_RUNNING;
    state[MB_DOP_CODE] = 0.0;
    state[MB_DOP_STEPS] = state[MB_DOP_REJECTED] = state[MB_DOP_NFEV] = 0.0;
    state[MB_DOP_REFRESHED] = 0.0;
    state[MB_DOP_FILTER] = state[MB_DOP_FILTER_NEXT];
    state[MB_DOP_DENSE] = 0.0;
    state[MB_DOP_DENSE_NFEV] = 0.0;
    for (int i = 0; i < MB_DOP_PROJECT_INFO; i++) state[MB_DOP_INFO + i] = 0.0;
    memcpy(work + MB_DOP_W_Y * n, y0, (size_t)n * sizeof(double));
    int code = evaluate(p, state[MB_DOP_FILTER_NEXT] != 0.0, t0, work + MB_DOP_W_Y * n,
                        work + MB_DOP_W_F * n, work, state);
    if (code) return stopped(state, code);
    double h = first_step;
    if (!(first_step > 0.0)) {
        code = initial_step(p, t0, state, work, &h);
        if (code) return stopped(state, code);
    }
    state[MB_DOP_H] = h;
    return MB_DOP_RUNNING;
}

/* One attempt from (t, y, f) with the (signed) step h: stages 0 .. 12 into K, the
 * solution into y_new, the error norm into *err. Returns 0 or a callback's code. */
static int attempt(const mb_ode *p, int filtered, double t, double h, double *state,
                   double *work, double *err) {
    const int64_t n = p->n;
    const double *y = work + MB_DOP_W_Y * n;
    double *K = work + MB_DOP_W_K * n, *y_new = work + MB_DOP_W_Y_NEW * n;
    double *z = work + MB_DOP_W_Z * n;
    double *e5 = work + MB_DOP_W_E5 * n, *e3 = work + MB_DOP_W_E3 * n;
    memcpy(K, work + MB_DOP_W_F * n, (size_t)n * sizeof(double));
    int code;
    for (int s = 1; s < STAGES; s++) {
        combine(n, y, K, A[s], s, h, z);
        code = evaluate(p, filtered, t + C[s] * h, z, K + s * n, work, state);
        if (code) return code;
    }
    combine(n, y, K, B, STAGES, h, y_new);
    code = evaluate(p, filtered, t + h, y_new, K + STAGES * n, work, state);
    if (code) return code;
    /* the two estimates (HNW's err and err2), each sum in the order of the stages */
    for (int64_t i = 0; i < n; i++) e5[i] = e3[i] = 0.0;
    for (int j = 0; j <= STAGES; j++) {
        const double a5 = E5[j], a3 = E3[j];
        const double *k = K + j * n;
        if (a5 != 0.0)
            for (int64_t i = 0; i < n; i++) e5[i] += k[i] * a5;
        if (a3 != 0.0)
            for (int64_t i = 0; i < n; i++) e3[i] += k[i] * a3;
    }
    if (filtered && p->tangent != NULL) {
        if ((code = p->tangent(p->ctx, t, y, e5))) return code;
        if ((code = p->tangent(p->ctx, t, y, e3))) return code;
    }
    const double rtol = state[MB_DOP_RTOL];
    double n5 = 0.0, n3 = 0.0;
    for (int64_t i = 0; i < n; i++) {
        const double a = fabs(y[i]), b = fabs(y_new[i]);
        const double sc = atol_at(p, state, i) + (b > a ? b : a) * rtol;
        const double r5 = e5[i] / sc, r3 = e3[i] / sc;
        n5 += r5 * r5;
        n3 += r3 * r3;
    }
    *err = (n5 == 0.0 && n3 == 0.0) ? 0.0 : fabs(h) * n5 / sqrt((n5 + 0.01 * n3) * (double)n);
    return 0;
}

int mb_dop853_run(const mb_ode *p, double t_stop, int64_t max_steps, double *state,
                  double *work) {
    const int64_t n = p->n;
    const double exponent = -1.0 / 8.0; /* the error estimate is of order 7: err ~ h^8 */
    const double safety = state[MB_DOP_SAFETY], fac_min = state[MB_DOP_FAC_MIN];
    const double fac_max = state[MB_DOP_FAC_MAX], max_step = state[MB_DOP_MAX_STEP];
    const double t_bound = state[MB_DOP_T_BOUND], direction = state[MB_DOP_DIRECTION];
    double *y = work + MB_DOP_W_Y * n, *f = work + MB_DOP_W_F * n;
    double *y_old = work + MB_DOP_W_Y_OLD * n, *y_new = work + MB_DOP_W_Y_NEW * n;
    const double *f_new = work + (MB_DOP_W_K + STAGES) * n;
    double t = state[MB_DOP_T], h_abs = state[MB_DOP_H];
    if (state[MB_DOP_STATUS] != MB_DOP_RUNNING) return (int)state[MB_DOP_STATUS];
    if (n == 0 || t == t_bound) { /* nothing to integrate: the run is over */
        state[MB_DOP_T_OLD] = t;
        state[MB_DOP_T] = t_bound;
        state[MB_DOP_STATUS] = MB_DOP_FINISHED;
        return MB_DOP_FINISHED;
    }
    double refresh_tol = INFINITY; /* refresh * the smallest atol */
    if (p->project != NULL) {
        refresh_tol = state[MB_DOP_ATOL];
        if (p->atol != NULL)
            for (int64_t i = 0; i < n; i++)
                if (i == 0 || p->atol[i] < refresh_tol) refresh_tol = p->atol[i];
        refresh_tol *= state[MB_DOP_REFRESH];
    }
    for (int64_t taken = 0; taken < max_steps; taken++) {
        const int filtered = state[MB_DOP_FILTER_NEXT] != 0.0;
        const double min_step = 10.0 * fabs(nextafter(t, direction * INFINITY) - t);
        if (h_abs > max_step) {
            h_abs = max_step;
        } else if (h_abs < min_step) {
            h_abs = min_step;
        }
        int rejected = 0;
        double h, t_new;
        for (;;) {
            if (!(h_abs >= min_step)) { /* NaN too: a state or f no longer finite */
                state[MB_DOP_T] = t;
                state[MB_DOP_H] = h_abs;
                state[MB_DOP_STATUS] = MB_DOP_TOO_SMALL;
                return MB_DOP_TOO_SMALL;
            }
            h = h_abs * direction;
            t_new = t + h;
            if (direction * (t_new - t_bound) > 0.0) t_new = t_bound;
            h = t_new - t;
            h_abs = fabs(h);
            double err;
            int code = attempt(p, filtered, t, h, state, work, &err);
            if (code) {
                state[MB_DOP_T] = t;
                state[MB_DOP_H] = h_abs;
                return stopped(state, code);
            }
            if (err < 1.0) {
                double factor = fac_max;
                if (err != 0.0) {
                    const double grow = safety * pow(err, exponent);
                    if (grow < factor) factor = grow;
                }
                if (rejected && factor > 1.0) factor = 1.0;
                h_abs *= factor;
                break;
            }
            const double shrink = safety * pow(err, exponent);
            h_abs *= shrink > fac_min ? shrink : fac_min; /* NaN: fac_min */
            rejected = 1;
            state[MB_DOP_REJECTED] += 1.0;
        }
        memcpy(y_old, y, (size_t)n * sizeof(double));
        memcpy(y, y_new, (size_t)n * sizeof(double));
        memcpy(f, f_new, (size_t)n * sizeof(double));
        state[MB_DOP_T_OLD] = t;
        state[MB_DOP_H_OLD] = h;
        t = t_new;
        state[MB_DOP_T] = t;
        state[MB_DOP_H] = h_abs;
        state[MB_DOP_STEPS] += 1.0;
        state[MB_DOP_FILTER] = filtered;
        state[MB_DOP_DENSE] = 0.0;
        if (p->project != NULL) {
            double *info = state + MB_DOP_INFO;
            int code = p->project(p->ctx, t, y, info);
            if (code) return stopped(state, code);
            if (filtered || info[0] > refresh_tol) {
                /* the next step starts from the derivative at the projected state */
                code = evaluate(p, filtered, t, y, f, work, state);
                if (code) return stopped(state, code);
                state[MB_DOP_REFRESHED] += 1.0;
            }
            state[MB_DOP_FILTER_NEXT] = info[1] != 0.0;
        }
        if (direction * (t - t_bound) >= 0.0) {
            state[MB_DOP_STATUS] = MB_DOP_FINISHED;
            return MB_DOP_FINISHED;
        }
        if (direction * (t - t_stop) >= 0.0) break;
    }
    return MB_DOP_RUNNING;
}

int mb_dop853_dense(const mb_ode *p, const double *t, int64_t m, double *out,
                    double *state, double *work) {
    const int64_t n = p->n;
    if (state[MB_DOP_STEPS] == 0.0) return -1;
    const double t_old = state[MB_DOP_T_OLD], h = state[MB_DOP_H_OLD];
    const double *y = work + MB_DOP_W_Y * n, *f = work + MB_DOP_W_F * n;
    const double *y_old = work + MB_DOP_W_Y_OLD * n;
    double *K = work + MB_DOP_W_K * n, *R = work + MB_DOP_W_DENSE * n;
    if (state[MB_DOP_DENSE] == 0.0) {
        const int filtered = state[MB_DOP_FILTER] != 0.0;
        double *z = work + MB_DOP_W_Z * n;
        for (int s = STAGES + 1; s < EXTENDED; s++) {
            combine(n, y_old, K, A[s], s, h, z);
            int code = evaluate(p, filtered, t_old + C[s] * h, z, K + s * n, work, state);
            if (code) return stopped(state, code);
            state[MB_DOP_DENSE_NFEV] += 1.0;
        }
        /* HNW's continuous extension: rows 0 .. 2 from y_old, y and the slopes at both
         * ends (f: at the step's end, as the next step starts), rows 3 .. 6 h sum d k. */
        double *r0 = R, *r1 = R + n, *r2 = R + 2 * n;
        for (int64_t i = 0; i < n; i++) {
            const double delta = y[i] - y_old[i];
            const double bspl = h * K[i] - delta;
            r0[i] = delta;
            r1[i] = bspl;
            r2[i] = delta - h * f[i] - bspl;
        }
        for (int r = 0; r < 4; r++) {
            double *row = R + (3 + r) * n;
            for (int64_t i = 0; i < n; i++) row[i] = 0.0;
            for (int j = 0; j < EXTENDED; j++) {
                const double dj = D[r][j];
                if (dj == 0.0) continue;
                const double *k = K + j * n;
                for (int64_t i = 0; i < n; i++) row[i] += k[i] * dj;
            }
            for (int64_t i = 0; i < n; i++) row[i] *= h;
        }
        state[MB_DOP_DENSE] = 1.0;
    }
    for (int64_t k = 0; k < m; k++) {
        const double s = (t[k] - t_old) / h, s1 = 1.0 - s;
        double *o = out + k * n;
        for (int64_t i = 0; i < n; i++) {
            const double inner = R[3 * n + i] + s * (R[4 * n + i]
                                 + s1 * (R[5 * n + i] + s * R[6 * n + i]));
            o[i] = y_old[i] + s * (R[i] + s1 * (R[n + i] + s * (R[2 * n + i] + s1 * inner)));
        }
    }
    return 0;
}

int mb_dop853_sampled(const mb_ode *p, double t_stop, int64_t max_steps, const double *t_eval,
                      int64_t m, int64_t *k, double *out, int project_samples, double *state,
                      double *work, double *marks, int64_t marks_cap, int64_t *count) {
    const int64_t n = p->n;
    const double direction = state[MB_DOP_DIRECTION], width = state[MB_DOP_MARK_WIDTH];
    const int marking = marks != NULL && width > 0.0 && marks_cap > 0;
    int status = (int)state[MB_DOP_STATUS];
    if (marking && *count >= marks_cap) return status;
    const double return_after = state[MB_DOP_RETURN_AFTER];
    const int timed = p->clock != NULL && return_after > 0.0;
    const double deadline = timed ? p->clock() + return_after : 0.0;
    for (int64_t taken = 0; taken < max_steps && status == MB_DOP_RUNNING; taken++) {
        const double before = state[MB_DOP_STEPS];
        status = mb_dop853_run(p, t_stop, 1, state, work);
        if (state[MB_DOP_STEPS] == before && status != MB_DOP_FINISHED) break; /* failed */
        const double t = state[MB_DOP_T];
        int64_t j = *k;
        while (j < m && direction * (t_eval[j] - t) <= 0.0) j++;
        if (j > *k && n > 0) {
            int code = mb_dop853_dense(p, t_eval + *k, j - *k, out + *k * n, state, work);
            if (code) return code;
            if (project_samples && p->project != NULL)
                for (int64_t i = *k; i < j; i++) {
                    double info[MB_DOP_PROJECT_INFO];
                    code = p->project(p->ctx, t_eval[i], out + i * n, info);
                    if (code) return stopped(state, code);
                }
        }
        *k = j;
        if (marking && !(t < state[MB_DOP_MARK_NEXT] && t < state[MB_DOP_T_BOUND])) {
            marks[2 * *count] = t;
            marks[2 * *count + 1] = state[MB_DOP_STEPS];
            ++*count;
            state[MB_DOP_MARK_NEXT] = (floor(t / width) + 1.0) * width;
            if (*count >= marks_cap) break;
        }
        if (status == MB_DOP_RUNNING && direction * (t - t_stop) >= 0.0) break;
        if (timed && p->clock() >= deadline) break;
    }
    return status;
}
