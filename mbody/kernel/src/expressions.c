/* Expressions of time t: postfix programs (MB_OP_* codes, those of
 * mbody.model.expressions.PROGRAM_CODES) evaluated as numpy would (out of a function's
 * domain: inf or nan), and what they set at t: the varying load entries, the laws of
 * driven components, the known reactions that vary in t. */
#include <stdlib.h>

#include "internal.h"

static double run_program(const mb_model *md, int64_t e, double t, double *stack) {
    int64_t top = 0;
    for (int64_t p = md->starts[e]; p < md->starts[e + 1]; p++) {
        int64_t c = md->codes[p];
        if (c == MB_OP_NUM) {
            stack[top++] = md->numbers[p];
        } else if (c == MB_OP_T) {
            stack[top++] = t;
        } else if (c == MB_OP_NEG) {
            stack[top - 1] = -stack[top - 1];
        } else if (c <= MB_OP_POW) {
            double a = stack[top - 2], b = stack[top - 1];
            top--;
            switch (c) {
            case MB_OP_ADD: stack[top - 1] = a + b; break;
            case MB_OP_SUB: stack[top - 1] = a - b; break;
            case MB_OP_MUL: stack[top - 1] = a * b; break;
            case MB_OP_DIV: stack[top - 1] = a / b; break;
            default: stack[top - 1] = pow(a, b); break;
            }
        } else {
            double a = stack[top - 1], r;
            switch (c) {
            case MB_OP_SIN: r = sin(a); break;
            case MB_OP_COS: r = cos(a); break;
            case MB_OP_TAN: r = tan(a); break;
            case MB_OP_EXP: r = exp(a); break;
            case MB_OP_LOG: r = a >= 0.0 ? log(a) : NAN; break;
            case MB_OP_SQRT: r = a >= 0.0 ? sqrt(a) : NAN; break;
            default: r = fabs(a); break;
            }
            stack[top - 1] = r;
        }
    }
    return stack[0];
}

double mb_expression(const mb_model *md, int64_t e, double t) {
    /* a private stack: the deepest program is at most n_code deep */
    double small[64];
    int64_t len = md->starts[e + 1] - md->starts[e];
    if (len <= 64) return run_program(md, e, t, small);
    double *stack = malloc((size_t)len * sizeof(double));
    if (stack == NULL) return NAN;
    double r = run_program(md, e, t, stack);
    free(stack);
    return r;
}

void mb_eval_all(const mb_model *md, mb_work *w, double t) {
    for (int64_t e = 0; e < md->n_expr; e++) w->evals[e] = run_program(md, e, t, w->stack);
}

/* w->loads (k x 3): the constant values with the varying entries at t (w->evals). */
void mb_loads_at(const mb_model *md, mb_work *w) {
    for (int64_t j = 0; j < md->k; j++)
        for (int a = 0; a < 3; a++) w->loads[3 * j + a] = md->loads[MB_LOAD_W * j + L_VALUE + a];
    for (int64_t v = 0; v < md->n_varying; v++) {
        const int64_t *vi = md->varying + 3 * v;
        w->loads[3 * vi[0] + vi[1]] = w->evals[vi[2]];
    }
}

void mb_law(const mb_model *md, const mb_work *w, int64_t comp, double *f) {
    int64_t l = md->comps_i[4 * comp + 3];
    if (l < 0) {
        f[0] = f[1] = f[2] = 0.0;
        return;
    }
    for (int a = 0; a < 3; a++) f[a] = w->evals[md->laws[3 * l + a]];
}

/* out (m) = lam with the known reactions that vary in t set to their values. */
void mb_known_at(const mb_model *md, const mb_work *w, const double *lam, double *out) {
    for (int64_t i = 0; i < md->m; i++) out[i] = lam[i];
    for (int64_t j = 0; j < md->n_known; j++) out[md->known[2 * j]] = w->evals[md->known[2 * j + 1]];
}
