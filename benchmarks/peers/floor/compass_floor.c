/*
 * Compass-gait walker: a minimal compiled loop (the benchmark "floor").
 *
 * Adaptive DOP853 (Dormand-Prince 8(5,3), the step-size control and 7th-order
 * dense output of SciPy's DOP853) integrating Drake's compass-gait swing-phase
 * equations; the foot-collision witness
 *     w(x) = max(2*slope - stance - swing, swing - stance)
 * is monitored after every accepted step and, when it goes from positive to
 * non-positive, its root is located on the dense output with Brent's method
 * (to `event_tol` in time).  Drake's impact reset is applied at the root and
 * the next swing phase starts from the post-impact state.
 *
 * State order (Drake): x = (stance, swing, stancedot, swingdot).
 * params = (mass_hip, mass_leg, length_leg, center_of_mass_leg, gravity, slope).
 *
 * The Butcher/dense-output tables come from "dop853_tab.h", generated at build
 * time (see benchmarks/peers/floor.py).
 */
#include <math.h>
#include <string.h>

#include "dop853_tab.h"

#define NX 4

typedef struct {
  double m11, mlb, m22, g1, g2; /* swing-phase constants */
  double m, mh, l, a, b, slope; /* raw parameters for the reset */
} model_t;

static void model_init(model_t *md, const double *p) {
  const double mh = p[0], m = p[1], l = p[2], b = p[3], g = p[4];
  const double a = l - b;
  md->m = m;
  md->mh = mh;
  md->l = l;
  md->a = a;
  md->b = b;
  md->slope = p[5];
  md->m11 = mh * l * l + m * (l * l + a * a);
  md->mlb = m * l * b;
  md->m22 = m * b * b;
  md->g1 = (mh * l + m * (a + l)) * g;
  md->g2 = m * b * g;
}

/* Swing-phase vector field: M qdd = -bias (Drake's MassMatrix/DynamicsBiasTerm). */
static inline void rhs(const model_t *md, const double *x, double *dx) {
  const double st = x[0], sw = x[1], vst = x[2], vsw = x[3];
  const double s = sin(st - sw);
  const double m12 = -md->mlb * cos(sw - st);
  const double b1 = -md->mlb * vsw * vsw * s - md->g1 * sin(st);
  const double b2 = md->mlb * vst * vst * s + md->g2 * sin(sw);
  const double idet = 1.0 / (md->m11 * md->m22 - m12 * m12);
  dx[0] = vst;
  dx[1] = vsw;
  dx[2] = (-md->m22 * b1 + m12 * b2) * idet;
  dx[3] = (m12 * b1 - md->m11 * b2) * idet;
}

/* Foot-collision witness (Drake's FootCollision). */
static inline double witness(const model_t *md, const double *x) {
  const double c = 2.0 * md->slope - x[0] - x[1];
  const double f = x[1] - x[0];
  return c > f ? c : f;
}

/* Solve the n x n system A z = r in place (Gaussian elimination, partial
 * pivoting); A is row-major and destroyed, r becomes z. */
static void solve_small(int n, double *A, double *r) {
  for (int k = 0; k < n; ++k) {
    int piv = k;
    for (int i = k + 1; i < n; ++i)
      if (fabs(A[i * n + k]) > fabs(A[piv * n + k])) piv = i;
    if (piv != k) {
      for (int j = 0; j < n; ++j) {
        double t = A[k * n + j];
        A[k * n + j] = A[piv * n + j];
        A[piv * n + j] = t;
      }
      double t = r[k];
      r[k] = r[piv];
      r[piv] = t;
    }
    for (int i = k + 1; i < n; ++i) {
      const double f = A[i * n + k] / A[k * n + k];
      for (int j = k; j < n; ++j) A[i * n + j] -= f * A[k * n + j];
      r[i] -= f * r[k];
    }
  }
  for (int k = n - 1; k >= 0; --k) {
    double s = r[k];
    for (int j = k + 1; j < n; ++j) s -= A[k * n + j] * r[j];
    r[k] = s / A[k * n + k];
  }
}

/* Drake's CollisionDynamics: floating-base impulse, then swap the legs. */
static void impact(const model_t *md, const double *x, double *xp) {
  const double m = md->m, mh = md->mh, a = md->a, b = md->b, l = md->l;
  const double st = x[0], sw = x[1];
  const double cst = cos(st), csw = cos(sw), sst = sin(st), ssw = sin(sw);
  const double c = cos(sw - st);
  const double k = m * a + m * l + mh * l;
  const double M[16] = {2 * m + mh,   0.0,         k * cst,      -m * b * csw,
                        0.0,          2 * m + mh,  -k * sst,     m * b * ssw,
                        k * cst,      -k * sst,    m * a * a + (m + mh) * l * l,
                        -m * l * b * c,
                        -m * b * csw, m * b * ssw, -m * l * b * c, m * b * b};
  const double J[2][4] = {{1.0, 0.0, l * cst, -l * csw}, {0.0, 1.0, -l * sst, l * ssw}};
  const double v[4] = {0.0, 0.0, x[2], x[3]};
  double MiJt[2][4]; /* columns of M^-1 J^T */
  for (int r = 0; r < 2; ++r) {
    double A[16];
    memcpy(A, M, sizeof A);
    for (int i = 0; i < 4; ++i) MiJt[r][i] = J[r][i];
    solve_small(4, A, MiJt[r]);
  }
  /* S = J M^-1 J^T (2x2), rhs = J v. */
  double S[4], jv[2];
  for (int i = 0; i < 2; ++i) {
    jv[i] = 0.0;
    for (int k2 = 0; k2 < 4; ++k2) jv[i] += J[i][k2] * v[k2];
    for (int j = 0; j < 2; ++j) {
      double s = 0.0;
      for (int k2 = 0; k2 < 4; ++k2) s += J[i][k2] * MiJt[j][k2];
      S[i * 2 + j] = s;
    }
  }
  solve_small(2, S, jv); /* jv := lambda */
  double vp[4];
  for (int i = 0; i < 4; ++i) vp[i] = v[i] - MiJt[0][i] * jv[0] - MiJt[1][i] * jv[1];
  xp[0] = sw;
  xp[1] = st;
  xp[2] = vp[3];
  xp[3] = vp[2];
}

/* Evaluate the DOP853 dense output F (7 x NX) at fraction s in [0, 1]. */
static inline void dense_eval(const double F[DOP853_POWER][NX], const double *y_old,
                              double s, double *y) {
  for (int i = 0; i < NX; ++i) {
    double acc = 0.0;
    for (int j = DOP853_POWER - 1, q = 0; j >= 0; --j, ++q) {
      acc += F[j][i];
      acc *= (q % 2 == 0) ? s : (1.0 - s);
    }
    y[i] = acc + y_old[i];
  }
}

static inline double rms(const double *v) {
  double s = 0.0;
  for (int i = 0; i < NX; ++i) s += v[i] * v[i];
  return sqrt(s / NX);
}

/* SciPy's select_initial_step for an order-7 error estimator. */
static double initial_step(const model_t *md, const double *y0, const double *f0,
                           double rtol, double atol, double t_bound, long *nfev) {
  double sy[NX], sf[NX], y1[NX], f1[NX], df[NX];
  for (int i = 0; i < NX; ++i) {
    const double sc = atol + fabs(y0[i]) * rtol;
    sy[i] = y0[i] / sc;
    sf[i] = f0[i] / sc;
  }
  const double d0 = rms(sy), d1 = rms(sf);
  double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
  if (h0 > t_bound) h0 = t_bound;
  for (int i = 0; i < NX; ++i) y1[i] = y0[i] + h0 * f0[i];
  rhs(md, y1, f1);
  ++*nfev;
  for (int i = 0; i < NX; ++i) df[i] = (f1[i] - f0[i]) / (atol + fabs(y0[i]) * rtol);
  const double d2 = rms(df) / h0;
  double h1;
  if (d1 <= 1e-15 && d2 <= 1e-15)
    h1 = fmax(1e-6, h0 * 1e-3);
  else
    h1 = pow(0.01 / fmax(d1, d2), 1.0 / 8.0);
  double h = 100 * h0;
  if (h1 < h) h = h1;
  if (t_bound < h) h = t_bound;
  return h;
}

/* Brent's method for g(s) = witness(dense(s)) on [0, 1] with g(0) > 0 >= g(1);
 * stops when the bracket is below `stol` (a fraction of the step). */
static double locate(const model_t *md, const double F[DOP853_POWER][NX],
                     const double *y_old, double ga, double gb, double stol) {
  double a = 0.0, b = 1.0, c = 0.0, fa = ga, fb = gb, fc = ga;
  double d = b - a, e = d, y[NX];
  if (fb == 0.0) return b;
  for (int it = 0; it < 200; ++it) {
    if ((fb > 0 && fc > 0) || (fb < 0 && fc < 0)) {
      c = a;
      fc = fa;
      d = e = b - a;
    }
    if (fabs(fc) < fabs(fb)) {
      a = b;
      b = c;
      c = a;
      fa = fb;
      fb = fc;
      fc = fa;
    }
    const double tol1 = 2.0 * 2.220446049250313e-16 * fabs(b) + 0.5 * stol;
    const double xm = 0.5 * (c - b);
    if (fabs(xm) <= tol1 || fb == 0.0) break;
    if (fabs(e) >= tol1 && fabs(fa) > fabs(fb)) {
      double p, q, r, s = fb / fa;
      if (a == c) {
        p = 2.0 * xm * s;
        q = 1.0 - s;
      } else {
        q = fa / fc;
        r = fb / fc;
        p = s * (2.0 * xm * q * (q - r) - (b - a) * (r - 1.0));
        q = (q - 1.0) * (r - 1.0) * (s - 1.0);
      }
      if (p > 0) q = -q;
      p = fabs(p);
      const double min1 = 3.0 * xm * q - fabs(tol1 * q), min2 = fabs(e * q);
      if (2.0 * p < (min1 < min2 ? min1 : min2)) {
        e = d;
        d = p / q;
      } else {
        d = xm;
        e = d;
      }
    } else {
      d = xm;
      e = d;
    }
    a = b;
    fa = fb;
    b += (fabs(d) > tol1) ? d : (xm > 0 ? tol1 : -tol1);
    dense_eval(F, y_old, b, y);
    fb = witness(md, y);
  }
  /* Return the end of the final bracket on the triggered (<= 0) side, like
   * Drake, so the reset is applied just after the crossing. */
  return fb <= 0.0 ? b : c;
}

/*
 * Walk `steps` steps from x0.
 *   post  : steps x 4 post-impact states (row-major), may be NULL
 *   times : steps cumulative impact times, may be NULL
 *   stats : [0] rhs evaluations, [1] accepted steps, [2] rejected steps
 * Returns 0 on success, k+1 if step k found no collision within t_bound, or
 * -(k+1) if the step size underflowed in step k.
 */
int compass_walk(const double *params, const double *x0, int steps, double rtol,
                 double atol, double event_tol, double t_bound, double *post,
                 double *times, long *stats) {
  model_t md;
  model_init(&md, params);
  if (rtol < 100 * 2.220446049250313e-16) rtol = 100 * 2.220446049250313e-16;
  const double SAFETY = 0.9, MIN_FACTOR = 0.2, MAX_FACTOR = 10.0;
  const double EXPO = -1.0 / 8.0;
  double y[NX], f[NX], K[DOP853_STAGES_EXT][NX], ynew[NX], tmp[NX];
  double F[DOP853_POWER][NX];
  long nfev = 0, nacc = 0, nrej = 0;
  double t_total = 0.0, h_abs = 0.0;

  memcpy(y, x0, sizeof y);
  rhs(&md, y, f);
  ++nfev;
  h_abs = initial_step(&md, y, f, rtol, atol, t_bound, &nfev);

  for (int k = 0; k < steps; ++k) {
    double t = 0.0;
    double w_old = witness(&md, y);
    int hit = 0;
    while (!hit) {
      if (t >= t_bound) {
        stats[0] = nfev, stats[1] = nacc, stats[2] = nrej;
        return k + 1;
      }
      const double min_step = 10.0 * (nextafter(t, INFINITY) - t);
      int rejected = 0;
      double h, err;
      for (;;) {
        if (h_abs < min_step) {
          stats[0] = nfev, stats[1] = nacc, stats[2] = nrej;
          return -(k + 1);
        }
        h = h_abs;
        if (t + h > t_bound) h = t_bound - t;
        /* 12 stages, then K[12] = f(t + h, ynew). */
        memcpy(K[0], f, sizeof f);
        for (int s = 1; s < DOP853_STAGES; ++s) {
          for (int i = 0; i < NX; ++i) {
            double acc = 0.0;
            for (int j = 0; j < s; ++j) acc += DOP853_A[s][j] * K[j][i];
            tmp[i] = y[i] + h * acc;
          }
          rhs(&md, tmp, K[s]);
        }
        for (int i = 0; i < NX; ++i) {
          double acc = 0.0;
          for (int j = 0; j < DOP853_STAGES; ++j) acc += DOP853_B[j] * K[j][i];
          ynew[i] = y[i] + h * acc;
        }
        rhs(&md, ynew, K[DOP853_STAGES]);
        nfev += DOP853_STAGES;
        /* Error norm (SciPy's DOP853 combination of the 5th/3rd-order estimates). */
        double e5 = 0.0, e3 = 0.0;
        for (int i = 0; i < NX; ++i) {
          const double sc = atol + fmax(fabs(y[i]), fabs(ynew[i])) * rtol;
          double a5 = 0.0, a3 = 0.0;
          for (int j = 0; j <= DOP853_STAGES; ++j) {
            a5 += DOP853_E5[j] * K[j][i];
            a3 += DOP853_E3[j] * K[j][i];
          }
          a5 /= sc;
          a3 /= sc;
          e5 += a5 * a5;
          e3 += a3 * a3;
        }
        if (e5 == 0.0 && e3 == 0.0)
          err = 0.0;
        else
          err = h * e5 / sqrt((e5 + 0.01 * e3) * NX);
        if (err < 1.0) {
          double factor = err == 0.0 ? MAX_FACTOR : fmin(MAX_FACTOR, SAFETY * pow(err, EXPO));
          if (rejected && factor > 1.0) factor = 1.0;
          h_abs *= factor;
          break;
        }
        h_abs *= fmax(MIN_FACTOR, SAFETY * pow(err, EXPO));
        rejected = 1;
        ++nrej;
      }
      ++nacc;
      const double w_new = witness(&md, ynew);
      if (w_old > 0.0 && w_new <= 0.0) {
        /* Dense output: 3 extra stages + SciPy's F table. */
        for (int s = DOP853_STAGES + 1; s < DOP853_STAGES_EXT; ++s) {
          for (int i = 0; i < NX; ++i) {
            double acc = 0.0;
            for (int j = 0; j < s; ++j) acc += DOP853_A[s][j] * K[j][i];
            tmp[i] = y[i] + h * acc;
          }
          rhs(&md, tmp, K[s]);
        }
        nfev += DOP853_STAGES_EXT - DOP853_STAGES - 1;
        for (int i = 0; i < NX; ++i) {
          const double dy = ynew[i] - y[i];
          F[0][i] = dy;
          F[1][i] = h * K[0][i] - dy;
          F[2][i] = 2.0 * dy - h * (K[DOP853_STAGES][i] + K[0][i]);
          for (int r = 0; r < DOP853_POWER - 3; ++r) {
            double acc = 0.0;
            for (int j = 0; j < DOP853_STAGES_EXT; ++j) acc += DOP853_D[r][j] * K[j][i];
            F[3 + r][i] = h * acc;
          }
        }
        const double sroot = locate(&md, F, y, w_old, w_new, event_tol / h);
        double yev[NX];
        dense_eval(F, y, sroot, yev);
        t += sroot * h;
        impact(&md, yev, y);
        t_total += t;
        if (post) memcpy(post + 4 * k, y, sizeof y);
        if (times) times[k] = t_total;
        rhs(&md, y, f);
        ++nfev;
        hit = 1;
      } else {
        t += h;
        memcpy(y, ynew, sizeof y);
        memcpy(f, K[DOP853_STAGES], sizeof f);
        w_old = w_new;
      }
    }
  }
  stats[0] = nfev, stats[1] = nacc, stats[2] = nrej;
  return 0;
}
