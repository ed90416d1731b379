/* The Python entry points of the DOP853 integrator (dop853.h), registered into
 * mbody.kernel._core by mb_dop853_register (called from PyInit__core in module.c).
 *
 * A problem is the tuple (rhs, params, project, stage, tangent, atol):
 *   rhs      an int, one of the built-in test systems below (SYSTEM_*), with its
 *            parameters `params` (a float64 buffer), or a callable rhs(t, y, ydot)
 *            writing y'(t, y) into ydot (y, ydot: memoryviews of float64), or a
 *            _core.Unknowns: the core's mechanism (mechanism.h: mb_derivative), with
 *            `params` = [MECH_PARAMS settings (MECH_*), lam (m)];
 *   project  None or project(t, y, info) (y, info writable; dop853.h's project), or
 *            True with a _core.Unknowns rhs: the core's projection (mechanism.h);
 *   stage    None or stage(t, y) (y writable), or True (the core's);
 *   tangent  None or tangent(t, y, e) (e writable), or True (the core's);
 *   atol     None or a float64 buffer of n absolute tolerances.
 * Python callables cost a few microseconds an evaluation: they are for tests and for
 * problems without a compiled right-hand side; a mechanism's run calls no Python at all.
 * state and work are float64 buffers of STATE_SIZE and work_size(n) (caller-owned: numpy
 * arrays).
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include <math.h>
#ifdef _WIN32
#include <windows.h>
#else
#include <time.h>
#endif

#include "dop853.h"
#include "mechanism.h"

/* A monotonic clock in seconds: what a sampled run reports as its integration time. */
static double now_seconds(void) {
#ifdef _WIN32
    LARGE_INTEGER count, frequency;
    QueryPerformanceCounter(&count);
    QueryPerformanceFrequency(&frequency);
    return (double)count.QuadPart / (double)frequency.QuadPart;
#else
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
#endif
}

/* The model, unknowns and scratch of a _core.Unknowns object: 1, or 0 when obj is not an
 * initialised one (module.c). */
int mb_unknowns_object(PyObject *obj, const mb_model **md, const mb_unknowns **u,
                       mb_work **w);

/* ---------------------------------------------------------------------------------------
 * Built-in test systems (plain ODEs with known behaviour), written with the same
 * operations in the same order as their Python versions in tests/test_dop853.py, so that
 * both give the same numbers.
 * ------------------------------------------------------------------------------------- */
enum { SYSTEM_OSCILLATOR, SYSTEM_VAN_DER_POL, SYSTEM_ARENSTORF, SYSTEM_PENDULUM,
       SYSTEMS };
static const int64_t SYSTEM_SIZE[SYSTEMS] = {2, 2, 4, 2};
static const int64_t SYSTEM_PARAMS[SYSTEMS] = {1, 1, 1, 1};

/* x'' = -w^2 x: y = [x, x'], params [w (rad/s)]. */
static void oscillator(const double *k, const double *y, double *d) {
    d[0] = y[1];
    d[1] = -(k[0] * k[0]) * y[0];
}

/* x'' = mu (1 - x^2) x' - x: y = [x, x'], params [mu]. */
static void van_der_pol(const double *k, const double *y, double *d) {
    d[0] = y[1];
    d[1] = k[0] * (1.0 - y[0] * y[0]) * y[1] - y[0];
}

/* The restricted three-body problem in the rotating frame (HNW I, II.0, Arenstorf's
 * orbits): y = [x, y, x', y'], params [mu (mass ratio)]. */
static void arenstorf(const double *k, const double *y, double *d) {
    const double mu = k[0], nu = 1.0 - mu;
    const double a = y[0] + mu, b = y[0] - nu, y2 = y[1] * y[1];
    const double ra = a * a + y2, rb = b * b + y2;
    const double d1 = ra * sqrt(ra), d2 = rb * sqrt(rb);
    d[0] = y[2];
    d[1] = y[3];
    d[2] = y[0] + 2.0 * y[3] - nu * a / d1 - mu * b / d2;
    d[3] = y[1] - 2.0 * y[2] - nu * y[1] / d1 - mu * y[1] / d2;
}

/* theta'' = -(g/L) sin(theta): y = [theta, theta'], params [g/L (1/s^2)]. */
static void pendulum(const double *k, const double *y, double *d) {
    d[0] = y[1];
    d[1] = -k[0] * sin(y[0]);
}

typedef void (*system_fn)(const double *k, const double *y, double *d);
static const system_fn SYSTEM_FN[SYSTEMS] = {oscillator, van_der_pol, arenstorf, pendulum};

/* ---------------------------------------------------------------------------------------
 * A problem tuple held for one call.
 * ------------------------------------------------------------------------------------- */
enum { SYSTEM_PYTHON = -1, SYSTEM_MECHANISM = -2 };

typedef struct {
    int system;        /* SYSTEM_*, SYSTEM_PYTHON or SYSTEM_MECHANISM */
    const double *params;
    PyObject *rhs, *project, *stage, *tangent; /* borrowed */
    Py_buffer params_view, atol_view;
    int has_params, has_atol;
    int64_t n;
    mb_mechanism mech; /* SYSTEM_MECHANISM: the core's model, unknowns, scratch */
} problem;

enum { PY_ERROR = -1000 }; /* a callback's code: a Python exception is set */

static int system_rhs(void *ctx, double t, const double *y, double *ydot) {
    const problem *pr = ctx;
    SYSTEM_FN[pr->system](pr->params, y, ydot);
    return 0;
}

/* The core's mechanism (mechanism.h), its ctx inside the problem. */
static int mech_rhs(void *ctx, double t, const double *y, double *ydot) {
    return mb_mechanism_rhs(&((problem *)ctx)->mech, t, y, ydot);
}

static int mech_project(void *ctx, double t, double *y, double *info) {
    return mb_mechanism_project(&((problem *)ctx)->mech, t, y, info);
}

static int mech_stage(void *ctx, double t, double *y) {
    return mb_mechanism_stage(&((problem *)ctx)->mech, t, y);
}

static int mech_tangent(void *ctx, double t, const double *y, double *e) {
    return mb_mechanism_tangent(&((problem *)ctx)->mech, t, y, e);
}

static PyObject *view(double *x, int64_t n, int writable) {
    return PyMemoryView_FromMemory((char *)x, (Py_ssize_t)(n * (int64_t)sizeof(double)),
                                   writable ? PyBUF_WRITE : PyBUF_READ);
}

/* Calls fn(t, views...) and returns 0, or PY_ERROR with the exception set. */
static int call(PyObject *fn, double t, double *a, int wa, double *b, int wb, int64_t nb,
                int64_t n) {
    PyObject *va = view(a, n, wa), *vb = b != NULL ? view(b, nb, wb) : NULL;
    PyObject *tt = PyFloat_FromDouble(t);
    PyObject *res = NULL;
    if (va != NULL && tt != NULL && (b == NULL || vb != NULL))
        res = b != NULL ? PyObject_CallFunctionObjArgs(fn, tt, va, vb, NULL)
                        : PyObject_CallFunctionObjArgs(fn, tt, va, NULL);
    Py_XDECREF(va);
    Py_XDECREF(vb);
    Py_XDECREF(tt);
    if (res == NULL) return PY_ERROR;
    Py_DECREF(res);
    return 0;
}

static int python_rhs(void *ctx, double t, const double *y, double *ydot) {
    const problem *pr = ctx;
    return call(pr->rhs, t, (double *)y, 0, ydot, 1, pr->n, pr->n);
}

static int python_project(void *ctx, double t, double *y, double *info) {
    const problem *pr = ctx;
    return call(pr->project, t, y, 1, info, 1, MB_DOP_PROJECT_INFO, pr->n);
}

static int python_stage(void *ctx, double t, double *y) {
    const problem *pr = ctx;
    return call(pr->stage, t, y, 1, NULL, 0, 0, pr->n);
}

static int python_tangent(void *ctx, double t, const double *y, double *e) {
    const problem *pr = ctx;
    return call(pr->tangent, t, (double *)y, 0, e, 1, pr->n, pr->n);
}

/* A C-contiguous float64 buffer of exactly `size` doubles (size < 0: any size). */
static int get_doubles(PyObject *obj, Py_buffer *b, int writable, Py_ssize_t size,
                       const char *what) {
    int flags = PyBUF_C_CONTIGUOUS | PyBUF_FORMAT | (writable ? PyBUF_WRITABLE : 0);
    if (PyObject_GetBuffer(obj, b, flags) < 0) return -1;
    if (b->itemsize != 8 || b->format == NULL || strcmp(b->format, "d") != 0) {
        PyErr_Format(PyExc_TypeError, "%s: a float64 array is needed", what);
        PyBuffer_Release(b);
        return -1;
    }
    if (size >= 0 && b->len != size * 8) {
        PyErr_Format(PyExc_ValueError, "%s: %zd values expected, got %zd", what, size,
                     b->len / 8);
        PyBuffer_Release(b);
        return -1;
    }
    return 0;
}

static void problem_release(problem *pr) {
    if (pr->has_params) PyBuffer_Release(&pr->params_view);
    if (pr->has_atol) PyBuffer_Release(&pr->atol_view);
    pr->has_params = pr->has_atol = 0;
    PyMem_Free(pr->mech.scratch);
    pr->mech.scratch = NULL;
}

static int is_unknowns(PyObject *obj) {
    const mb_model *md;
    const mb_unknowns *u;
    mb_work *w;
    return mb_unknowns_object(obj, &md, &u, &w);
}

/* A mechanism's rhs: the Unknowns object's model, its params and lam; n checked. */
static int mechanism_read(PyObject *rhs, PyObject *params, int64_t n, problem *pr) {
    const mb_model *md;
    const mb_unknowns *u;
    mb_work *w;
    if (!mb_unknowns_object(rhs, &md, &u, &w)) {
        PyErr_SetString(PyExc_TypeError, "rhs: an initialised _core.Unknowns is needed");
        return -1;
    }
    if (MB_STATE_SIZE(md->n, md->planar) != n) {
        PyErr_Format(PyExc_ValueError, "the mechanism's state has %lld values, not %lld",
                     (long long)MB_STATE_SIZE(md->n, md->planar), (long long)n);
        return -1;
    }
    if (get_doubles(params, &pr->params_view, 0, MB_MECH_PARAMS + md->m, "params") < 0)
        return -1;
    pr->has_params = 1;
    pr->params = pr->params_view.buf;
    pr->mech.md = md;
    pr->mech.u = u;
    pr->mech.w = w;
    pr->mech.params = pr->params;
    pr->mech.lam = pr->params + MB_MECH_PARAMS;
    pr->mech.scratch = PyMem_Malloc((size_t)mb_mechanism_scratch(md) * sizeof(double) + 1);
    if (pr->mech.scratch == NULL) {
        PyErr_NoMemory();
        return -1;
    }
    pr->system = SYSTEM_MECHANISM;
    return 0;
}

/* A callback slot: None (none), True (the core's, for a mechanism) or a callable. */
static int callback_kind(PyObject *obj, const problem *pr, const char *what) {
    if (obj == Py_None) return 0;
    if (obj == Py_True) {
        if (pr->system != SYSTEM_MECHANISM) {
            PyErr_Format(PyExc_TypeError, "%s: True (the core's) needs a _core.Unknowns rhs",
                         what);
            return -1;
        }
        return 1;
    }
    if (!PyCallable_Check(obj)) {
        PyErr_Format(PyExc_TypeError, "%s: None, True or a callable", what);
        return -1;
    }
    return 2;
}

/* Reads the problem tuple into pr and ode; n: the size of y. */
static int problem_read(PyObject *tuple, int64_t n, problem *pr, mb_ode *ode) {
    PyObject *rhs, *params, *project, *stage, *tangent, *atol;
    memset(pr, 0, sizeof(*pr));
    memset(ode, 0, sizeof(*ode));
    if (!PyArg_ParseTuple(tuple, "OOOOOO", &rhs, &params, &project, &stage, &tangent,
                          &atol))
        return -1;
    pr->n = ode->n = n;
    ode->ctx = pr;
    ode->clock = now_seconds;
    if (PyLong_Check(rhs)) {
        long s = PyLong_AsLong(rhs);
        if (s < 0 || s >= SYSTEMS) {
            PyErr_Format(PyExc_ValueError, "no built-in system %ld", s);
            return -1;
        }
        if (SYSTEM_SIZE[s] != n) {
            PyErr_Format(PyExc_ValueError, "built-in system %ld has %lld states, not %lld",
                         s, (long long)SYSTEM_SIZE[s], (long long)n);
            return -1;
        }
        if (get_doubles(params, &pr->params_view, 0, SYSTEM_PARAMS[s], "params") < 0)
            return -1;
        pr->has_params = 1;
        pr->system = (int)s;
        pr->params = pr->params_view.buf;
        ode->rhs = system_rhs;
    } else if (PyCallable_Check(rhs)) {
        pr->system = SYSTEM_PYTHON;
        pr->rhs = rhs;
        ode->rhs = python_rhs;
    } else if (is_unknowns(rhs)) {
        if (mechanism_read(rhs, params, n, pr) < 0) {
            problem_release(pr);
            return -1;
        }
        ode->rhs = mech_rhs;
    } else {
        PyErr_SetString(PyExc_TypeError,
                        "rhs: a built-in system number, a callable or a _core.Unknowns");
        return -1;
    }
    int kp = callback_kind(project, pr, "project"), ks = callback_kind(stage, pr, "stage");
    int kt = callback_kind(tangent, pr, "tangent");
    if (kp < 0 || ks < 0 || kt < 0) {
        problem_release(pr);
        return -1;
    }
    pr->project = project, pr->stage = stage, pr->tangent = tangent;
    ode->project = kp == 1 ? mech_project : kp == 2 ? python_project : NULL;
    ode->stage = ks == 1 ? mech_stage : ks == 2 ? python_stage : NULL;
    ode->tangent = kt == 1 ? mech_tangent : kt == 2 ? python_tangent : NULL;
    if (atol != Py_None) {
        if (get_doubles(atol, &pr->atol_view, 0, n, "atol") < 0) {
            problem_release(pr);
            return -1;
        }
        pr->has_atol = 1;
        ode->atol = pr->atol_view.buf;
    }
    return 0;
}

/* The state and work buffers; n from work's size. */
static int buffers(PyObject *state, PyObject *work, Py_buffer *bs, Py_buffer *bw,
                   int64_t *n) {
    if (get_doubles(state, bs, 1, MB_DOP_STATE_SIZE, "state") < 0) return -1;
    if (get_doubles(work, bw, 1, -1, "work") < 0) {
        PyBuffer_Release(bs);
        return -1;
    }
    if ((bw->len / 8) % MB_DOP_W_ROWS != 0) {
        PyErr_Format(PyExc_ValueError, "work: a multiple of %d values expected",
                     (int)MB_DOP_W_ROWS);
        PyBuffer_Release(bs);
        PyBuffer_Release(bw);
        return -1;
    }
    *n = (int64_t)(bw->len / 8) / MB_DOP_W_ROWS;
    return 0;
}

/* The status, or NULL when a Python callback raised. */
static PyObject *status_or_error(int status, const double *state) {
    if (status == MB_DOP_STOPPED && state[MB_DOP_CODE] == PY_ERROR && PyErr_Occurred())
        return NULL;
    return PyLong_FromLong(status);
}

static PyObject *py_start(PyObject *self, PyObject *args) {
    PyObject *tuple, *y0, *state, *work;
    double t0, first_step;
    if (!PyArg_ParseTuple(args, "O!dOdOO", &PyTuple_Type, &tuple, &t0, &y0, &first_step,
                          &state, &work))
        return NULL;
    Py_buffer bs, bw, by;
    int64_t n;
    if (buffers(state, work, &bs, &bw, &n) < 0) return NULL;
    problem pr;
    mb_ode ode;
    PyObject *out = NULL;
    if (get_doubles(y0, &by, 0, (Py_ssize_t)n, "y0") == 0) {
        if (problem_read(tuple, n, &pr, &ode) == 0) {
            const double start = now_seconds();
            int status = mb_dop853_start(&ode, t0, by.buf, first_step, bs.buf, bw.buf);
            ((double *)bs.buf)[MB_DOP_WALL] += now_seconds() - start;
            out = status_or_error(status, bs.buf);
            problem_release(&pr);
        }
        PyBuffer_Release(&by);
    }
    PyBuffer_Release(&bs);
    PyBuffer_Release(&bw);
    return out;
}

static PyObject *py_run(PyObject *self, PyObject *args) {
    PyObject *tuple, *state, *work;
    double t_stop;
    long long max_steps;
    if (!PyArg_ParseTuple(args, "O!dLOO", &PyTuple_Type, &tuple, &t_stop, &max_steps,
                          &state, &work))
        return NULL;
    Py_buffer bs, bw;
    int64_t n;
    if (buffers(state, work, &bs, &bw, &n) < 0) return NULL;
    problem pr;
    mb_ode ode;
    PyObject *out = NULL;
    if (problem_read(tuple, n, &pr, &ode) == 0) {
        int status = mb_dop853_run(&ode, t_stop, (int64_t)max_steps, bs.buf, bw.buf);
        out = status_or_error(status, bs.buf);
        problem_release(&pr);
    }
    PyBuffer_Release(&bs);
    PyBuffer_Release(&bw);
    return out;
}

static PyObject *py_dense(PyObject *self, PyObject *args) {
    PyObject *tuple, *times, *result, *state, *work;
    if (!PyArg_ParseTuple(args, "O!OOOO", &PyTuple_Type, &tuple, &times, &result, &state,
                          &work))
        return NULL;
    Py_buffer bs, bw, bt, bo;
    int64_t n;
    if (buffers(state, work, &bs, &bw, &n) < 0) return NULL;
    problem pr;
    mb_ode ode;
    PyObject *out = NULL;
    if (get_doubles(times, &bt, 0, -1, "t") == 0) {
        const int64_t m = (int64_t)(bt.len / 8);
        if (get_doubles(result, &bo, 1, (Py_ssize_t)(m * n), "out") == 0) {
            if (problem_read(tuple, n, &pr, &ode) == 0) {
                int code = mb_dop853_dense(&ode, bt.buf, m, bo.buf, bs.buf, bw.buf);
                if (code == -1)
                    PyErr_SetString(PyExc_RuntimeError, "no step to interpolate yet");
                else
                    out = status_or_error(code, bs.buf);
                problem_release(&pr);
            }
            PyBuffer_Release(&bo);
        }
        PyBuffer_Release(&bt);
    }
    PyBuffer_Release(&bs);
    PyBuffer_Release(&bw);
    return out;
}

static PyObject *py_sampled(PyObject *self, PyObject *args) {
    PyObject *tuple, *times, *result, *state, *work, *marks = Py_None;
    double t_stop;
    long long max_steps, k;
    int project_samples;
    if (!PyArg_ParseTuple(args, "O!dLOLOpOO|O", &PyTuple_Type, &tuple, &t_stop, &max_steps,
                          &times, &k, &result, &project_samples, &state, &work, &marks))
        return NULL;
    Py_buffer bs, bw, bt, bo, bm;
    int64_t n;
    if (buffers(state, work, &bs, &bw, &n) < 0) return NULL;
    const int have_marks = marks != Py_None;
    if (have_marks && get_doubles(marks, &bm, 1, -1, "marks") < 0) {
        PyBuffer_Release(&bs);
        PyBuffer_Release(&bw);
        return NULL;
    }
    problem pr;
    mb_ode ode;
    PyObject *out = NULL;
    if (get_doubles(times, &bt, 0, -1, "t_eval") == 0) {
        const int64_t m = (int64_t)(bt.len / 8);
        if (k < 0 || k > m) {
            PyErr_Format(PyExc_ValueError, "k: expected 0 to %lld", (long long)m);
        } else if (get_doubles(result, &bo, 1, (Py_ssize_t)(m * n), "out") == 0) {
            if (problem_read(tuple, n, &pr, &ode) == 0) {
                int64_t kk = (int64_t)k, count = 0;
                double *st_buf = bs.buf;
                const double start = now_seconds();
                int status = mb_dop853_sampled(
                    &ode, t_stop, (int64_t)max_steps, bt.buf, m, &kk, bo.buf,
                    project_samples, st_buf, bw.buf, have_marks ? bm.buf : NULL,
                    have_marks ? (int64_t)(bm.len / 16) : 0, &count);
                st_buf[MB_DOP_WALL] += now_seconds() - start;
                PyObject *st = status_or_error(status, bs.buf);
                if (st != NULL)
                    out = have_marks ? Py_BuildValue("(NLL)", st, (long long)kk,
                                                     (long long)count)
                                     : Py_BuildValue("(NL)", st, (long long)kk);
                problem_release(&pr);
            }
            PyBuffer_Release(&bo);
        }
        PyBuffer_Release(&bt);
    }
    if (have_marks) PyBuffer_Release(&bm);
    PyBuffer_Release(&bs);
    PyBuffer_Release(&bw);
    return out;
}

static PyObject *py_samples(PyObject *self, PyObject *args) {
    PyObject *unknowns, *lam, *times, *states, *reactions, *lengths, *drift;
    if (!PyArg_ParseTuple(args, "OOOOOOO", &unknowns, &lam, &times, &states, &reactions,
                          &lengths, &drift))
        return NULL;
    const mb_model *md;
    const mb_unknowns *u;
    mb_work *w;
    if (!mb_unknowns_object(unknowns, &md, &u, &w)) {
        PyErr_SetString(PyExc_TypeError, "unknowns: an initialised _core.Unknowns is needed");
        return NULL;
    }
    Py_buffer bl, bt, by, br, bs, bd;
    int have_r = 0, have_s = 0, ok = 0;
    if (get_doubles(lam, &bl, 0, md->m, "lam") < 0) return NULL;
    if (get_doubles(times, &bt, 0, -1, "t") < 0) goto lam_;
    const int64_t K = (int64_t)(bt.len / 8), size = MB_STATE_SIZE(md->n, md->planar);
    if (get_doubles(states, &by, 0, K * size, "Y") < 0) goto t_;
    if (reactions != Py_None) {
        if (get_doubles(reactions, &br, 1, K * md->m, "reactions") < 0) goto y_;
        have_r = 1;
    }
    if (lengths != Py_None) {
        if (get_doubles(lengths, &bs, 1, K * md->s, "lengths") < 0) goto r_;
        have_s = 1;
    }
    if (get_doubles(drift, &bd, 1, 2, "drift") < 0) goto s_;
    if (mb_samples(md, u, w, bl.buf, K, bt.buf, by.buf, size, have_r ? br.buf : NULL,
                   have_s ? bs.buf : NULL, bd.buf) < 0)
        PyErr_NoMemory();
    else
        ok = 1;
    PyBuffer_Release(&bd);
s_:
    if (have_s) PyBuffer_Release(&bs);
r_:
    if (have_r) PyBuffer_Release(&br);
y_:
    PyBuffer_Release(&by);
t_:
    PyBuffer_Release(&bt);
lam_:
    PyBuffer_Release(&bl);
    if (!ok) return NULL;
    Py_RETURN_NONE;
}

static PyObject *py_conservation(PyObject *self, PyObject *args) {
    /* mass, J, gravity, stiffness, rest, lengths (or None), Y | T, V, H, figures, spin */
    PyObject *o[12];
    int planar, kind;
    if (!PyArg_ParseTuple(args, "OOOOOOOpiOOOOO", &o[0], &o[1], &o[2], &o[3], &o[4], &o[5],
                          &o[6], &planar, &kind, &o[7], &o[8], &o[9], &o[10], &o[11]))
        return NULL;
    if (kind < 0 || kind > 2) {
        PyErr_SetString(PyExc_ValueError, "kind: 0 (world origin), 1 (spins), 2 (mass centre)");
        return NULL;
    }
    static const char *names[12] = {"mass", "J", "gravity", "stiffness", "rest", "lengths",
                                    "Y", "T", "V", "H", "figures", "spin"};
    Py_buffer b[12];
    int held[12] = {0};
    int ok = 0;
    /* the sizes follow from mass (n), stiffness (s) and T (K) */
    if (get_doubles(o[0], &b[0], 0, -1, names[0]) < 0) return NULL;
    held[0] = 1;
    const int64_t n = (int64_t)(b[0].len / 8);
    if (get_doubles(o[3], &b[3], 0, -1, names[3]) < 0) goto done;
    held[3] = 1;
    const int64_t s = (int64_t)(b[3].len / 8);
    if (get_doubles(o[7], &b[7], 1, -1, names[7]) < 0) goto done;
    held[7] = 1;
    const int64_t K = (int64_t)(b[7].len / 8);
    const Py_ssize_t sizes[12] = {n, 9 * n, 3, s, s, K * s, K * MB_STATE_SIZE(n, planar), K,
                                  K, 3 * K, 6, n};
    for (int i = 1; i < 12; i++) {
        if (held[i]) continue;
        if (i == 5 && o[5] == Py_None) {
            if (s > 0) {
                PyErr_SetString(PyExc_ValueError, "lengths: the springs' lengths are needed");
                goto done;
            }
            continue;
        }
        if (get_doubles(o[i], &b[i], i >= 7, sizes[i], names[i]) < 0) goto done;
        held[i] = 1;
    }
    if (mb_conservation(n, planar, b[0].buf, b[1].buf, b[2].buf, s, b[3].buf, b[4].buf,
                        held[5] ? b[5].buf : NULL, K, b[6].buf, MB_STATE_SIZE(n, planar), kind,
                        b[7].buf, b[8].buf, b[9].buf, b[10].buf, b[11].buf) < 0)
        PyErr_NoMemory();
    else
        ok = 1;
done:
    for (int i = 0; i < 12; i++)
        if (held[i]) PyBuffer_Release(&b[i]);
    if (!ok) return NULL;
    Py_RETURN_NONE;
}

static PyObject *py_unit_samples(PyObject *self, PyObject *args) {
    PyObject *states;
    long long n;
    int planar;
    if (!PyArg_ParseTuple(args, "OLp", &states, &n, &planar)) return NULL;
    if (n < 0) {
        PyErr_SetString(PyExc_ValueError, "n must be >= 0");
        return NULL;
    }
    Py_buffer b;
    if (get_doubles(states, &b, 1, -1, "Y") < 0) return NULL;
    const int64_t size = MB_STATE_SIZE((int64_t)n, planar), count = (int64_t)(b.len / 8);
    if (size == 0 ? count != 0 : count % size != 0) {
        PyErr_Format(PyExc_ValueError, "Y: rows of %lld values expected", (long long)size);
        PyBuffer_Release(&b);
        return NULL;
    }
    const double worst = mb_unit_samples((int64_t)n, planar, size ? count / size : 0, b.buf,
                                         size);
    PyBuffer_Release(&b);
    return PyFloat_FromDouble(worst);
}

static PyObject *py_system(PyObject *self, PyObject *args) {
    int s;
    double t;
    PyObject *params, *y, *ydot;
    if (!PyArg_ParseTuple(args, "iOdOO", &s, &params, &t, &y, &ydot)) return NULL;
    if (s < 0 || s >= SYSTEMS) {
        PyErr_Format(PyExc_ValueError, "no built-in system %d", s);
        return NULL;
    }
    Py_buffer bp, by, bd;
    if (get_doubles(params, &bp, 0, SYSTEM_PARAMS[s], "params") < 0) return NULL;
    PyObject *out = NULL;
    if (get_doubles(y, &by, 0, SYSTEM_SIZE[s], "y") == 0) {
        if (get_doubles(ydot, &bd, 1, SYSTEM_SIZE[s], "ydot") == 0) {
            SYSTEM_FN[s](bp.buf, by.buf, bd.buf);
            out = Py_NewRef(Py_None);
            PyBuffer_Release(&bd);
        }
        PyBuffer_Release(&by);
    }
    PyBuffer_Release(&bp);
    (void)t;
    return out;
}

static PyObject *list_of(const double *x, int n) {
    PyObject *out = PyList_New(n);
    if (out == NULL) return NULL;
    for (int i = 0; i < n; i++) {
        PyObject *v = PyFloat_FromDouble(x[i]);
        if (v == NULL) {
            Py_DECREF(out);
            return NULL;
        }
        PyList_SET_ITEM(out, i, v);
    }
    return out;
}

static PyObject *py_tableau(PyObject *self, PyObject *unused) {
    double c[16], a[16 * 16], b[12], e5[13], e3[13], d[4 * 16];
    mb_dop853_tableau(c, a, b, e5, e3, d);
    return Py_BuildValue("{s:N,s:N,s:N,s:N,s:N,s:N}", "c", list_of(c, 16), "a",
                         list_of(a, 16 * 16), "b", list_of(b, 12), "e5", list_of(e5, 13),
                         "e3", list_of(e3, 13), "d", list_of(d, 4 * 16));
}

static PyObject *py_work_size(PyObject *self, PyObject *arg) {
    long long n = PyLong_AsLongLong(arg);
    if (n == -1 && PyErr_Occurred()) return NULL;
    if (n < 0) {
        PyErr_SetString(PyExc_ValueError, "n must be >= 0");
        return NULL;
    }
    return PyLong_FromLongLong((long long)mb_dop853_work_size((int64_t)n));
}

static PyMethodDef dop853_methods[] = {
    {"dop853_start", py_start, METH_VARARGS,
     "dop853_start(problem, t0, y0, first_step, state, work) -> status: f(t0, y0) and "
     "the first step (first_step <= 0: HNW's initial step); the settings in state first."},
    {"dop853_run", py_run, METH_VARARGS,
     "dop853_run(problem, t_stop, max_steps, state, work) -> status: steps until the "
     "first that reaches t_stop, max_steps steps, t_bound or a failure."},
    {"dop853_dense", py_dense, METH_VARARGS,
     "dop853_dense(problem, t, out, state, work) -> status: out (len(t), n) <- the "
     "last step's dense output at the times t."},
    {"dop853_sampled", py_sampled, METH_VARARGS,
     "dop853_sampled(problem, t_stop, max_steps, t_eval, k, out, project_samples, state, "
     "work) -> (status, k): steps as dop853_run, and after each step out's rows k, k + 1, "
     "... (len(t_eval) x n) <- the dense output at the sample times the step reached, each "
     "moved by project when project_samples; k: the first row not yet written. With "
     "marks (a float64 buffer of rows (t, steps)): -> (status, k, count), the first count "
     "rows written at each step reaching DOP_MARK_NEXT or t_bound (dop853.h); the seconds "
     "spent are added to state[DOP_WALL] (as dop853_start's). state[DOP_RETURN_AFTER] > 0: "
     "the call also returns after the first step ending that many seconds after it began."},
    {"samples", py_samples, METH_VARARGS,
     "samples(unknowns, lam, t, Y, reactions, lengths, drift): a run's figures at its K "
     "output samples (Y: K rows of the packed state at the times t): reactions (K x m, or "
     "None) <- every reaction value, the unknowns' solved; lengths (K x s, or None) <- the "
     "springs' lengths; drift (2) <- the largest |phi| and |G^T v - f'|."},
    {"conservation", py_conservation, METH_VARARGS,
     "conservation(mass, J, gravity, stiffness, rest, lengths, Y, planar, kind, T, V, H, "
     "figures, spin): what a run conserves at its K samples (Y: K rows of the packed state): T "
     "(K) <- kinetic energy, V (K) <- gravity's and the springs' potential (lengths: K x s, "
     "None without springs), H (K x 3) <- angular momentum (kind 0: about the world "
     "origin, 1: the spins alone, 2: about the system's mass centre), figures (6) <- the "
     "largest relative changes of E, p and H, then p at the first sample (6), spin (n) <- "
     "each body's largest |w| (mechanism.h: mb_conservation)."},
    {"unit_samples", py_unit_samples, METH_VARARGS,
     "unit_samples(Y, n, planar) -> the largest |norm - 1| of the quaternions: the samples "
     "Y (K rows of the packed state) finished in place: unit quaternions, and a planar "
     "model's carried angles set to theirs on their branch (mechanism.h)."},
    {"dop853_system", py_system, METH_VARARGS,
     "dop853_system(number, params, t, y, ydot): a built-in test system's y'."},
    {"dop853_tableau", py_tableau, METH_NOARGS,
     "dop853_tableau() -> dict of the coefficients c, a (16 x 16 flat), b, e5, e3, d "
     "(4 x 16 flat), as the core uses them."},
    {"dop853_work_size", py_work_size, METH_O,
     "dop853_work_size(n) -> the size of the work array for n states."},
    {NULL, NULL, 0, NULL},
};

int mb_dop853_register(PyObject *m) {
    if (PyModule_AddFunctions(m, dop853_methods) < 0) return -1;
    static const struct { const char *name; long value; } constants[] = {
        {"DOP_STATE_SIZE", MB_DOP_STATE_SIZE}, {"DOP_PROJECT_INFO", MB_DOP_PROJECT_INFO},
        {"DOP_RTOL", MB_DOP_RTOL}, {"DOP_ATOL", MB_DOP_ATOL},
        {"DOP_MAX_STEP", MB_DOP_MAX_STEP}, {"DOP_T_BOUND", MB_DOP_T_BOUND},
        {"DOP_SAFETY", MB_DOP_SAFETY}, {"DOP_FAC_MIN", MB_DOP_FAC_MIN},
        {"DOP_FAC_MAX", MB_DOP_FAC_MAX}, {"DOP_REFRESH", MB_DOP_REFRESH},
        {"DOP_T", MB_DOP_T}, {"DOP_H", MB_DOP_H}, {"DOP_DIRECTION", MB_DOP_DIRECTION},
        {"DOP_T_OLD", MB_DOP_T_OLD}, {"DOP_H_OLD", MB_DOP_H_OLD},
        {"DOP_STATUS", MB_DOP_STATUS}, {"DOP_CODE", MB_DOP_CODE},
        {"DOP_STEPS", MB_DOP_STEPS}, {"DOP_REJECTED", MB_DOP_REJECTED},
        {"DOP_NFEV", MB_DOP_NFEV}, {"DOP_REFRESHED", MB_DOP_REFRESHED},
        {"DOP_FILTER", MB_DOP_FILTER}, {"DOP_FILTER_NEXT", MB_DOP_FILTER_NEXT},
        {"DOP_DENSE", MB_DOP_DENSE}, {"DOP_DENSE_NFEV", MB_DOP_DENSE_NFEV},
        {"DOP_WALL", MB_DOP_WALL}, {"DOP_MARK_WIDTH", MB_DOP_MARK_WIDTH},
        {"DOP_MARK_NEXT", MB_DOP_MARK_NEXT}, {"DOP_RETURN_AFTER", MB_DOP_RETURN_AFTER},
        {"DOP_INFO", MB_DOP_INFO},
        {"MECH_RATE", MB_MECH_RATE}, {"MECH_ROBUST", MB_MECH_ROBUST},
        {"MECH_ITERS", MB_MECH_ITERS}, {"MECH_STAGE_ITERS", MB_MECH_STAGE_ITERS},
        {"MECH_PARAMS", MB_MECH_PARAMS},
        {"DOP_RUNNING", MB_DOP_RUNNING}, {"DOP_FINISHED", MB_DOP_FINISHED},
        {"DOP_TOO_SMALL", MB_DOP_TOO_SMALL}, {"DOP_STOPPED", MB_DOP_STOPPED},
        {"DOP_W_Y", MB_DOP_W_Y}, {"DOP_W_F", MB_DOP_W_F}, {"DOP_W_Y_OLD", MB_DOP_W_Y_OLD},
        {"DOP_W_K", MB_DOP_W_K}, {"DOP_W_DENSE", MB_DOP_W_DENSE},
        {"DOP_W_ROWS", MB_DOP_W_ROWS}, {"DOP_PY_ERROR", PY_ERROR},
        {"DOP_SYSTEM_OSCILLATOR", SYSTEM_OSCILLATOR},
        {"DOP_SYSTEM_VAN_DER_POL", SYSTEM_VAN_DER_POL},
        {"DOP_SYSTEM_ARENSTORF", SYSTEM_ARENSTORF},
        {"DOP_SYSTEM_PENDULUM", SYSTEM_PENDULUM},
    };
    for (size_t i = 0; i < sizeof(constants) / sizeof(constants[0]); i++)
        if (PyModule_AddIntConstant(m, constants[i].name, constants[i].value) < 0) return -1;
    return 0;
}
