/* The Python module mbody.kernel._core: the buffers of the packed model handed to the
 * kernel's functions (kernel.h). */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include "kernel.h"

/* The DOP853 integrator's entry points (dop853_module.c). */
int mb_dop853_register(PyObject *m);

static PyMethodDef methods[] = {
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "_core", "mbody's compiled core (kernel.h).", -1, methods,
};

PyMODINIT_FUNC PyInit__core(void) {
    PyObject *m = PyModule_Create(&module);
    if (m == NULL) return NULL;
    if (PyModule_AddIntConstant(m, "KINDS", MB_KINDS) < 0) return NULL;
    if (mb_dop853_register(m) < 0) return NULL;
    return m;
}
