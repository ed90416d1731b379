/* The Python module mbody.kernel._core: the buffers of the packed model handed to the
 * kernel's functions (kernel.h). Arrays pass through the buffer protocol (no numpy C API):
 * float64 or int64, C-contiguous, of the size the model implies, else a ValueError. The
 * calls keep the GIL: each owns scratch memory (mb_work) that is not shared across threads
 * while it runs. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdlib.h>
#include <string.h>

#include "internal.h"

/* -- buffers ------------------------------------------------------------------------ */

/* A C-contiguous buffer of 8-byte items of `want` (1 'd' float64, 0 'q' int64); count
 * items (-1: any). Returns 0, or -1 with a ValueError naming `what`. */
static int get_buffer(PyObject *obj, Py_buffer *view, int writable, int want_float,
                      Py_ssize_t count, const char *what) {
    int flags = PyBUF_C_CONTIGUOUS | PyBUF_FORMAT | (writable ? PyBUF_WRITABLE : 0);
    if (PyObject_GetBuffer(obj, view, flags) < 0) {
        PyErr_Clear();
        PyErr_Format(PyExc_ValueError,
                     "%s: expected a C-contiguous%s %s array", what,
                     writable ? " writable" : "", want_float ? "float64" : "int64");
        return -1;
    }
    const char *f = view->format ? view->format : "B";
    if (*f == '@' || *f == '=' || *f == '<') f++;
    int ok = view->itemsize == 8 && f[1] == '\0' &&
             (want_float ? *f == 'd' : (*f == 'l' || *f == 'q'));
    if (!ok) {
        PyErr_Format(PyExc_ValueError, "%s: expected a %s array, got item format '%s'",
                     what, want_float ? "float64" : "int64", view->format ? view->format : "?");
        PyBuffer_Release(view);
        return -1;
    }
    if (count >= 0 && view->len / 8 != count) {
        PyErr_Format(PyExc_ValueError, "%s: expected %zd values, got %zd", what, count,
                     view->len / 8);
        PyBuffer_Release(view);
        return -1;
    }
    return 0;
}

static int get_double(PyObject *obj, double *out, const char *what) {
    *out = PyFloat_AsDouble(obj);
    if (*out == -1.0 && PyErr_Occurred()) {
        PyErr_Format(PyExc_TypeError, "%s: expected a number", what);
        return -1;
    }
    return 0;
}

static int check_nargs(Py_ssize_t nargs, Py_ssize_t want, const char *name) {
    if (nargs != want) {
        PyErr_Format(PyExc_TypeError, "%s() takes %zd arguments (%zd given)", name, want, nargs);
        return -1;
    }
    return 0;
}

/* A long call's progress (kernel.h, mb_progress) in Python: ctx is a callable taking (stage,
 * done, total), or NULL. Ctrl-C (a pending signal) or an exception from the callable stops
 * the call; its error is then the one set. */
static int report_progress(void *ctx, int stage, int64_t done, int64_t total) {
    if (PyErr_CheckSignals() < 0) return 1;
    if (ctx == NULL) return 0;
    PyObject *r = PyObject_CallFunction((PyObject *)ctx, "iLL", stage, (long long)done,
                                        (long long)total);
    if (r == NULL) return 1;
    Py_DECREF(r);
    return 0;
}

/* -- Model --------------------------------------------------------------------------- */

typedef struct {
    PyObject_HEAD
    Py_buffer F, I;
    int have_F, have_I;
    mb_model md;
    mb_work *w;
} ModelObject;

static void Model_dealloc(ModelObject *self) {
    mb_work_free(self->w);
    if (self->have_F) PyBuffer_Release(&self->F);
    if (self->have_I) PyBuffer_Release(&self->I);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static int Model_init(ModelObject *self, PyObject *args, PyObject *kwds) {
    static char *kwlist[] = {"F", "I", "planar", NULL};
    PyObject *F, *I;
    int planar;
    if (self->have_F || self->have_I) {
        PyErr_SetString(PyExc_RuntimeError, "Model is initialised once");
        return -1;
    }
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "OOp", kwlist, &F, &I, &planar)) return -1;
    if (get_buffer(F, &self->F, 0, 1, -1, "F") < 0) return -1;
    self->have_F = 1;
    if (get_buffer(I, &self->I, 0, 0, -1, "I") < 0) return -1;
    self->have_I = 1;
    if (mb_model_view(&self->md, self->F.buf, self->F.len / 8, self->I.buf, self->I.len / 8,
                      planar) < 0) {
        PyErr_SetString(PyExc_ValueError,
                        "F and I do not describe a packed model (kernel.h): the sizes in "
                        "I's header do not add up to the arrays' lengths, or an index is "
                        "out of range, or an expression's program is malformed");
        return -1;
    }
    self->w = mb_work_new(&self->md, NULL);
    if (self->w == NULL) {
        PyErr_NoMemory();
        return -1;
    }
    return 0;
}

static int model_ready(ModelObject *self) {
    if (self->w == NULL) {
        PyErr_SetString(PyExc_RuntimeError, "Model is not initialised");
        return -1;
    }
    return 0;
}

/* y: the state, MB_STATE_SIZE or (solve, columns, wrenches) 13 n values. */
static int get_state(const mb_model *md, PyObject *obj, Py_buffer *view, int writable,
                     int exact) {
    if (get_buffer(obj, view, writable, 1, -1, "y") < 0) return -1;
    Py_ssize_t len = view->len / 8, full = MB_STATE_SIZE(md->n, md->planar);
    if (len != full && (exact || len != 13 * md->n)) {
        PyErr_Format(PyExc_ValueError, "y: expected %zd values (the packed state), got %zd",
                     full, len);
        PyBuffer_Release(view);
        return -1;
    }
    return 0;
}

PyDoc_STRVAR(net_wrench_doc,
"net_wrench(t, y, out)\n\nout (n x 6) <- Q - b per body at time t (s) and state y:\n"
"[W_F (world); B_M - w x J w (body axes)], the loads at t.");

static PyObject *Model_net_wrench(ModelObject *self, PyObject *const *args, Py_ssize_t nargs) {
    Py_buffer y, out;
    double t;
    if (model_ready(self) < 0 || check_nargs(nargs, 3, "net_wrench") < 0 ||
        get_double(args[0], &t, "t") < 0)
        return NULL;
    if (get_state(&self->md, args[1], &y, 0, 0) < 0) return NULL;
    if (get_buffer(args[2], &out, 1, 1, 6 * self->md.n, "out") < 0) {
        PyBuffer_Release(&y);
        return NULL;
    }
    mb_net_wrench(&self->md, self->w, t, y.buf, out.buf);
    PyBuffer_Release(&y);
    PyBuffer_Release(&out);
    Py_RETURN_NONE;
}

PyDoc_STRVAR(wrench_parts_doc,
"wrench_parts(t, y, Q, b)\n\nQ (n x 6) <- the applied loads per body [W_F (world); B_M "
"(about G, body axes)],\nb (n x 6) <- the gyroscopic term [0; w x J w]; net_wrench is "
"Q - b.");

static PyObject *Model_wrench_parts(ModelObject *self, PyObject *const *args, Py_ssize_t nargs) {
    Py_buffer y, Q, b;
    double t;
    if (model_ready(self) < 0 || check_nargs(nargs, 4, "wrench_parts") < 0 ||
        get_double(args[0], &t, "t") < 0)
        return NULL;
    if (get_state(&self->md, args[1], &y, 0, 0) < 0) return NULL;
    if (get_buffer(args[2], &Q, 1, 1, 6 * self->md.n, "Q") < 0) {
        PyBuffer_Release(&y);
        return NULL;
    }
    if (get_buffer(args[3], &b, 1, 1, 6 * self->md.n, "b") < 0) {
        PyBuffer_Release(&y);
        PyBuffer_Release(&Q);
        return NULL;
    }
    mb_wrench_parts(&self->md, self->w, t, y.buf, Q.buf, b.buf);
    PyBuffer_Release(&y);
    PyBuffer_Release(&Q);
    PyBuffer_Release(&b);
    Py_RETURN_NONE;
}

PyDoc_STRVAR(springs_doc,
"springs(t, y, out)\n\nout (s x 6) <- each spring-damper's [L (m), L' (m/s), T (N), u (3)] "
"at state y:\nits length, rate, tension k (L - L0) + c L' and unit direction from end a "
"to end b (world).");

static PyObject *Model_springs(ModelObject *self, PyObject *const *args, Py_ssize_t nargs) {
    Py_buffer y, out;
    double t;
    if (model_ready(self) < 0 || check_nargs(nargs, 3, "springs") < 0 ||
        get_double(args[0], &t, "t") < 0)
        return NULL;
    if (get_state(&self->md, args[1], &y, 0, 0) < 0) return NULL;
    if (get_buffer(args[2], &out, 1, 1, 6 * self->md.s, "out") < 0) {
        PyBuffer_Release(&y);
        return NULL;
    }
    mb_springs(&self->md, self->w, t, y.buf, out.buf);
    PyBuffer_Release(&y);
    PyBuffer_Release(&out);
    Py_RETURN_NONE;
}

PyDoc_STRVAR(load_wrenches_doc,
"load_wrenches(t, y, out)\n\nout ((k + 2 s) x 7) <- each point load's, then each spring's "
"end a's and end b's\nshare of net_wrench: [body (-1: ground), W_F (world), B_M (about G, "
"body axes)].");

static PyObject *Model_load_wrenches(ModelObject *self, PyObject *const *args,
                                     Py_ssize_t nargs) {
    Py_buffer y, out;
    double t;
    if (model_ready(self) < 0 || check_nargs(nargs, 3, "load_wrenches") < 0 ||
        get_double(args[0], &t, "t") < 0)
        return NULL;
    const mb_model *md = &self->md;
    if (get_state(md, args[1], &y, 0, 0) < 0) return NULL;
    if (get_buffer(args[2], &out, 1, 1, 7 * (md->k + 2 * md->s), "out") < 0) {
        PyBuffer_Release(&y);
        return NULL;
    }
    mb_rotations(md->n, (const double *)y.buf + 3 * md->n, self->w->R);
    mb_eval_all(md, self->w, t);
    mb_loads_at(md, self->w);
    mb_load_wrenches_at(md, self->w, y.buf, out.buf);
    PyBuffer_Release(&y);
    PyBuffer_Release(&out);
    Py_RETURN_NONE;
}

PyDoc_STRVAR(loads_at_doc,
"loads_at(t, out)\n\nout (k x 3) <- the point loads' values at time t (constant ones as "
"packed).");

static PyObject *Model_loads_at(ModelObject *self, PyObject *const *args, Py_ssize_t nargs) {
    Py_buffer out;
    double t;
    if (model_ready(self) < 0 || check_nargs(nargs, 2, "loads_at") < 0 ||
        get_double(args[0], &t, "t") < 0)
        return NULL;
    if (get_buffer(args[1], &out, 1, 1, 3 * self->md.k, "out") < 0) return NULL;
    mb_eval_all(&self->md, self->w, t);
    mb_loads_at(&self->md, self->w);
    memcpy(out.buf, self->w->loads, sizeof(double) * 3 * self->md.k);
    PyBuffer_Release(&out);
    Py_RETURN_NONE;
}

PyDoc_STRVAR(columns_doc,
"columns(t, y, child6, parent6, W_e, W_P, gamma, phi, gtv)\n\nPer reaction component "
"(m): its columns of G on the child and the parent (m x 6),\nits direction W_e and point "
"W_P (m x 3, world), gamma = -G'^T v, phi and\nG^T v (m each); a driven component's phi, "
"G^T v and gamma are shifted by its\nlaw f, f', f'' at t (kernel.h).");

static PyObject *Model_columns(ModelObject *self, PyObject *const *args, Py_ssize_t nargs) {
    static const char *names[] = {"child6", "parent6", "W_e", "W_P", "gamma", "phi", "gtv"};
    static const int width[] = {6, 6, 3, 3, 1, 1, 1};
    Py_buffer y, b[7];
    double t;
    if (model_ready(self) < 0 || check_nargs(nargs, 9, "columns") < 0 ||
        get_double(args[0], &t, "t") < 0)
        return NULL;
    if (get_state(&self->md, args[1], &y, 0, 0) < 0) return NULL;
    int got = 0;
    for (; got < 7; got++)
        if (get_buffer(args[2 + got], &b[got], 1, 1, width[got] * self->md.m, names[got]) < 0)
            break;
    if (got == 7)
        mb_columns(&self->md, self->w, t, y.buf, b[0].buf, b[1].buf, b[2].buf, b[3].buf,
                   b[4].buf, b[5].buf, b[6].buf);
    for (int i = 0; i < got; i++) PyBuffer_Release(&b[i]);
    PyBuffer_Release(&y);
    if (got < 7) return NULL;
    Py_RETURN_NONE;
}

PyDoc_STRVAR(expression_doc,
"expression(e, t) -> float\n\nThe value at time t of the packed expression e (out of a "
"function's domain: inf\nor nan, as numpy gives them).");

static PyObject *Model_expression(ModelObject *self, PyObject *const *args, Py_ssize_t nargs) {
    double t;
    if (model_ready(self) < 0 || check_nargs(nargs, 2, "expression") < 0) return NULL;
    Py_ssize_t e = PyLong_AsSsize_t(args[0]);
    if (e == -1 && PyErr_Occurred()) return NULL;
    if (get_double(args[1], &t, "t") < 0) return NULL;
    if (e < 0 || e >= self->md.n_expr) {
        PyErr_Format(PyExc_IndexError, "expression %zd: the model has %lld", e,
                     (long long)self->md.n_expr);
        return NULL;
    }
    return PyFloat_FromDouble(mb_expression(&self->md, e, t));
}

/* Iq and cols of a generalized call: views checked against the model (mb_coordinates_check). */
static int get_coordinates(const mb_model *md, PyObject *Iq_obj, PyObject *cols_obj,
                           Py_buffer *Iq, Py_buffer *cols) {
    if (get_buffer(Iq_obj, Iq, 0, 0, -1, "Iq") < 0) return -1;
    if (get_buffer(cols_obj, cols, 0, 0, -1, "cols") < 0) {
        PyBuffer_Release(Iq);
        return -1;
    }
    Py_ssize_t nI = Iq->len / 8;
    if (nI % MB_GQ_W != 0 ||
        mb_coordinates_check(md, nI / MB_GQ_W, Iq->buf, cols->len / 8, cols->buf) < 0) {
        PyErr_SetString(PyExc_ValueError,
                        "Iq and cols do not describe generalized coordinates of this model "
                        "(kernel.h: kinds, joint or body indices, axes, increasing columns)");
        PyBuffer_Release(Iq);
        PyBuffer_Release(cols);
        return -1;
    }
    return 0;
}

PyDoc_STRVAR(coordinate_rows_doc,
"coordinate_rows(t, y, Iq, cols, rows, values)\n\nThe generalized coordinates' rate rows "
"at (t, y) over the columns cols: rows\n(nq x len(cols)), and their values (nq; NaN for a "
"quasi-velocity). kernel.h: MB_GQ_*.");

static PyObject *Model_coordinate_rows(ModelObject *self, PyObject *const *args,
                                       Py_ssize_t nargs) {
    Py_buffer y, Iq, cols, rows, values;
    double t;
    if (model_ready(self) < 0 || check_nargs(nargs, 6, "coordinate_rows") < 0 ||
        get_double(args[0], &t, "t") < 0)
        return NULL;
    const mb_model *md = &self->md;
    if (get_state(md, args[1], &y, 0, 0) < 0) return NULL;
    if (get_coordinates(md, args[2], args[3], &Iq, &cols) < 0) {
        PyBuffer_Release(&y);
        return NULL;
    }
    Py_ssize_t nq = Iq.len / 8 / MB_GQ_W, N = cols.len / 8;
    int ok = get_buffer(args[4], &rows, 1, 1, nq * N, "rows") == 0;
    if (ok && get_buffer(args[5], &values, 1, 1, nq, "values") < 0) {
        PyBuffer_Release(&rows);
        ok = 0;
    }
    int status = 0;
    if (ok) {
        status = mb_coordinate_rows(md, self->w, t, y.buf, nq, Iq.buf, N, cols.buf, rows.buf,
                                    values.buf);
        PyBuffer_Release(&rows);
        PyBuffer_Release(&values);
    }
    PyBuffer_Release(&cols);
    PyBuffer_Release(&Iq);
    PyBuffer_Release(&y);
    if (!ok) return NULL;
    if (status < 0) return PyErr_NoMemory();
    Py_RETURN_NONE;
}

static PyObject *Model_get_int(ModelObject *self, void *which) {
    const mb_model *md = &self->md;
    switch ((int)(intptr_t)which) {
    case 0: return PyLong_FromLongLong(md->n);
    case 1: return PyLong_FromLongLong(md->m);
    case 2: return PyLong_FromLongLong(md->k);
    case 3: return PyLong_FromLongLong(md->s);
    case 4: return PyBool_FromLong(md->planar);
    case 5: return PyLong_FromLongLong(MB_STATE_SIZE(md->n, md->planar));
    default: return PyLong_FromLongLong(md->n_expr);
    }
}

static PyGetSetDef Model_getset[] = {
    {"n", (getter)Model_get_int, NULL, "number of bodies", (void *)0},
    {"m", (getter)Model_get_int, NULL, "number of reaction components", (void *)1},
    {"k", (getter)Model_get_int, NULL, "number of point loads", (void *)2},
    {"s", (getter)Model_get_int, NULL, "number of springs", (void *)3},
    {"planar", (getter)Model_get_int, NULL, "a planar model", (void *)4},
    {"state_size", (getter)Model_get_int, NULL, "length of the packed state y", (void *)5},
    {"n_expr", (getter)Model_get_int, NULL, "number of packed expressions", (void *)6},
    {NULL, NULL, NULL, NULL, NULL},
};

static PyMethodDef Model_methods[] = {
    {"net_wrench", (PyCFunction)(void (*)(void))Model_net_wrench, METH_FASTCALL, net_wrench_doc},
    {"wrench_parts", (PyCFunction)(void (*)(void))Model_wrench_parts, METH_FASTCALL, wrench_parts_doc},
    {"springs", (PyCFunction)(void (*)(void))Model_springs, METH_FASTCALL, springs_doc},
    {"load_wrenches", (PyCFunction)(void (*)(void))Model_load_wrenches, METH_FASTCALL,
     load_wrenches_doc},
    {"loads_at", (PyCFunction)(void (*)(void))Model_loads_at, METH_FASTCALL, loads_at_doc},
    {"columns", (PyCFunction)(void (*)(void))Model_columns, METH_FASTCALL, columns_doc},
    {"expression", (PyCFunction)(void (*)(void))Model_expression, METH_FASTCALL, expression_doc},
    {"coordinate_rows", (PyCFunction)(void (*)(void))Model_coordinate_rows, METH_FASTCALL,
     coordinate_rows_doc},
    {NULL, NULL, 0, NULL},
};

PyDoc_STRVAR(Model_doc,
"Model(F, I, planar)\n\nA packed model (mbody.equations.pack.pack_model: F float64, I "
"int64, both\nC-contiguous; kernel.h's layout). Keeps both buffers alive; a ValueError when "
"their\nsizes do not add up or an index is out of range.");

static PyTypeObject ModelType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "mbody.kernel._core.Model",
    .tp_basicsize = sizeof(ModelObject),
    .tp_dealloc = (destructor)Model_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = Model_doc,
    .tp_methods = Model_methods,
    .tp_getset = Model_getset,
    .tp_init = (initproc)Model_init,
    .tp_new = PyType_GenericNew,
};

/* -- Unknowns ------------------------------------------------------------------------ */

typedef struct {
    PyObject_HEAD
    ModelObject *model;
    Py_buffer Iu;
    int have_Iu;
    mb_unknowns u;
    mb_work *w;
} UnknownsObject;

static void Unknowns_dealloc(UnknownsObject *self) {
    mb_work_free(self->w);
    if (self->have_Iu) PyBuffer_Release(&self->Iu);
    Py_XDECREF(self->model);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static int Unknowns_init(UnknownsObject *self, PyObject *args, PyObject *kwds) {
    static char *kwlist[] = {"model", "Iu", NULL};
    PyObject *model, *Iu;
    if (self->model != NULL) {
        PyErr_SetString(PyExc_RuntimeError, "Unknowns is initialised once");
        return -1;
    }
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "O!O", kwlist, &ModelType, &model, &Iu))
        return -1;
    if (model_ready((ModelObject *)model) < 0) return -1;
    Py_INCREF(model);
    self->model = (ModelObject *)model;
    if (get_buffer(Iu, &self->Iu, 0, 0, -1, "Iu") < 0) return -1;
    self->have_Iu = 1;
    if (mb_unknowns_view(&self->u, &self->model->md, self->Iu.buf, self->Iu.len / 8) < 0) {
        PyErr_SetString(PyExc_ValueError,
                        "Iu does not describe unknowns of this model (kernel.h): sizes, "
                        "component indices, the per-body incidence or the band width");
        return -1;
    }
    self->w = mb_work_new(&self->model->md, &self->u);
    if (self->w == NULL) {
        PyErr_NoMemory();
        return -1;
    }
    return 0;
}

static int unknowns_ready(UnknownsObject *self) {
    if (self->w == NULL) {
        PyErr_SetString(PyExc_RuntimeError, "Unknowns is not initialised");
        return -1;
    }
    return 0;
}

PyDoc_STRVAR(solve_doc,
"solve(t, y, lam, out) -> info\n\nAccelerations and reactions at (t, y) with the unknown "
"components solved; lam (m):\nthe known values (0 on unknown components). out: "
"solve_layout(n, m, planar)'s\nlength: accelerations (planar [a_x, a_y, alpha], spatial "
"[a_G world, w' body\naxes] per body), lambda (m, known values in place), G^T v (m), "
"not-unique flags (m),\ninfo (INFO: slots ST_*). Returns info as a tuple (slots ST_*): the "
"backward error a\nfloat, the rest ints.");

static PyObject *Unknowns_solve(UnknownsObject *self, PyObject *const *args, Py_ssize_t nargs) {
    Py_buffer y, lam, out;
    double t;
    if (unknowns_ready(self) < 0 || check_nargs(nargs, 4, "solve") < 0 ||
        get_double(args[0], &t, "t") < 0)
        return NULL;
    const mb_model *md = &self->model->md;
    if (get_state(md, args[1], &y, 0, 0) < 0) return NULL;
    if (get_buffer(args[2], &lam, 0, 1, md->m, "lam") < 0) {
        PyBuffer_Release(&y);
        return NULL;
    }
    Py_ssize_t N = (md->planar ? 3 : 6) * md->n;
    if (get_buffer(args[3], &out, 1, 1, N + 3 * md->m + MB_INFO, "out") < 0) {
        PyBuffer_Release(&y);
        PyBuffer_Release(&lam);
        return NULL;
    }
    mb_solve(md, &self->u, self->w, t, y.buf, lam.buf, out.buf);
    PyBuffer_Release(&y);
    PyBuffer_Release(&lam);
    /* info again as Python numbers, what the caller reads first (cheaper than a slice's
     * tolist): the backward error a float, the counts and codes ints (small ones are
     * Python's shared objects, nothing to allocate) */
    const double *info = (const double *)out.buf + N + 3 * md->m;
    PyObject *res = PyTuple_New(MB_INFO);
    for (int k = 0; res != NULL && k < MB_INFO; k++) {
        PyObject *v = k == MB_ST_BERR ? PyFloat_FromDouble(info[k])
                                      : PyLong_FromLongLong((long long)info[k]);
        if (v == NULL) Py_CLEAR(res);
        else PyTuple_SET_ITEM(res, k, v);
    }
    PyBuffer_Release(&out);
    return res;
}

PyDoc_STRVAR(set_generic_rank_doc,
"set_generic_rank(rank)\n\nThe rank G_U has at the mechanism's generic configurations "
"(kernel.h: mb_unknowns.generic_rank);\nmu (the default) for a mechanism that is not "
"redundant there.");

static PyObject *Unknowns_set_generic_rank(UnknownsObject *self, PyObject *arg) {
    if (unknowns_ready(self) < 0) return NULL;
    long long r = PyLong_AsLongLong(arg);
    if (r == -1 && PyErr_Occurred()) return NULL;
    if (r < 0 || r > self->u.mu) {
        PyErr_Format(PyExc_ValueError, "generic rank %lld is not between 0 and mu = %lld", r,
                     (long long)self->u.mu);
        return NULL;
    }
    self->u.generic_rank = (int64_t)r;
    Py_RETURN_NONE;
}

static PyObject *Unknowns_get_generic_rank(UnknownsObject *self, void *closure) {
    (void)closure;
    return PyLong_FromLongLong((long long)self->u.generic_rank);
}

PyDoc_STRVAR(solve_given_doc,
"solve_given(r6, child6, parent6, gamma_U, out)\n\nThe constrained solve with G's "
"columns (m x 6 each side), the right-hand side r6\n(n x 6: Q - b + G_K lam_K) and "
"gamma of the unknowns (mu) given: out [acc (n x 6) |\nlam_U (mu) | not-unique flags (mu) "
"| info (INFO)].");

static PyObject *Unknowns_solve_given(UnknownsObject *self, PyObject *const *args,
                                      Py_ssize_t nargs) {
    Py_buffer r6, c6, p6, gam, out;
    if (unknowns_ready(self) < 0 || check_nargs(nargs, 5, "solve_given") < 0) return NULL;
    const mb_model *md = &self->model->md;
    Py_ssize_t n = md->n, m = md->m, mu = self->u.mu;
    if (get_buffer(args[0], &r6, 0, 1, 6 * n, "r6") < 0) return NULL;
    if (get_buffer(args[1], &c6, 0, 1, 6 * m, "child6") < 0) goto r6_;
    if (get_buffer(args[2], &p6, 0, 1, 6 * m, "parent6") < 0) goto c6_;
    if (get_buffer(args[3], &gam, 0, 1, mu, "gamma_U") < 0) goto p6_;
    if (get_buffer(args[4], &out, 1, 1, 6 * n + 2 * mu + MB_INFO, "out") < 0) goto gam_;
    mb_solve_given(md, &self->u, self->w, r6.buf, c6.buf, p6.buf, gam.buf, out.buf);
    PyBuffer_Release(&out);
    PyBuffer_Release(&gam);
    PyBuffer_Release(&p6);
    PyBuffer_Release(&c6);
    PyBuffer_Release(&r6);
    Py_RETURN_NONE;
gam_:
    PyBuffer_Release(&gam);
p6_:
    PyBuffer_Release(&p6);
c6_:
    PyBuffer_Release(&c6);
r6_:
    PyBuffer_Release(&r6);
    return NULL;
}

PyDoc_STRVAR(derivative_doc,
"derivative(t, y, lam, rate, out) -> int\n\nout <- dy/dt at (t, y) (y: the packed state, "
"state_size values) with the unknown\nreactions solved and Baumgarte's terms (alpha = beta "
"= rate); lam: the known values.\nReturns 0, or the singular-mass code 1 + 6 body + row "
"(then out is not written).");

static PyObject *Unknowns_derivative(UnknownsObject *self, PyObject *const *args,
                                     Py_ssize_t nargs) {
    Py_buffer y, lam, out;
    double t, rate;
    if (unknowns_ready(self) < 0 || check_nargs(nargs, 5, "derivative") < 0 ||
        get_double(args[0], &t, "t") < 0 || get_double(args[3], &rate, "rate") < 0)
        return NULL;
    const mb_model *md = &self->model->md;
    if (get_state(md, args[1], &y, 0, 1) < 0) return NULL;
    if (get_buffer(args[2], &lam, 0, 1, md->m, "lam") < 0) {
        PyBuffer_Release(&y);
        return NULL;
    }
    if (get_buffer(args[4], &out, 1, 1, MB_STATE_SIZE(md->n, md->planar), "out") < 0) {
        PyBuffer_Release(&y);
        PyBuffer_Release(&lam);
        return NULL;
    }
    int status = mb_derivative(md, &self->u, self->w, t, y.buf, lam.buf, rate, out.buf);
    PyBuffer_Release(&y);
    PyBuffer_Release(&lam);
    PyBuffer_Release(&out);
    return PyLong_FromLong(status);
}

PyDoc_STRVAR(project_doc,
"project(t, y, iters, robust_below, homogeneous, info)\n\nMove y (in place) onto the "
"enforced joints at t: `iters` Gauss-Newton position steps,\nthen the mass-orthogonal "
"velocity projection (target G^T v = f'(t); with\n`homogeneous` G^T v = 0 and the laws "
"left out). info (PROJECT_INFO) <- slots PR_*.\nBelow a geometric ratio of robust_below the "
"solves take the null-space route.");

static PyObject *Unknowns_project(UnknownsObject *self, PyObject *const *args,
                                  Py_ssize_t nargs) {
    Py_buffer y, info;
    double t, robust_below;
    if (unknowns_ready(self) < 0 || check_nargs(nargs, 6, "project") < 0 ||
        get_double(args[0], &t, "t") < 0 || get_double(args[3], &robust_below, "robust_below") < 0)
        return NULL;
    long iters = PyLong_AsLong(args[2]);
    if (iters == -1 && PyErr_Occurred()) return NULL;
    if (iters < 0 || iters > 1000) {
        PyErr_SetString(PyExc_ValueError, "iters: expected 0 to 1000");
        return NULL;
    }
    int homogeneous = PyObject_IsTrue(args[4]);
    if (homogeneous < 0) return NULL;
    const mb_model *md = &self->model->md;
    if (get_state(md, args[1], &y, 1, 1) < 0) return NULL;
    if (get_buffer(args[5], &info, 1, 1, MB_PROJECT_INFO, "info") < 0) {
        PyBuffer_Release(&y);
        return NULL;
    }
    mb_project(md, &self->u, self->w, t, y.buf, (int)iters, robust_below, homogeneous, info.buf);
    PyBuffer_Release(&y);
    PyBuffer_Release(&info);
    Py_RETURN_NONE;
}

PyDoc_STRVAR(kinematic_run_doc,
"kinematic_run(t, y, lam, max_newton, tol, Y, OUT, ENERGY, info) -> int\n\nA kinematic "
"run (kernel.h: mb_kinematic_run): at each time of t (K, increasing),\ny carried forward, "
"moved onto every joint and driver by Newton steps (at most\nmax_newton, until a step is at "
"most tol), stored in Y (K x state_size), solved\ninto OUT (K x solve_layout's length) and "
"its energy terms into ENERGY (K x 3:\nQ . v, the springs' elastic energy, its rate). "
"Returns K, or the index of the\nsample where the loops did not close; info (KR_INFO) <- "
"slots KR_*.");

static PyObject *Unknowns_kinematic_run(UnknownsObject *self, PyObject *const *args,
                                        Py_ssize_t nargs) {
    Py_buffer t, y, lam, Y, OUT, E, info;
    double tol;
    if (unknowns_ready(self) < 0 || check_nargs(nargs, 9, "kinematic_run") < 0 ||
        get_double(args[4], &tol, "tol") < 0)
        return NULL;
    long max_newton = PyLong_AsLong(args[3]);
    if (max_newton == -1 && PyErr_Occurred()) return NULL;
    if (max_newton < 1 || max_newton > 1000) {
        PyErr_SetString(PyExc_ValueError, "max_newton: expected 1 to 1000");
        return NULL;
    }
    const mb_model *md = &self->model->md;
    Py_ssize_t S = MB_STATE_SIZE(md->n, md->planar);
    Py_ssize_t L = (md->planar ? 3 : 6) * md->n + 3 * md->m + MB_INFO;
    PyObject *result = NULL;
    if (get_buffer(args[0], &t, 0, 1, -1, "t") < 0) return NULL;
    Py_ssize_t K = t.len / 8;
    if (get_state(md, args[1], &y, 1, 1) < 0) goto t_;
    if (get_buffer(args[2], &lam, 0, 1, md->m, "lam") < 0) goto y_;
    if (get_buffer(args[5], &Y, 1, 1, K * S, "Y") < 0) goto lam_;
    if (get_buffer(args[6], &OUT, 1, 1, K * L, "OUT") < 0) goto Y_;
    if (get_buffer(args[7], &E, 1, 1, K * 3, "ENERGY") < 0) goto OUT_;
    if (get_buffer(args[8], &info, 1, 1, MB_KR_INFO, "info") < 0) goto E_;
    const double *tt = t.buf;
    for (Py_ssize_t k = 1; k < K; k++)
        if (!(tt[k] > tt[k - 1])) {
            PyErr_SetString(PyExc_ValueError, "t: expected increasing times");
            goto info_;
        }
    /* the GIL is kept: the work buffers are the object's own (as every method's) */
    int64_t done = mb_kinematic_run(md, &self->u, self->w, tt, K, y.buf, lam.buf,
                                    (int)max_newton, tol, Y.buf, OUT.buf, E.buf, info.buf);
    if (((double *)info.buf)[MB_KR_SINGULAR] < 0.0)
        PyErr_NoMemory();
    else
        result = PyLong_FromLongLong((long long)done);
info_:
    PyBuffer_Release(&info);
E_:
    PyBuffer_Release(&E);
OUT_:
    PyBuffer_Release(&OUT);
Y_:
    PyBuffer_Release(&Y);
lam_:
    PyBuffer_Release(&lam);
y_:
    PyBuffer_Release(&y);
t_:
    PyBuffer_Release(&t);
    return result;
}

PyDoc_STRVAR(energy_samples_doc,
"energy_samples(t, Y, lam, ACC, ENERGY) -> int\n\nAt each of the K sampled states (the "
"rows of Y, K x state_size) at the times t:\nthe accelerations with the unknown reactions "
"solved into ACC (K x N, the model's\ncoordinates) and ENERGY (K x 3): Q . v, the springs' "
"elastic energy, its rate\n(kernel.h: mb_energy_samples). Returns 0 or the first "
"singular-mass status.");

static PyObject *Unknowns_energy_samples(UnknownsObject *self, PyObject *const *args,
                                         Py_ssize_t nargs) {
    Py_buffer t, Y, lam, A, E;
    if (unknowns_ready(self) < 0 || check_nargs(nargs, 5, "energy_samples") < 0) return NULL;
    const mb_model *md = &self->model->md;
    Py_ssize_t S = MB_STATE_SIZE(md->n, md->planar), N = (md->planar ? 3 : 6) * md->n;
    PyObject *result = NULL;
    if (get_buffer(args[0], &t, 0, 1, -1, "t") < 0) return NULL;
    Py_ssize_t K = t.len / 8;
    if (get_buffer(args[1], &Y, 0, 1, K * S, "Y") < 0) goto t_;
    if (get_buffer(args[2], &lam, 0, 1, md->m, "lam") < 0) goto Y_;
    if (get_buffer(args[3], &A, 1, 1, K * N, "ACC") < 0) goto lam_;
    if (get_buffer(args[4], &E, 1, 1, K * 3, "ENERGY") < 0) goto A_;
    int status = mb_energy_samples(md, &self->u, self->w, lam.buf, K, t.buf, Y.buf, S,
                                   A.buf, E.buf);
    if (status < 0)
        PyErr_NoMemory();
    else
        result = PyLong_FromLong(status);
    PyBuffer_Release(&E);
A_:
    PyBuffer_Release(&A);
lam_:
    PyBuffer_Release(&lam);
Y_:
    PyBuffer_Release(&Y);
t_:
    PyBuffer_Release(&t);
    return result;
}

PyDoc_STRVAR(schur_doc,
"schur(t, y, S_out)\n\nS_out (mu x mu) <- S = G_U^T M^-1 G_U at (t, y), dense, in the "
"unknowns' order (for a\ncondition estimate).");

static PyObject *Unknowns_schur(UnknownsObject *self, PyObject *const *args, Py_ssize_t nargs) {
    Py_buffer y, S;
    double t;
    if (unknowns_ready(self) < 0 || check_nargs(nargs, 3, "schur") < 0 ||
        get_double(args[0], &t, "t") < 0)
        return NULL;
    const mb_model *md = &self->model->md;
    mb_work *w = self->w;
    if (get_state(md, args[1], &y, 0, 0) < 0) return NULL;
    if (get_buffer(args[2], &S, 1, 1, self->u.mu * self->u.mu, "S_out") < 0) {
        PyBuffer_Release(&y);
        return NULL;
    }
    mb_rotations(md->n, (const double *)y.buf + 3 * md->n, w->R);
    mb_eval_all(md, w, t);
    mb_columns_at(md, w, y.buf, 1, w->child6, w->parent6, NULL, NULL, w->gamma, w->phi, w->gtv);
    memset(S.buf, 0, sizeof(double) * self->u.mu * self->u.mu);
    mb_schur(md, &self->u, md->bodies, w->child6, w->parent6, S.buf, 0);
    PyBuffer_Release(&y);
    PyBuffer_Release(&S);
    Py_RETURN_NONE;
}

PyDoc_STRVAR(generalized_doc,
"generalized(t, y, lam, Iq, cols, qdot, out)\n\nThe velocity transformation and the "
"generalized mass and forces at (t, y) with the\nunknowns' components held (kernel.h, "
"mb_generalized): out [T (N x nq) | v_e (N) |\na0 (N) | M_q (nq x nq) | f_q (nq) | q (nq) "
"| q' (nq) | f_scale (nq) | info (GENERALIZED_INFO)],\nN = len(cols), nq = len(Iq) / GQ_W. qdot: the "
"rates (nq), or None for those of y's\nvelocities. lam (m): the known components' values "
"(0 on held ones).");

static PyObject *Unknowns_generalized(UnknownsObject *self, PyObject *const *args,
                                      Py_ssize_t nargs) {
    Py_buffer y, lam, Iq, cols, qdot, out;
    double t;
    int have_qdot = 0;
    if (unknowns_ready(self) < 0 || check_nargs(nargs, 7, "generalized") < 0 ||
        get_double(args[0], &t, "t") < 0)
        return NULL;
    const mb_model *md = &self->model->md;
    if (get_state(md, args[1], &y, 0, 0) < 0) return NULL;
    if (get_buffer(args[2], &lam, 0, 1, md->m, "lam") < 0) goto y_;
    if (get_coordinates(md, args[3], args[4], &Iq, &cols) < 0) goto lam_;
    Py_ssize_t nq = Iq.len / 8 / MB_GQ_W, N = cols.len / 8;
    if (args[5] != Py_None) {
        if (get_buffer(args[5], &qdot, 0, 1, nq, "qdot") < 0) goto Iq_;
        have_qdot = 1;
    }
    if (get_buffer(args[6], &out, 1, 1, N * nq + 2 * N + nq * nq + 4 * nq + MB_GENERALIZED_INFO,
                   "out") < 0)
        goto qdot_;
    int status = mb_generalized(md, &self->u, self->w, t, y.buf, lam.buf, nq, Iq.buf, N,
                                cols.buf, have_qdot ? qdot.buf : NULL, out.buf);
    PyBuffer_Release(&out);
    if (have_qdot) PyBuffer_Release(&qdot);
    PyBuffer_Release(&cols);
    PyBuffer_Release(&Iq);
    PyBuffer_Release(&lam);
    PyBuffer_Release(&y);
    if (status < 0) return PyErr_NoMemory();
    Py_RETURN_NONE;
qdot_:
    if (have_qdot) PyBuffer_Release(&qdot);
Iq_:
    PyBuffer_Release(&cols);
    PyBuffer_Release(&Iq);
lam_:
    PyBuffer_Release(&lam);
y_:
    PyBuffer_Release(&y);
    return NULL;
}

PyDoc_STRVAR(independence_doc,
"independence(t, y, Iq, cols, colscale, out)\n\nHow far each row of B = D_r [G_U^T; A^T] S "
"(S = diag(colscale), rows\nscaled to unit length) is from the span of the others, for a "
"square B (kernel.h,\nmb_independence): out (r + 1) [1 / |B^-1 e_i| | the QR's pivot ratio], "
"0 where B\nis singular or not square.");

static PyObject *Unknowns_independence(UnknownsObject *self, PyObject *const *args,
                                       Py_ssize_t nargs) {
    Py_buffer y, Iq, cols, scale, out;
    double t;
    if (unknowns_ready(self) < 0 || check_nargs(nargs, 6, "independence") < 0 ||
        get_double(args[0], &t, "t") < 0)
        return NULL;
    const mb_model *md = &self->model->md;
    if (get_state(md, args[1], &y, 0, 0) < 0) return NULL;
    if (get_coordinates(md, args[2], args[3], &Iq, &cols) < 0) {
        PyBuffer_Release(&y);
        return NULL;
    }
    Py_ssize_t nq = Iq.len / 8 / MB_GQ_W, N = cols.len / 8;
    int ok = get_buffer(args[4], &scale, 0, 1, N, "colscale") == 0;
    if (ok && get_buffer(args[5], &out, 1, 1, self->u.mu + nq + 1, "out") < 0) {
        PyBuffer_Release(&scale);
        ok = 0;
    }
    int status = 0;
    if (ok) {
        status = mb_independence(md, &self->u, self->w, t, y.buf, nq, Iq.buf, N, cols.buf,
                                 scale.buf, out.buf);
        PyBuffer_Release(&out);
        PyBuffer_Release(&scale);
    }
    PyBuffer_Release(&cols);
    PyBuffer_Release(&Iq);
    PyBuffer_Release(&y);
    if (!ok) return NULL;
    if (status < 0) return PyErr_NoMemory();
    Py_RETURN_NONE;
}

PyDoc_STRVAR(generalized_perturbed_doc,
"generalized_perturbed(t, y, lam, Iq, cols, qdot, P, out)\n\nf_q at perturbed states "
"(kernel.h, mb_generalized_perturbed): P (np x 2 nq) rows\n[dq | du]: y's positions moved "
"along T(y) dq, the rates qdot + du; out (np x nq).");

static PyObject *Unknowns_generalized_perturbed(UnknownsObject *self, PyObject *const *args,
                                                Py_ssize_t nargs) {
    Py_buffer y, lam, Iq, cols, qdot, P, out;
    double t;
    if (unknowns_ready(self) < 0 || check_nargs(nargs, 8, "generalized_perturbed") < 0 ||
        get_double(args[0], &t, "t") < 0)
        return NULL;
    const mb_model *md = &self->model->md;
    if (get_state(md, args[1], &y, 0, 0) < 0) return NULL;
    if (get_buffer(args[2], &lam, 0, 1, md->m, "lam") < 0) goto y_;
    if (get_coordinates(md, args[3], args[4], &Iq, &cols) < 0) goto lam_;
    Py_ssize_t nq = Iq.len / 8 / MB_GQ_W, N = cols.len / 8;
    if (get_buffer(args[5], &qdot, 0, 1, nq, "qdot") < 0) goto Iq_;
    if (get_buffer(args[6], &P, 0, 1, -1, "P") < 0) goto qdot_;
    Py_ssize_t np_ = nq > 0 ? P.len / 8 / (2 * nq) : 0;
    if (nq > 0 && P.len / 8 != np_ * 2 * nq) {
        PyErr_SetString(PyExc_ValueError, "P: expected rows of 2 nq values");
        goto P_;
    }
    if (get_buffer(args[7], &out, 1, 1, np_ * nq, "out") < 0) goto P_;
    int status = mb_generalized_perturbed(md, &self->u, self->w, t, y.buf, lam.buf, nq,
                                          Iq.buf, N, cols.buf, qdot.buf, np_, P.buf, out.buf);
    PyBuffer_Release(&out);
    PyBuffer_Release(&P);
    PyBuffer_Release(&qdot);
    PyBuffer_Release(&cols);
    PyBuffer_Release(&Iq);
    PyBuffer_Release(&lam);
    PyBuffer_Release(&y);
    if (status < 0) return PyErr_NoMemory();
    Py_RETURN_NONE;
P_:
    PyBuffer_Release(&P);
qdot_:
    PyBuffer_Release(&qdot);
Iq_:
    PyBuffer_Release(&cols);
    PyBuffer_Release(&Iq);
lam_:
    PyBuffer_Release(&lam);
y_:
    PyBuffer_Release(&y);
    return NULL;
}

PyDoc_STRVAR(differences_doc,
"differences(t, y, lam, Iq, cols, qdot, h, hu, fscale, rounding, skip, out)\n\nThe "
"linearisation's differences (kernel.h, mb_differences): out [K | K_err | D | D_err],\n"
"each nq x nq; h, hu, fscale (nq): position and rate steps, f's magnitudes; skip (nq,\n"
"int64): coordinates known not to enter f.");

static PyObject *Unknowns_differences(UnknownsObject *self, PyObject *const *args,
                                      Py_ssize_t nargs) {
    Py_buffer y, lam, Iq, cols, v[4], skip, out;
    static const char *names[4] = {"qdot", "h", "hu", "fscale"};
    double t, rounding;
    if (unknowns_ready(self) < 0 || check_nargs(nargs, 12, "differences") < 0 ||
        get_double(args[0], &t, "t") < 0 || get_double(args[9], &rounding, "rounding") < 0)
        return NULL;
    const mb_model *md = &self->model->md;
    if (get_state(md, args[1], &y, 0, 0) < 0) return NULL;
    if (get_buffer(args[2], &lam, 0, 1, md->m, "lam") < 0) {
        PyBuffer_Release(&y);
        return NULL;
    }
    if (get_coordinates(md, args[3], args[4], &Iq, &cols) < 0) {
        PyBuffer_Release(&lam);
        PyBuffer_Release(&y);
        return NULL;
    }
    Py_ssize_t nq = Iq.len / 8 / MB_GQ_W, N = cols.len / 8;
    mb_progress signals = {report_progress, NULL};
    int got = 0, ok = 1;
    for (; got < 4; got++)
        if (get_buffer(args[5 + got], &v[got], 0, 1, nq, names[got]) < 0) break;
    int have_skip = 0;
    if (got < 4 || get_buffer(args[10], &skip, 0, 0, nq, "skip") < 0) ok = 0;
    else have_skip = 1;
    if (ok && get_buffer(args[11], &out, 1, 1, 4 * nq * nq, "out") < 0) ok = 0;
    int status = 0;
    if (ok) {
        status = mb_differences(md, &self->u, self->w, t, y.buf, lam.buf, nq, Iq.buf, N,
                                cols.buf, v[0].buf, v[1].buf, v[2].buf, v[3].buf, NULL,
                                rounding, skip.buf, &signals, out.buf);
        PyBuffer_Release(&out);
    }
    if (have_skip) PyBuffer_Release(&skip);
    for (int i = 0; i < got; i++) PyBuffer_Release(&v[i]);
    PyBuffer_Release(&cols);
    PyBuffer_Release(&Iq);
    PyBuffer_Release(&lam);
    PyBuffer_Release(&y);
    if (!ok || status == MB_STOPPED) return NULL;
    if (status < 0) return PyErr_NoMemory();
    Py_RETURN_NONE;
}

PyDoc_STRVAR(linearize_doc,
"linearize(t, y, lam, Iq, cols, scales, quasi, skip, params, out, progress=None)\n\nThe "
"linearisation about (t, y) (kernel.h, mb_linearize): out [generalized's out | K |\nK_err "
"| D | D_err | q'' | left out | A ((2 nq)^2 slot) | info (LINEARIZE_INFO)]; scales\n(nq): 1 "
"or the model's length; quasi, skip (nq, int64); params (LINEARIZE_PARAMS).\nprogress: "
"called as progress(stage, done, total) before each step (STAGE_*);\nan exception it "
"raises, or Ctrl-C, stops the call.");

static PyObject *Unknowns_linearize(UnknownsObject *self, PyObject *const *args,
                                    Py_ssize_t nargs) {
    Py_buffer y, lam, Iq, cols, scales, quasi, skip, params, out;
    double t;
    if (unknowns_ready(self) < 0 || get_double(args[0], &t, "t") < 0) return NULL;
    if (nargs != 10 && nargs != 11) {
        PyErr_Format(PyExc_TypeError, "linearize() takes 10 or 11 arguments (%zd given)",
                     nargs);
        return NULL;
    }
    PyObject *callback = nargs == 11 && args[10] != Py_None ? args[10] : NULL;
    if (callback != NULL && !PyCallable_Check(callback)) {
        PyErr_SetString(PyExc_TypeError, "progress: expected a callable or None");
        return NULL;
    }
    mb_progress progress = {report_progress, callback};
    const mb_model *md = &self->model->md;
    if (get_state(md, args[1], &y, 0, 0) < 0) return NULL;
    if (get_buffer(args[2], &lam, 0, 1, md->m, "lam") < 0) {
        PyBuffer_Release(&y);
        return NULL;
    }
    if (get_coordinates(md, args[3], args[4], &Iq, &cols) < 0) {
        PyBuffer_Release(&lam);
        PyBuffer_Release(&y);
        return NULL;
    }
    Py_ssize_t nq = Iq.len / 8 / MB_GQ_W, N = cols.len / 8;
    int stage = 0, status = 0;
    if (get_buffer(args[5], &scales, 0, 1, nq, "scales") == 0) stage = 1;
    if (stage == 1 && get_buffer(args[6], &quasi, 0, 0, nq, "quasi") == 0) stage = 2;
    if (stage == 2 && get_buffer(args[7], &skip, 0, 0, nq, "skip") == 0) stage = 3;
    if (stage == 3 && get_buffer(args[8], &params, 0, 1, MB_LINEARIZE_PARAMS, "params") == 0)
        stage = 4;
    Py_ssize_t size = N * nq + 2 * N + nq * nq + 4 * nq + MB_GENERALIZED_INFO + 4 * nq * nq +
                      2 * nq + 4 * nq * nq + MB_LINEARIZE_INFO + 22 * nq + 12 * nq * nq;
    if (stage == 4 && get_buffer(args[9], &out, 1, 1, size, "out") == 0) stage = 5;
    if (stage == 5) {
        status = mb_linearize(md, &self->u, self->w, t, y.buf, lam.buf, nq, Iq.buf, N, cols.buf,
                              scales.buf, quasi.buf, skip.buf, params.buf, &progress, out.buf);
        PyBuffer_Release(&out);
    }
    if (stage >= 4) PyBuffer_Release(&params);
    if (stage >= 3) PyBuffer_Release(&skip);
    if (stage >= 2) PyBuffer_Release(&quasi);
    if (stage >= 1) PyBuffer_Release(&scales);
    PyBuffer_Release(&cols);
    PyBuffer_Release(&Iq);
    PyBuffer_Release(&lam);
    PyBuffer_Release(&y);
    if (stage < 5 || status == MB_STOPPED) return NULL;
    if (status < 0) return PyErr_NoMemory();
    Py_RETURN_NONE;
}

/* -- batches: one call, many states ------------------------------------------------ */

/* The optional (F, rows) pair of a batch: F (C x nF float64: models of this structure
 * with other values, pack.py's F of each) and rows (K int64: which F each state uses), or
 * both None. Fills *nrows (0 without them). Returns 0, or -1 with an exception set. */
static int get_values(const ModelObject *model, PyObject *F, PyObject *rows, Py_ssize_t K,
                      Py_buffer *Fv, Py_buffer *rv, int *have) {
    *have = 0;
    if (F == Py_None && rows == Py_None) return 0;
    if (F == Py_None || rows == Py_None) {
        PyErr_SetString(PyExc_ValueError, "F and rows: give both, or neither");
        return -1;
    }
    Py_ssize_t nF = model->F.len / 8;
    if (get_buffer(F, Fv, 0, 1, -1, "F") < 0) return -1;
    if (nF == 0 || Fv->len / 8 % nF != 0) {
        PyErr_Format(PyExc_ValueError, "F: expected rows of %zd values (this model's F), got "
                     "%zd values", nF, Fv->len / 8);
        PyBuffer_Release(Fv);
        return -1;
    }
    Py_ssize_t C = Fv->len / 8 / nF;
    if (get_buffer(rows, rv, 0, 0, K, "rows") < 0) {
        PyBuffer_Release(Fv);
        return -1;
    }
    const int64_t *r = rv->buf;
    for (Py_ssize_t k = 0; k < K; k++)
        if (r[k] < 0 || r[k] >= C) {
            PyErr_Format(PyExc_ValueError, "rows[%zd] = %lld: F has %zd rows", k,
                         (long long)r[k], C);
            PyBuffer_Release(Fv);
            PyBuffer_Release(rv);
            return -1;
        }
    *have = 1;
    return 0;
}

/* The model state k is evaluated with: md itself, or md rebased onto F[rows[k]]. */
static const mb_model *model_of(const ModelObject *model, mb_model *scratch, int have,
                                const Py_buffer *Fv, const Py_buffer *rv, Py_ssize_t k) {
    if (!have) return &model->md;
    Py_ssize_t nF = model->F.len / 8;
    const double *F = (const double *)Fv->buf + nF * ((const int64_t *)rv->buf)[k];
    mb_model_rebase(scratch, &model->md, model->F.buf, F);
    return scratch;
}

PyDoc_STRVAR(solve_many_doc,
"solve_many(t, Y, lam, out, F, rows, states)\n\nsolve() at K states in one call: t (K), "
"Y (S x ys: states packed, ys = 13 n\nor state_size), lam (m: the known values of every "
"state, or K x m: each its own),\nout (K x L: each state's solve() output, L = "
"solve_layout's info offset + INFO).\nstates (K int64): state k is Y[states[k]]; or None: "
"Y[k] (then S = K). F (C x nF)\nand rows (K): state k evaluated with the model of the same "
"structure whose packed\nF is F[rows[k]] (pack_model of a model whose I equals this "
"one's); or None and None:\nthis model.");

static PyObject *Unknowns_solve_many(UnknownsObject *self, PyObject *const *args,
                                     Py_ssize_t nargs) {
    Py_buffer t, Y, lam, out, Fv, rv, sv;
    int have = 0, have_states = 0;
    if (unknowns_ready(self) < 0 || check_nargs(nargs, 7, "solve_many") < 0) return NULL;
    const mb_model *md = &self->model->md;
    if (get_buffer(args[0], &t, 0, 1, -1, "t") < 0) return NULL;
    Py_ssize_t K = t.len / 8;
    Py_ssize_t full = MB_STATE_SIZE(md->n, md->planar), ys = full;
    Py_ssize_t N = (md->planar ? 3 : 6) * md->n, L = N + 3 * md->m + MB_INFO;
    PyObject *result = NULL;
    if (get_buffer(args[1], &Y, 0, 1, -1, "Y") < 0) goto t_;
    if (args[6] != Py_None) {
        if (get_buffer(args[6], &sv, 0, 0, K, "states") < 0) goto states_;
        have_states = 1;
    }
    Py_ssize_t S = have_states ? -1 : K; /* states packed in Y */
    {
        Py_ssize_t nY = Y.len / 8;
        if (S < 0) { /* a 2-D Y: its rows are the states, of full or 13 n values */
            Py_ssize_t width = Y.ndim == 2 ? Y.shape[1] : -1;
            if (width == full || width == 13 * md->n) ys = width, S = Y.shape[0];
        } else if (nY != S * full) {
            ys = 13 * md->n;
        }
        if (S < 0 || (S > 0 && nY != S * ys) || (S == 0 && nY != 0)) {
            PyErr_Format(PyExc_ValueError, "Y: expected %zd states of %zd (or %zd) values, "
                         "got %zd values", S < 0 ? K : S, full, (Py_ssize_t)(13 * md->n), nY);
            goto states_;
        }
        if (have_states) {
            const int64_t *st = sv.buf;
            for (Py_ssize_t k = 0; k < K; k++)
                if (st[k] < 0 || st[k] >= S) {
                    PyErr_Format(PyExc_ValueError, "states[%zd] = %lld: Y holds %zd states",
                                 k, (long long)st[k], S);
                    goto states_;
                }
        }
    }
    if (get_buffer(args[2], &lam, 0, 1, -1, "lam") < 0) goto states_;
    Py_ssize_t nl = lam.len / 8;
    if (nl != md->m && nl != K * md->m) {
        PyErr_Format(PyExc_ValueError, "lam: expected %lld or %zd values, got %zd",
                     (long long)md->m, K * md->m, nl);
        goto lam_;
    }
    if (get_buffer(args[3], &out, 1, 1, K * L, "out") < 0) goto lam_;
    if (get_values(self->model, args[4], args[5], K, &Fv, &rv, &have) < 0) goto out_;
    {
        mb_model scratch;
        const double *tv = t.buf, *yv = Y.buf, *lv = lam.buf;
        double *ov = out.buf;
        int per_state = nl != md->m; /* K x m (with K = 1 either reads the same) */
        const int64_t *st = have_states ? sv.buf : NULL;
        for (Py_ssize_t k = 0; k < K; k++) {
            const mb_model *mk = model_of(self->model, &scratch, have, &Fv, &rv, k);
            mb_solve(mk, &self->u, self->w, tv[k], yv + (st ? st[k] : k) * ys,
                     lv + (per_state ? k * md->m : 0), ov + k * L);
        }
    }
    if (have) {
        PyBuffer_Release(&Fv);
        PyBuffer_Release(&rv);
    }
    Py_INCREF(Py_None);
    result = Py_None;
out_:
    PyBuffer_Release(&out);
lam_:
    PyBuffer_Release(&lam);
states_:
    if (have_states) PyBuffer_Release(&sv);
    PyBuffer_Release(&Y);
t_:
    PyBuffer_Release(&t);
    return result;
}

PyDoc_STRVAR(peaks_many_doc,
"peaks_many(t, Y, lam, peaks, F, rows, states, segment)\n\nsolve_many's solves, each "
"state's output folded into its segment's row of peaks\ninstead of written out: state k "
"is in segment k // segment; peaks (K / segment x\n(m + 1)) <- per segment the largest "
"|lambda_i| of each reaction component (known\nvalues included), then the first nonzero "
"singular code of its states (0: none). t,\nY, lam, F, rows, states: as solve_many's (K "
"a multiple of segment).");

static PyObject *Unknowns_peaks_many(UnknownsObject *self, PyObject *const *args,
                                     Py_ssize_t nargs) {
    Py_buffer t, Y, lam, pk, Fv, rv, sv;
    int have = 0, have_states = 0;
    if (unknowns_ready(self) < 0 || check_nargs(nargs, 8, "peaks_many") < 0) return NULL;
    const mb_model *md = &self->model->md;
    long segment = PyLong_AsLong(args[7]);
    if (segment == -1 && PyErr_Occurred()) return NULL;
    if (get_buffer(args[0], &t, 0, 1, -1, "t") < 0) return NULL;
    Py_ssize_t K = t.len / 8, S = 0, ys = MB_STATE_SIZE(md->n, md->planar);
    Py_ssize_t N = (md->planar ? 3 : 6) * md->n, L = N + 3 * md->m + MB_INFO;
    PyObject *result = NULL;
    if (segment < 1 || K % segment != 0) {
        PyErr_Format(PyExc_ValueError, "segment: expected a divisor of the %zd states, got %ld",
                     K, segment);
        goto t_;
    }
    if (get_buffer(args[1], &Y, 0, 1, -1, "Y") < 0) goto t_;
    if (args[6] == Py_None) {
        PyErr_SetString(PyExc_ValueError, "states: expected K int64 indices into Y");
        goto Y_;
    }
    if (get_buffer(args[6], &sv, 0, 0, K, "states") < 0) goto Y_;
    have_states = 1;
    {
        Py_ssize_t width = Y.ndim == 2 ? Y.shape[1] : -1;
        if (width != ys && width != 13 * md->n) {
            PyErr_Format(PyExc_ValueError, "Y: expected rows of %zd (or %zd) values", ys,
                         (Py_ssize_t)(13 * md->n));
            goto states_;
        }
        ys = width, S = Y.shape[0];
        const int64_t *st = sv.buf;
        for (Py_ssize_t k = 0; k < K; k++)
            if (st[k] < 0 || st[k] >= S) {
                PyErr_Format(PyExc_ValueError, "states[%zd] = %lld: Y holds %zd states", k,
                             (long long)st[k], S);
                goto states_;
            }
    }
    if (get_buffer(args[2], &lam, 0, 1, md->m, "lam") < 0) goto states_;
    if (get_buffer(args[3], &pk, 1, 1, (K / segment) * (md->m + 1), "peaks") < 0) goto lam_;
    if (get_values(self->model, args[4], args[5], K, &Fv, &rv, &have) < 0) goto pk_;
    {
        double *out = malloc(sizeof(double) * (size_t)L);
        if (out == NULL) {
            PyErr_NoMemory();
            goto values_;
        }
        mb_model scratch;
        const double *tv = t.buf, *yv = Y.buf;
        const int64_t *st = sv.buf;
        double *pv = pk.buf;
        int64_t m = md->m;
        for (Py_ssize_t k = 0; k < K; k++) {
            double *row = pv + (k / segment) * (m + 1);
            if (k % segment == 0)
                for (int64_t i = 0; i <= m; i++) row[i] = 0.0;
            const mb_model *mk = model_of(self->model, &scratch, have, &Fv, &rv, k);
            mb_solve(mk, &self->u, self->w, tv[k], yv + st[k] * ys, lam.buf, out);
            for (int64_t i = 0; i < m; i++) {
                double a = fabs(out[N + i]);
                if (!(a <= row[i])) row[i] = a; /* a NaN stays */
            }
            double code = out[N + 3 * m + MB_ST_SINGULAR];
            if (row[m] == 0.0 && code != 0.0) row[m] = code;
        }
        free(out);
    }
    Py_INCREF(Py_None);
    result = Py_None;
values_:
    if (have) {
        PyBuffer_Release(&Fv);
        PyBuffer_Release(&rv);
    }
pk_:
    PyBuffer_Release(&pk);
lam_:
    PyBuffer_Release(&lam);
states_:
    if (have_states) PyBuffer_Release(&sv);
Y_:
    PyBuffer_Release(&Y);
t_:
    PyBuffer_Release(&t);
    return result;
}

PyDoc_STRVAR(kinematics_many_doc,
"kinematics_many(t, Y, F, rows, chain, phi_scale, settings, info)\n\nThe kinematic "
"analysis (kernel.h: mb_kinematics) at K times, in place: Y (K x\nstate_size, each row "
"its start; moved onto every enforced joint and driver at\nt[k]). chain (K int64): 1 where "
"row k starts from row k - 1's result (copied\nthere), moved along its velocities for "
"t[k] - t[k-1] when settings' predict is\nset; or None. F, rows: as solve_many's. "
"phi_scale (m): each component's scale\n(lengths: the model's size; angles: 1). settings "
"(6): [max_iters, step_tol,\nphi_tol, robust_below, fast, predict]. info (K x KN_INFO) <- "
"each row's\n[steps, max |phi| / scale, singular code, last step].");

static PyObject *Unknowns_kinematics_many(UnknownsObject *self, PyObject *const *args,
                                          Py_ssize_t nargs) {
    Py_buffer t, Y, Fv, rv, ch, sc, st, info;
    int have = 0, have_chain = 0;
    if (unknowns_ready(self) < 0 || check_nargs(nargs, 8, "kinematics_many") < 0) return NULL;
    const mb_model *md = &self->model->md;
    if (get_buffer(args[0], &t, 0, 1, -1, "t") < 0) return NULL;
    Py_ssize_t K = t.len / 8, ys = MB_STATE_SIZE(md->n, md->planar);
    PyObject *result = NULL;
    if (get_buffer(args[1], &Y, 1, 1, K * ys, "Y") < 0) goto t_;
    if (get_values(self->model, args[2], args[3], K, &Fv, &rv, &have) < 0) goto Y_;
    if (args[4] != Py_None) {
        if (get_buffer(args[4], &ch, 0, 0, K, "chain") < 0) goto values_;
        have_chain = 1;
    }
    if (get_buffer(args[5], &sc, 0, 1, md->m, "phi_scale") < 0) goto chain_;
    if (get_buffer(args[6], &st, 0, 1, 6, "settings") < 0) goto scale_;
    if (get_buffer(args[7], &info, 1, 1, K * MB_KN_INFO, "info") < 0) goto settings_;
    {
        const double *s = st.buf;
        if (!(s[0] >= 0 && s[0] <= 1000)) {
            PyErr_SetString(PyExc_ValueError, "settings[0] (max_iters): expected 0 to 1000");
            goto info_;
        }
        mb_model scratch;
        const double *tv = t.buf;
        const int64_t *cv = have_chain ? ch.buf : NULL;
        double *yv = Y.buf, *iv = info.buf;
        int fast = s[4] != 0.0, predict = s[5] != 0.0;
        for (Py_ssize_t k = 0; k < K; k++) {
            double *y = yv + k * ys;
            if (cv != NULL && cv[k] && k > 0) {
                memcpy(y, y - ys, sizeof(double) * ys);
                if (predict) mb_predict(md, y, tv[k] - tv[k - 1]);
            }
            const mb_model *mk = model_of(self->model, &scratch, have, &Fv, &rv, k);
            mb_kinematics(mk, &self->u, self->w, tv[k], y, sc.buf, (int)s[0], s[1], s[2],
                          s[3], fast, iv + k * MB_KN_INFO);
        }
    }
    Py_INCREF(Py_None);
    result = Py_None;
info_:
    PyBuffer_Release(&info);
settings_:
    PyBuffer_Release(&st);
scale_:
    PyBuffer_Release(&sc);
chain_:
    if (have_chain) PyBuffer_Release(&ch);
values_:
    if (have) {
        PyBuffer_Release(&Fv);
        PyBuffer_Release(&rv);
    }
Y_:
    PyBuffer_Release(&Y);
t_:
    PyBuffer_Release(&t);
    return result;
}

static PyObject *Unknowns_get(UnknownsObject *self, void *which) {
    switch ((int)(intptr_t)which) {
    case 0: return PyLong_FromLongLong(self->u.mu);
    case 1: return PyLong_FromLongLong(self->u.bw);
    default: Py_INCREF(self->model); return (PyObject *)self->model;
    }
}

static PyGetSetDef Unknowns_getset[] = {
    {"mu", (getter)Unknowns_get, NULL, "number of unknown components", (void *)0},
    {"bw", (getter)Unknowns_get, NULL, "half bandwidth of S in the unknowns' order", (void *)1},
    {"model", (getter)Unknowns_get, NULL, "the Model", (void *)2},
    {"generic_rank", (getter)Unknowns_get_generic_rank, NULL,
     "the rank G_U has at generic configurations (set_generic_rank)", NULL},
    {NULL, NULL, NULL, NULL, NULL},
};

static PyMethodDef Unknowns_methods[] = {
    {"solve", (PyCFunction)(void (*)(void))Unknowns_solve, METH_FASTCALL, solve_doc},
    {"set_generic_rank", (PyCFunction)Unknowns_set_generic_rank, METH_O, set_generic_rank_doc},
    {"solve_given", (PyCFunction)(void (*)(void))Unknowns_solve_given, METH_FASTCALL,
     solve_given_doc},
    {"derivative", (PyCFunction)(void (*)(void))Unknowns_derivative, METH_FASTCALL, derivative_doc},
    {"project", (PyCFunction)(void (*)(void))Unknowns_project, METH_FASTCALL, project_doc},
    {"kinematic_run", (PyCFunction)(void (*)(void))Unknowns_kinematic_run, METH_FASTCALL,
     kinematic_run_doc},
    {"energy_samples", (PyCFunction)(void (*)(void))Unknowns_energy_samples, METH_FASTCALL,
     energy_samples_doc},
    {"schur", (PyCFunction)(void (*)(void))Unknowns_schur, METH_FASTCALL, schur_doc},
    {"generalized", (PyCFunction)(void (*)(void))Unknowns_generalized, METH_FASTCALL,
     generalized_doc},
    {"independence", (PyCFunction)(void (*)(void))Unknowns_independence, METH_FASTCALL,
     independence_doc},
    {"generalized_perturbed", (PyCFunction)(void (*)(void))Unknowns_generalized_perturbed,
     METH_FASTCALL, generalized_perturbed_doc},
    {"differences", (PyCFunction)(void (*)(void))Unknowns_differences, METH_FASTCALL,
     differences_doc},
    {"linearize", (PyCFunction)(void (*)(void))Unknowns_linearize, METH_FASTCALL,
     linearize_doc},
    {"solve_many", (PyCFunction)(void (*)(void))Unknowns_solve_many, METH_FASTCALL,
     solve_many_doc},
    {"kinematics_many", (PyCFunction)(void (*)(void))Unknowns_kinematics_many, METH_FASTCALL,
     kinematics_many_doc},
    {"peaks_many", (PyCFunction)(void (*)(void))Unknowns_peaks_many, METH_FASTCALL,
     peaks_many_doc},
    {NULL, NULL, 0, NULL},
};

PyDoc_STRVAR(Unknowns_doc,
"Unknowns(model, Iu)\n\nThe unknown reaction components of one solve "
"(mbody.equations.pack.pack_unknowns),\nwith the scratch memory of its evaluations "
"(allocated once). A ValueError when Iu\ndoes not describe unknowns of this model.");

static PyTypeObject UnknownsType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "mbody.kernel._core.Unknowns",
    .tp_basicsize = sizeof(UnknownsObject),
    .tp_dealloc = (destructor)Unknowns_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = Unknowns_doc,
    .tp_methods = Unknowns_methods,
    .tp_getset = Unknowns_getset,
    .tp_init = (initproc)Unknowns_init,
    .tp_new = PyType_GenericNew,
};

/* For the integrator's module (dop853_module.c): the model, unknowns and scratch of an
 * initialised Unknowns object (1), or 0 when obj is not one. */
int mb_unknowns_object(PyObject *obj, const mb_model **md, const mb_unknowns **u,
                       mb_work **w) {
    if (!PyObject_TypeCheck(obj, &UnknownsType)) return 0;
    UnknownsObject *self = (UnknownsObject *)obj;
    if (self->w == NULL) return 0;
    *md = &self->model->md;
    *u = &self->u;
    *w = self->w;
    return 1;
}

/* -- module -------------------------------------------------------------------------- */

PyDoc_STRVAR(solve_layout_doc,
"solve_layout(n, m, planar) -> (N, lam, info)\n\nWhere Unknowns.solve writes into out: "
"N accelerations, lambda (m) at offset lam,\nthen G^T v (m) and the not-unique flags (m), "
"info (INFO values) at offset info.");

static PyObject *solve_layout(PyObject *mod, PyObject *args) {
    long long n, m;
    int planar;
    if (!PyArg_ParseTuple(args, "LLp", &n, &m, &planar)) return NULL;
    long long N = (planar ? 3 : 6) * n;
    return Py_BuildValue("(LLL)", N, N, N + 3 * m);
}

PyDoc_STRVAR(pack_unknowns_doc,
"pack_unknowns(child, parent, n, U, out) -> int\n\nIu (kernel.h) of the components U "
"(int64, in solve order), from every component's\nchild and parent body (int64, m each; "
"-1 the ground) among n bodies, into out (int64,\nat least 3 + 5 mu + n + 1 values). "
"Returns the length of Iu; a ValueError when an\nindex is out of range.");

static PyObject *pack_unknowns(PyObject *mod, PyObject *const *args, Py_ssize_t nargs) {
    Py_buffer child, parent, U, out;
    if (check_nargs(nargs, 5, "pack_unknowns") < 0) return NULL;
    long long n = PyLong_AsLongLong(args[2]);
    if (n == -1 && PyErr_Occurred()) return NULL;
    if (get_buffer(args[0], &child, 0, 0, -1, "child") < 0) return NULL;
    if (get_buffer(args[1], &parent, 0, 0, child.len / 8, "parent") < 0) {
        PyBuffer_Release(&child);
        return NULL;
    }
    if (get_buffer(args[3], &U, 0, 0, -1, "U") < 0) {
        PyBuffer_Release(&parent);
        PyBuffer_Release(&child);
        return NULL;
    }
    int64_t mu = U.len / 8;
    if (get_buffer(args[4], &out, 1, 0, -1, "out") < 0) {
        PyBuffer_Release(&U);
        PyBuffer_Release(&parent);
        PyBuffer_Release(&child);
        return NULL;
    }
    /* n and mu bounded by out's size first: then the sum cannot overflow */
    Py_ssize_t have = out.len / 8;
    int room = n >= 0 && n <= have && mu <= have && 4 + 5 * mu + n <= have;
    /* out is written while the inputs are read again: they may not share its memory */
    const char *o0 = out.buf, *o1 = o0 + out.len;
    int apart = 1;
    const Py_buffer *ins[3] = {&child, &parent, &U};
    for (int i = 0; i < 3; i++) {
        const char *a0 = ins[i]->buf, *a1 = a0 + ins[i]->len;
        if (a0 < o1 && o0 < a1) apart = 0;
    }
    int64_t used = room && apart ? mb_pack_unknowns(child.buf, parent.buf, child.len / 8, n,
                                                    U.buf, mu, out.buf)
                                 : -1;
    PyBuffer_Release(&out);
    PyBuffer_Release(&U);
    PyBuffer_Release(&parent);
    PyBuffer_Release(&child);
    if (n < 0) return PyErr_Format(PyExc_ValueError, "n: expected n >= 0 bodies, got %lld", n);
    if (!room)
        return PyErr_Format(PyExc_ValueError, "out: expected at least 3 + 5 mu + n + 1 values "
                            "for n = %lld bodies and mu = %lld unknowns, got %zd", n,
                            (long long)mu, have);
    if (!apart)
        return PyErr_Format(PyExc_ValueError, "out: shares memory with child, parent or U");
    if (used == -2) return PyErr_NoMemory();
    if (used < 0)
        return PyErr_Format(PyExc_ValueError, "U, child or parent: an index out of range "
                            "(U in 0..m-1, bodies in -1..n-1)");
    return PyLong_FromLongLong(used);
}

PyDoc_STRVAR(spectrum_doc,
"spectrum(A, dA, tol, out) -> int\n\nThe eigenvalues, unit right eigenvectors and error "
"bounds of the\nsquare float64 matrix A (kernel.h, mb_spectrum), into out (float64, "
"2 n + 2 n^2 + n:\nview a complex array of n + n^2 + n entries as float64). Returns 0, "
"or 1 when the\nQR iteration did not converge.");

static PyObject *spectrum(PyObject *mod, PyObject *const *args, Py_ssize_t nargs) {
    Py_buffer A, out;
    double dA, tol;
    if (check_nargs(nargs, 4, "spectrum") < 0 || get_double(args[1], &dA, "dA") < 0 ||
        get_double(args[2], &tol, "tol") < 0 || get_buffer(args[0], &A, 0, 1, -1, "A") < 0)
        return NULL;
    Py_ssize_t n = (Py_ssize_t)floor(sqrt((double)(A.len / 8)) + 0.5);
    if (n * n != A.len / 8) {
        PyBuffer_Release(&A);
        return PyErr_Format(PyExc_ValueError, "A: expected a square matrix, got %zd values",
                            A.len / 8);
    }
    if (get_buffer(args[3], &out, 1, 1, 2 * n + 2 * n * n + n, "out") < 0) {
        PyBuffer_Release(&A);
        return NULL;
    }
    mb_progress signals = {report_progress, NULL};
    int status = mb_spectrum(A.buf, n, dA, tol, &signals, out.buf);
    PyBuffer_Release(&out);
    PyBuffer_Release(&A);
    if (status == MB_STOPPED) return NULL;
    if (status < 0) return PyErr_NoMemory();
    return PyLong_FromLong(status);
}

PyDoc_STRVAR(modes_doc,
"modes(spectrum, k, kept, out) -> int\n\nThe modes of spectrum()'s out for k coordinates, "
"the kept ones' indices in\nkept (int64) (kernel.h, mb_modes), into out (float64, "
"MODE_W n + 2 n k). Returns their\nnumber m.");

static PyObject *modes(PyObject *mod, PyObject *const *args, Py_ssize_t nargs) {
    Py_buffer spec, kept, out;
    long long k;
    if (check_nargs(nargs, 4, "modes") < 0) return NULL;
    k = PyLong_AsLongLong(args[1]);
    if (k == -1 && PyErr_Occurred()) return NULL;
    if (k < 0) return PyErr_Format(PyExc_ValueError, "k: expected k >= 0");
    if (get_buffer(args[0], &spec, 0, 1, -1, "spectrum") < 0) return NULL;
    Py_ssize_t len = spec.len / 8;
    Py_ssize_t n = (Py_ssize_t)floor((sqrt(9.0 + 8.0 * (double)len) - 3.0) / 4.0 + 0.5);
    if (3 * n + 2 * n * n != len) {
        PyBuffer_Release(&spec);
        return PyErr_Format(PyExc_ValueError, "spectrum: expected 3 n + 2 n^2 values, got %zd",
                            len);
    }
    if (get_buffer(args[2], &kept, 0, 0, -1, "kept") < 0) {
        PyBuffer_Release(&spec);
        return NULL;
    }
    Py_ssize_t nk = kept.len / 8;
    const int64_t *kp = kept.buf;
    int bad = nk > n || nk > k;
    for (Py_ssize_t j = 0; j < nk && !bad; j++) bad = kp[j] < 0 || kp[j] >= k;
    if (bad || n - nk != k) {
        PyBuffer_Release(&kept);
        PyBuffer_Release(&spec);
        return PyErr_Format(PyExc_ValueError,
                            "kept: expected indices below k = %lld, and n = kept + k", k);
    }
    if (get_buffer(args[3], &out, 1, 1, MB_MODE_W * n + 2 * n * k, "out") < 0) {
        PyBuffer_Release(&kept);
        PyBuffer_Release(&spec);
        return NULL;
    }
    int64_t m = mb_modes(n, spec.buf, k, nk, kp, out.buf);
    PyBuffer_Release(&out);
    PyBuffer_Release(&kept);
    PyBuffer_Release(&spec);
    if (m < 0) return PyErr_NoMemory();
    return PyLong_FromLongLong(m);
}

/* The DOP853 integrator's entry points (dop853_module.c). */
int mb_dop853_register(PyObject *m);

static PyMethodDef methods[] = {
    {"solve_layout", solve_layout, METH_VARARGS, solve_layout_doc},
    {"pack_unknowns", (PyCFunction)(void (*)(void))pack_unknowns, METH_FASTCALL,
     pack_unknowns_doc},
    {"spectrum", (PyCFunction)(void (*)(void))spectrum, METH_FASTCALL, spectrum_doc},
    {"modes", (PyCFunction)(void (*)(void))modes, METH_FASTCALL, modes_doc},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "_core",
    "mbody's compiled core (kernel.h): Model, Unknowns, solve_layout and the layout "
    "constants.", -1, methods, NULL, NULL, NULL, NULL,
};

PyMODINIT_FUNC PyInit__core(void) {
    if (PyType_Ready(&ModelType) < 0 || PyType_Ready(&UnknownsType) < 0) return NULL;
    PyObject *m = PyModule_Create(&module);
    if (m == NULL) return NULL;
    struct { const char *name; long value; } constants[] = {
        {"KIND_FORCE", MB_KIND_FORCE}, {"KIND_TILT", MB_KIND_TILT}, {"KIND_LOCK", MB_KIND_LOCK},
        {"KIND_RIGHT_ANGLE", MB_KIND_RIGHT_ANGLE}, {"KIND_LINK", MB_KIND_LINK},
        {"KIND_TURN", MB_KIND_TURN}, {"KIND_SCREW", MB_KIND_SCREW}, {"KINDS", MB_KINDS},
        {"I_HEADER", MB_I_HEADER}, {"BODY_W", MB_BODY_W}, {"LOAD_W", MB_LOAD_W},
        {"SPRING_W", MB_SPRING_W}, {"JOINT_W", MB_JOINT_W}, {"COMP_W", MB_COMP_W},
        {"J_LINK", MB_J_LINK}, {"J_PARTICLE_PARENT", MB_J_PARTICLE_PARENT},
        {"OP_NUM", MB_OP_NUM}, {"OP_T", MB_OP_T}, {"OP_NEG", MB_OP_NEG}, {"OP_ADD", MB_OP_ADD},
        {"OP_SUB", MB_OP_SUB}, {"OP_MUL", MB_OP_MUL}, {"OP_DIV", MB_OP_DIV},
        {"OP_POW", MB_OP_POW}, {"OP_SIN", MB_OP_SIN}, {"OP_COS", MB_OP_COS},
        {"OP_TAN", MB_OP_TAN}, {"OP_EXP", MB_OP_EXP}, {"OP_LOG", MB_OP_LOG},
        {"OP_SQRT", MB_OP_SQRT}, {"OP_ABS", MB_OP_ABS},
        {"ST_RANK", MB_ST_RANK}, {"ST_BERR", MB_ST_BERR}, {"ST_BROKEN", MB_ST_BROKEN},
        {"ST_MU", MB_ST_MU}, {"ST_PATH", MB_ST_PATH}, {"ST_SINGULAR", MB_ST_SINGULAR},
        {"INFO", MB_INFO}, {"PR_STEP", MB_PR_STEP}, {"PR_VELOCITY", MB_PR_VELOCITY},
        {"PR_RATIO", MB_PR_RATIO}, {"PR_SINGULAR", MB_PR_SINGULAR},
        {"PROJECT_INFO", MB_PROJECT_INFO}, {"KN_ITERS", MB_KN_ITERS},
        {"KN_ERROR", MB_KN_ERROR}, {"KN_SINGULAR", MB_KN_SINGULAR}, {"KN_STEP", MB_KN_STEP},
        {"KN_INFO", MB_KN_INFO},
        {"KR_STEP", MB_KR_STEP}, {"KR_NEWTON", MB_KR_NEWTON}, {"KR_WORST", MB_KR_WORST},
        {"KR_SINGULAR", MB_KR_SINGULAR}, {"KR_INFO", MB_KR_INFO},
        {"GQ_TURN", MB_GQ_TURN}, {"GQ_CHILD_TURN", MB_GQ_CHILD_TURN},
        {"GQ_SLIDE", MB_GQ_SLIDE}, {"GQ_BODY", MB_GQ_BODY}, {"GQ_W", MB_GQ_W},
        {"GI_RANK", MB_GI_RANK}, {"GI_RESIDUAL", MB_GI_RESIDUAL},
        {"GENERALIZED_INFO", MB_GENERALIZED_INFO},
        {"LP_STEP", MB_LP_STEP}, {"LP_ROUNDING", MB_LP_ROUNDING}, {"LP_STEADY", MB_LP_STEADY},
        {"LP_MOVING", MB_LP_MOVING}, {"LP_STOP", MB_LP_STOP},
        {"STOP_NONE", MB_STOP_NONE}, {"STOP_STIFFNESS", MB_STOP_STIFFNESS},
        {"STOP_SYSTEM", MB_STOP_SYSTEM},
        {"LINEARIZE_PARAMS", MB_LINEARIZE_PARAMS},
        {"LI_STEADY", MB_LI_STEADY}, {"LI_UNSTEADY", MB_LI_UNSTEADY}, {"LI_TOL", MB_LI_TOL},
        {"LI_KEPT", MB_LI_KEPT}, {"LI_SINGULAR", MB_LI_SINGULAR}, {"LI_DA", MB_LI_DA},
        {"LI_NORM", MB_LI_NORM}, {"LI_RESTING", MB_LI_RESTING},
        {"LI_GROWING", MB_LI_GROWING}, {"LI_MODES", MB_LI_MODES},
        {"LI_UNCONVERGED", MB_LI_UNCONVERGED}, {"LI_OSCILLATIONS", MB_LI_OSCILLATIONS},
        {"MODE_INDEX", MB_MODE_INDEX}, {"MODE_KIND", MB_MODE_KIND}, {"MODE_RE", MB_MODE_RE},
        {"MODE_IM", MB_MODE_IM}, {"MODE_FREQUENCY", MB_MODE_FREQUENCY},
        {"MODE_DAMPING", MB_MODE_DAMPING}, {"MODE_W", MB_MODE_W},
        {"MODE_NEUTRAL", MB_MODE_NEUTRAL}, {"MODE_OSCILLATION", MB_MODE_OSCILLATION},
        {"MODE_GROWTH", MB_MODE_GROWTH}, {"MODE_DECAY", MB_MODE_DECAY},
        {"LINEARIZE_INFO", MB_LINEARIZE_INFO},
        {"STAGE_GENERALIZED", MB_STAGE_GENERALIZED}, {"STAGE_DAMPING", MB_STAGE_DAMPING},
        {"STAGE_STIFFNESS", MB_STAGE_STIFFNESS}, {"STAGE_SYSTEM", MB_STAGE_SYSTEM},
        {"STAGE_HESSENBERG", MB_STAGE_HESSENBERG}, {"STAGE_SCHUR", MB_STAGE_SCHUR},
        {"STAGE_VECTORS", MB_STAGE_VECTORS}, {"STAGES", MB_STAGES},
    };
    for (size_t i = 0; i < sizeof(constants) / sizeof(constants[0]); i++)
        if (PyModule_AddIntConstant(m, constants[i].name, constants[i].value) < 0) goto fail;
    Py_INCREF(&ModelType);
    if (PyModule_AddObject(m, "Model", (PyObject *)&ModelType) < 0) goto fail;
    Py_INCREF(&UnknownsType);
    if (PyModule_AddObject(m, "Unknowns", (PyObject *)&UnknownsType) < 0) goto fail;
    if (mb_dop853_register(m) < 0) goto fail;
    return m;
fail:
    Py_DECREF(m);
    return NULL;
}
