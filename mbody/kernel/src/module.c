/* The Python module mbody.kernel._core: the buffers of the packed model handed to the
 * kernel's functions (kernel.h). */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include "kernel.h"

static PyMethodDef methods[] = {
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "_core", "mbody's compiled core (kernel.h).", -1, methods,
};

PyMODINIT_FUNC PyInit__core(void) {
    PyObject *m = PyModule_Create(&module);
    if (m == NULL) return NULL;
    /* the constraint primitives (kernel.h), named as mbody.joints reads them */
    if (PyModule_AddIntConstant(m, "KIND_FORCE", MB_KIND_FORCE) < 0
        || PyModule_AddIntConstant(m, "KIND_TILT", MB_KIND_TILT) < 0
        || PyModule_AddIntConstant(m, "KIND_LOCK", MB_KIND_LOCK) < 0
        || PyModule_AddIntConstant(m, "KIND_RIGHT_ANGLE", MB_KIND_RIGHT_ANGLE) < 0
        || PyModule_AddIntConstant(m, "KIND_LINK", MB_KIND_LINK) < 0
        || PyModule_AddIntConstant(m, "KIND_TURN", MB_KIND_TURN) < 0
        || PyModule_AddIntConstant(m, "KIND_SCREW", MB_KIND_SCREW) < 0
        || PyModule_AddIntConstant(m, "KINDS", MB_KINDS) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
