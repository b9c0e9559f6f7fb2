/* Helpers shared by generated model code: small dense linear solves.
 *
 * Generated kernels call these from the right-hand side (mass matrix solve) and from impulsive
 * resets (the KKT system of a plastic impact); sizes are a few dozen at most, so plain
 * Cholesky / partial-pivoting LU on the stack is the fastest choice.
 */
#ifndef AMBLE_CORE_H
#define AMBLE_CORE_H
#include <math.h>
#include <stdbool.h> /* derivatives of saturations print `true`/`false` conditions */
#include <string.h>

/* Inline a small generated function into every caller (the compiler's own choice otherwise). */
#if defined(__GNUC__) || defined(__clang__)
#define AMBLE_INLINE inline __attribute__((always_inline))
#else
#define AMBLE_INLINE inline
#endif
/* Inline every call of a function into its body, so that the kernels it calls at one point share
 * their common terms (codegen.py: rhs_surfaces_k). */
#if defined(__GNUC__) || defined(__clang__)
#define AMBLE_FLATTEN __attribute__((flatten))
#else
#define AMBLE_FLATTEN
#endif

/* A kernel compiled in a translation unit of its own (backend/cache.py: the two units of a large
 * model compile in parallel) and linked into the same library: called directly, not exported. */
#if defined(__GNUC__) || defined(__clang__)
#define AMBLE_HIDDEN __attribute__((visibility("hidden")))
#else
#define AMBLE_HIDDEN
#endif

/* Error codes returned by kernels (0 = ok). */
#define AMBLE_ERR_SINGULAR_MASS 1
#define AMBLE_ERR_SINGULAR_RESET 2
#define AMBLE_ERR_NO_DERIVATIVES 3 /* a library built without its derivative kernels */

/* Solve A x = b for symmetric positive definite A by LDL^T (A = L D L^T, L unit lower
 * triangular): no square root; the failure test (a pivot D_j not positive, or max D / min D > 1e14, a lower
 * bound of cond(A)). The lower triangle of A is overwritten by L, b by x. Generated right-hand
 * sides of small systems write this solve out unrolled (backend/ldl.py); larger ones call it. */
static int amble_ldl_solve(int n, double *A, double *b) {
    double D[n], u[n];
    double dmin = INFINITY, dmax = 0.0;
    for (int j = 0; j < n; ++j) {
        double d = A[j * n + j];
        for (int k = 0; k < j; ++k) {
            u[k] = A[j * n + k] * D[k];
            d -= A[j * n + k] * u[k];
        }
        if (!(d > 0.0)) return AMBLE_ERR_SINGULAR_MASS;
        D[j] = d;
        if (d < dmin) dmin = d;
        if (d > dmax) dmax = d;
        const double r = 1.0 / d;
        for (int i = j + 1; i < n; ++i) {
            double v = A[i * n + j];
            for (int k = 0; k < j; ++k) v -= A[i * n + k] * u[k];
            A[i * n + j] = v * r;
        }
    }
    if (dmax > 1e14 * dmin) return AMBLE_ERR_SINGULAR_MASS;
    for (int i = 1; i < n; ++i) {
        double v = b[i];
        for (int k = 0; k < i; ++k) v -= A[i * n + k] * b[k];
        b[i] = v;
    }
    for (int i = 0; i < n; ++i) b[i] /= D[i];
    for (int i = n - 2; i >= 0; --i) {
        double v = b[i];
        for (int k = i + 1; k < n; ++k) v -= A[k * n + i] * b[k];
        b[i] = v;
    }
    return 0;
}

/* Solve A x = b for a general square A (row-major n x n) by LU with partial pivoting.
 * A and b are overwritten (b by x). Returns AMBLE_ERR_SINGULAR_RESET on a (near) zero pivot. */
static int amble_lu_solve(int n, double *A, double *b) {
    double scale = 0.0;
    for (int i = 0; i < n * n; ++i) scale = fmax(scale, fabs(A[i]));
    if (!(scale > 0.0)) return AMBLE_ERR_SINGULAR_RESET;
    for (int k = 0; k < n; ++k) {
        int piv = k;
        double best = fabs(A[k * n + k]);
        for (int i = k + 1; i < n; ++i)
            if (fabs(A[i * n + k]) > best) { best = fabs(A[i * n + k]); piv = i; }
        if (!(best > 1e-13 * scale)) return AMBLE_ERR_SINGULAR_RESET;
        if (piv != k) {
            for (int j = 0; j < n; ++j) { double tmp = A[k * n + j]; A[k * n + j] = A[piv * n + j]; A[piv * n + j] = tmp; }
            double tmp = b[k]; b[k] = b[piv]; b[piv] = tmp;
        }
        for (int i = k + 1; i < n; ++i) {
            double f = A[i * n + k] / A[k * n + k];
            if (f == 0.0) continue;
            for (int j = k; j < n; ++j) A[i * n + j] -= f * A[k * n + j];
            b[i] -= f * b[k];
        }
    }
    for (int i = n - 1; i >= 0; --i) {
        double v = b[i];
        for (int j = i + 1; j < n; ++j) v -= A[i * n + j] * b[j];
        b[i] = v / A[i * n + i];
    }
    return 0;
}

/* Plastic impulse: given the (extended) mass matrix Me (ne x ne), constraint Jacobian J
 * (nc x ne, row-major) and the pre-impact velocity v (ne), overwrite v with the post-impact
 * velocity solving  Me (v+ - v-) = J^T lambda,  J v+ = 0  (the KKT system of a perfectly
 * plastic, non-sliding contact or a joint lock). */
static int amble_impulse(int ne, int nc, const double *Me, const double *J, double *v) {
    int nk = ne + nc;
    double A[nk * nk];
    double r[nk];
    memset(A, 0, sizeof(double) * nk * nk);
    for (int i = 0; i < ne; ++i) {
        double s = 0.0;
        for (int j = 0; j < ne; ++j) {
            A[i * nk + j] = Me[i * ne + j];
            s += Me[i * ne + j] * v[j];
        }
        r[i] = s;
    }
    for (int c = 0; c < nc; ++c) {
        for (int j = 0; j < ne; ++j) {
            A[(ne + c) * nk + j] = J[c * ne + j];
            A[j * nk + ne + c] = -J[c * ne + j];
        }
        r[ne + c] = 0.0;
    }
    int err = amble_lu_solve(nk, A, r);
    if (err) return err;
    for (int i = 0; i < ne; ++i) v[i] = r[i];
    return 0;
}

/* ---- solves for sensitivity runs: one factorisation, many right-hand sides ---- */

/* Cholesky factor of a symmetric positive definite A (row-major, lower triangle read and
 * overwritten by L). A pivot not positive, or pivots spread by more than 1e7 (cond(A) ≥ 1e14),
 * is AMBLE_ERR_SINGULAR_MASS, as for amble_ldl_solve. */
static int amble_chol_factor(int n, double *A) {
    double dmin = INFINITY, dmax = 0.0;
    for (int j = 0; j < n; ++j) {
        double s = A[j * n + j];
        for (int k = 0; k < j; ++k) s -= A[j * n + k] * A[j * n + k];
        if (!(s > 0.0)) return AMBLE_ERR_SINGULAR_MASS;
        double d = sqrt(s);
        A[j * n + j] = d;
        if (d < dmin) dmin = d;
        if (d > dmax) dmax = d;
        for (int i = j + 1; i < n; ++i) {
            double v = A[i * n + j];
            for (int k = 0; k < j; ++k) v -= A[i * n + k] * A[j * n + k];
            A[i * n + j] = v / d;
        }
    }
    return dmax > 1e7 * dmin ? AMBLE_ERR_SINGULAR_MASS : 0;
}

/* Solve L Lᵀ X = B in place for the ncols columns of B (row-major n × ncols). */
static void amble_chol_apply(int n, const double *L, double *B, int ncols) {
    for (int c = 0; c < ncols; ++c) {
        for (int i = 0; i < n; ++i) {
            double v = B[i * ncols + c];
            for (int k = 0; k < i; ++k) v -= L[i * n + k] * B[k * ncols + c];
            B[i * ncols + c] = v / L[i * n + i];
        }
        for (int i = n - 1; i >= 0; --i) {
            double v = B[i * ncols + c];
            for (int k = i + 1; k < n; ++k) v -= L[k * n + i] * B[k * ncols + c];
            B[i * ncols + c] = v / L[i * n + i];
        }
    }
}

/* amble_chol_apply for many columns: the same solve with the columns inner (contiguous rows,
 * which the compiler vectorises) and one reciprocal of each pivot instead of a division per
 * column (the derivative kernels solve for a column per state and parameter). */
static void amble_chol_apply_rows(int n, const double *L, double *B, int ncols) {
    for (int i = 0; i < n; ++i) {
        double *bi = B + i * ncols;
        for (int k = 0; k < i; ++k) {
            const double l = L[i * n + k], *bk = B + k * ncols;
            for (int c = 0; c < ncols; ++c) bi[c] -= l * bk[c];
        }
        const double r = 1.0 / L[i * n + i];
        for (int c = 0; c < ncols; ++c) bi[c] *= r;
    }
    for (int i = n - 1; i >= 0; --i) {
        double *bi = B + i * ncols;
        for (int k = i + 1; k < n; ++k) {
            const double l = L[k * n + i], *bk = B + k * ncols;
            for (int c = 0; c < ncols; ++c) bi[c] -= l * bk[c];
        }
        const double r = 1.0 / L[i * n + i];
        for (int c = 0; c < ncols; ++c) bi[c] *= r;
    }
}

/* LU factorisation with partial pivoting in place (piv: row swaps); AMBLE_ERR_SINGULAR_RESET on a
 * (near) zero pivot, with the threshold of amble_lu_solve. */
static int amble_lu_factor(int n, double *A, int *piv) {
    double scale = 0.0;
    for (int i = 0; i < n * n; ++i) scale = fmax(scale, fabs(A[i]));
    if (!(scale > 0.0)) return AMBLE_ERR_SINGULAR_RESET;
    for (int k = 0; k < n; ++k) {
        int pk = k;
        double best = fabs(A[k * n + k]);
        for (int i = k + 1; i < n; ++i)
            if (fabs(A[i * n + k]) > best) { best = fabs(A[i * n + k]); pk = i; }
        if (!(best > 1e-13 * scale)) return AMBLE_ERR_SINGULAR_RESET;
        piv[k] = pk;
        if (pk != k)
            for (int j = 0; j < n; ++j) { double tmp = A[k * n + j]; A[k * n + j] = A[pk * n + j]; A[pk * n + j] = tmp; }
        for (int i = k + 1; i < n; ++i) {
            double f = A[i * n + k] / A[k * n + k];
            A[i * n + k] = f;
            if (f == 0.0) continue;
            for (int j = k + 1; j < n; ++j) A[i * n + j] -= f * A[k * n + j];
        }
    }
    return 0;
}

/* Solve with the factors of amble_lu_factor for the ncols columns of B (row-major n × ncols). */
static void amble_lu_apply(int n, const double *LU, const int *piv, double *B, int ncols) {
    for (int c = 0; c < ncols; ++c) {
        for (int k = 0; k < n; ++k)
            if (piv[k] != k) { double tmp = B[k * ncols + c]; B[k * ncols + c] = B[piv[k] * ncols + c]; B[piv[k] * ncols + c] = tmp; }
        for (int i = 1; i < n; ++i) {
            double v = B[i * ncols + c];
            for (int k = 0; k < i; ++k) v -= LU[i * n + k] * B[k * ncols + c];
            B[i * ncols + c] = v;
        }
        for (int i = n - 1; i >= 0; --i) {
            double v = B[i * ncols + c];
            for (int k = i + 1; k < n; ++k) v -= LU[i * n + k] * B[k * ncols + c];
            B[i * ncols + c] = v / LU[i * n + i];
        }
    }
}

/* The KKT matrix [[Me, −Jᵀ], [J, 0]] of an impulsive reset, row-major (ne + nc)². */
static void amble_kkt_matrix(int ne, int nc, const double *Me, const double *J, double *A) {
    const int nk = ne + nc;
    memset(A, 0, sizeof(double) * nk * nk);
    for (int i = 0; i < ne; ++i)
        for (int j = 0; j < ne; ++j) A[i * nk + j] = Me[i * ne + j];
    for (int c = 0; c < nc; ++c)
        for (int j = 0; j < ne; ++j) {
            A[(ne + c) * nk + j] = J[c * ne + j];
            A[j * nk + ne + c] = -J[c * ne + j];
        }
}

/* amble_impulse that also returns the impulse λ (nc). */
static int amble_impulse_lambda(int ne, int nc, const double *Me, const double *J, double *v, double *lam) {
    const int nk = ne + nc;
    double A[nk * nk], r[nk];
    int piv[nk];
    amble_kkt_matrix(ne, nc, Me, J, A);
    for (int i = 0; i < ne; ++i) {
        double s = 0.0;
        for (int j = 0; j < ne; ++j) s += Me[i * ne + j] * v[j];
        r[i] = s;
    }
    for (int c = 0; c < nc; ++c) r[ne + c] = 0.0;
    int err = amble_lu_factor(nk, A, piv);
    if (err) return err;
    amble_lu_apply(nk, A, piv, r, 1);
    for (int i = 0; i < ne; ++i) v[i] = r[i];
    for (int c = 0; c < nc; ++c) lam[c] = r[ne + c];
    return 0;
}

/* Solve the KKT system for the ncols columns of B ((ne + nc) × ncols, row-major), in place. */
static int amble_kkt_solve_columns(int ne, int nc, const double *Me, const double *J, double *B, int ncols) {
    const int nk = ne + nc;
    double A[nk * nk];
    int piv[nk];
    amble_kkt_matrix(ne, nc, Me, J, A);
    int err = amble_lu_factor(nk, A, piv);
    if (err) return err;
    amble_lu_apply(nk, A, piv, B, ncols);
    return 0;
}

/* Constrained accelerations of a mode with m holonomic constraints (the model's unit calls it from
 * its right-hand side): M q̈ = f + Jᵀλ, J q̈ = γ, with the Cholesky factor of M (overwritten) and
 * X = M⁻¹[f Jᵀ]: λ = (J X_J)⁻¹ (γ − J X_f), q̈ = X_f + X_J λ. f (n) is overwritten by q̈, lam (m)
 * receives λ. A singular M, or J without full row rank (J M⁻¹ Jᵀ singular), is
 * AMBLE_ERR_SINGULAR_MASS. */
static int amble_holonomic_solve(int n, int m, double *M, const double *J, const double *gam, double *f,
                                 double *lam) {
    const int w = m + 1;
    double X[n * w], S[m * m];
    if (amble_chol_factor(n, M)) return AMBLE_ERR_SINGULAR_MASS;
    for (int i = 0; i < n; ++i) {
        X[i * w] = f[i];
        for (int c = 0; c < m; ++c) X[i * w + 1 + c] = J[c * n + i];
    }
    amble_chol_apply_rows(n, M, X, w);
    for (int a = 0; a < m; ++a) {
        double r = gam[a];
        for (int i = 0; i < n; ++i) r -= J[a * n + i] * X[i * w];
        lam[a] = r;
        for (int b = 0; b < m; ++b) {
            double s = 0.0;
            for (int i = 0; i < n; ++i) s += J[a * n + i] * X[i * w + 1 + b];
            S[a * m + b] = s;
        }
    }
    if (amble_chol_factor(m, S)) return AMBLE_ERR_SINGULAR_MASS;
    amble_chol_apply(m, S, lam, 1);
    for (int i = 0; i < n; ++i) {
        double v = X[i * w];
        for (int c = 0; c < m; ++c) v += X[i * w + 1 + c] * lam[c];
        f[i] = v;
    }
    return 0;
}

/* The tangent of amble_holonomic_solve in nv directions: with L the Cholesky factor of M that it
 * left, solve M a = R1 + Jᵀ l, J a = R2 (R1 n × nv, R2 m × nv, row-major); R1 is overwritten by a
 * (the tangents of q̈), R2 by l (those of λ). */
static int amble_holonomic_tangent(int n, int m, int nv, const double *L, const double *J, double *R1, double *R2) {
    double XJ[n * m], S[m * m];
    for (int i = 0; i < n; ++i)
        for (int c = 0; c < m; ++c) XJ[i * m + c] = J[c * n + i];
    amble_chol_apply_rows(n, L, XJ, m);
    for (int a = 0; a < m; ++a)
        for (int b = 0; b < m; ++b) {
            double s = 0.0;
            for (int i = 0; i < n; ++i) s += J[a * n + i] * XJ[i * m + b];
            S[a * m + b] = s;
        }
    if (amble_chol_factor(m, S)) return AMBLE_ERR_SINGULAR_MASS;
    amble_chol_apply_rows(n, L, R1, nv);
    for (int c = 0; c < m; ++c)
        for (int i = 0; i < n; ++i) {
            const double j = J[c * n + i];
            for (int v = 0; v < nv; ++v) R2[c * nv + v] -= j * R1[i * nv + v];
        }
    amble_chol_apply_rows(m, S, R2, nv);
    for (int i = 0; i < n; ++i)
        for (int c = 0; c < m; ++c) {
            const double x = XJ[i * m + c];
            for (int v = 0; v < nv; ++v) R1[i * nv + v] += x * R2[c * nv + v];
        }
    return 0;
}

#endif
