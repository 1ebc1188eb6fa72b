/*
 * Integrate an FMI 2.0 or 3.0 Model-Exchange instance and sample its outputs, without
 * returning to Python between steps.
 *
 * The caller (pydiag/native_me.py) instantiates, parameterises and initialises the FMU
 * with fmpy, enters continuous-time mode, then passes the instance, the FMI version and
 * the addresses of five functions: SetTime, SetContinuousStates, GetContinuousState-
 * Derivatives (fmi2GetDerivatives), GetFloat64 (fmi2GetReal), CompletedIntegratorStep.
 * Only FMUs without event indicators qualify (the Python side checks); an FMU that asks
 * for an event at a completed step stops the run with PD_EVENT, and the caller falls
 * back to an event-handling solver. Integration: an explicit embedded Runge-Kutta pair with
 * adaptive steps. Method 8 is DOP853 (Hairer's 8(5,3), coefficients generated from
 * scipy) with its 7th-order dense output: steps run freely and outputs are evaluated at
 * interpolated states. Method 5 is Dormand-Prince 5(4) with steps clipped to land on the
 * output grid. Only FMUs without event indicators qualify (the Python side
 * checks).
 *
 * Error scale per state: atol + rtol * max(|x_i|, |x_new_i|, peak_i), where peak_i is
 * the largest |x_i| seen so far (a tolerance relative to the state's own scale, so
 * states in metres or micrometres are treated alike).
 *
 * A periodic response can stop the run early. Given a check at output n_check (one period
 * of the forcing), the run stops after that output when the response repeats from there:
 * every state is back at its value at output 0, and at every accepted step between them
 * the derivatives and the outputs are the same at the same state one period later (the
 * model depends on time only through its period: no strike or ripple of another period),
 * each to within tol of its range over the period plus ten times the integrator's error,
 * and the period crossed in CHECK_MIN_STEPS steps at least (fewer sample the forcing too
 * sparsely).
 *
 * With free outputs (a store for the period's states), a run whose states and derivatives
 * repeat but whose outputs do not (returned 2: an output that depends on time otherwise
 * than through the period, as a bearing's strikes added at the sensor, while the dynamics
 * depend on it only through the period) is not integrated further either: each later
 * output is read at its own time from the state one or more whole periods earlier, which
 * the state is (the derivatives are the same there, so the trajectory repeats). A run
 * given a stop whose response does not repeat stops after that many outputs (two periods:
 * the caller compares them) instead of integrating on.
 */
#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "dop853_coefficients.h"

typedef int (*fn_set_time)(void *, double);
typedef int (*fn_set_states)(void *, const double *, size_t);
typedef int (*fn_get_derivs)(void *, double *, size_t);
typedef int (*fn_get_f64)(void *, const uint32_t *, size_t, double *, size_t);
typedef int (*fn_completed)(void *, bool, bool *, bool *);
typedef int (*fn2_get_real)(void *, const unsigned int *, size_t, double *);
typedef int (*fn2_completed)(void *, int, int *, int *);

enum { PD_OK = 0, PD_FMI_ERROR = -1, PD_STEP_UNDERFLOW = -2, PD_NOT_FINITE = -3,
       PD_MAX_STEPS = -4, PD_NO_MEMORY = -5, PD_TERMINATED = -6, PD_BAD_METHOD = -7,
       PD_EVENT = -8, PD_BAD_VERSION = -9 };

/* FMI status codes above fmi3Warning (1) are failures. */
#define FMI_OK(s) ((s) <= 1)

/* Dormand-Prince 5(4). */
#define DP5_STAGES 6
static const double DP5_A[DP5_STAGES][DP5_STAGES] = {
    {0, 0, 0, 0, 0, 0},
    {1.0 / 5, 0, 0, 0, 0, 0},
    {3.0 / 40, 9.0 / 40, 0, 0, 0, 0},
    {44.0 / 45, -56.0 / 15, 32.0 / 9, 0, 0, 0},
    {19372.0 / 6561, -25360.0 / 2187, 64448.0 / 6561, -212.0 / 729, 0, 0},
    {9017.0 / 3168, -355.0 / 33, 46732.0 / 5247, 49.0 / 176, -5103.0 / 18656, 0}};
static const double DP5_B[DP5_STAGES] = {35.0 / 384, 0, 500.0 / 1113, 125.0 / 192,
                                         -2187.0 / 6784, 11.0 / 84};
static const double DP5_C[DP5_STAGES] = {0, 1.0 / 5, 3.0 / 10, 4.0 / 5, 8.0 / 9, 1};
static const double DP5_E[DP5_STAGES + 1] = {71.0 / 57600, 0, -71.0 / 16695, 71.0 / 1920,
                                             -17253.0 / 339200, 22.0 / 525, -1.0 / 40};

typedef struct {
    void *inst;
    int fmi_version; /* 2 or 3 */
    fn_set_time set_time;
    fn_set_states set_states;
    fn_get_derivs get_derivs;
    void *get_outputs; /* fmi3GetFloat64 or fmi2GetReal */
    void *completed;   /* fmi3/fmi2CompletedIntegratorStep */
    size_t nx;
    long *n_rhs;
} Model;

/* The outputs vr[0..ny) at the FMU's current time and states. */
static int get_outputs(const Model *m, const uint32_t *vr, size_t ny, double *out) {
    int status = m->fmi_version == 3
        ? ((fn_get_f64)m->get_outputs)(m->inst, vr, ny, out, ny)
        : ((fn2_get_real)m->get_outputs)(m->inst, (const unsigned int *)vr, ny, out);
    if (!FMI_OK(status)) return PD_FMI_ERROR;
    for (size_t j = 0; j < ny; j++)
        if (!isfinite(out[j])) return PD_NOT_FINITE;
    return PD_OK;
}

/* Tell the FMU a step was accepted; it may ask for an event or to terminate. */
static int completed_step(const Model *m) {
    bool event = false, terminate = false;
    int status;
    if (m->fmi_version == 3) {
        status = ((fn_completed)m->completed)(m->inst, true, &event, &terminate);
    } else {
        int event2 = 0, terminate2 = 0;
        status = ((fn2_completed)m->completed)(m->inst, 1, &event2, &terminate2);
        event = event2 != 0;
        terminate = terminate2 != 0;
    }
    if (!FMI_OK(status)) return PD_FMI_ERROR;
    if (terminate) return PD_TERMINATED;
    if (event) return PD_EVENT;
    return PD_OK;
}

static int rhs(const Model *m, double t, const double *x, double *dx) {
    if (!FMI_OK(m->set_time(m->inst, t))) return PD_FMI_ERROR;
    if (!FMI_OK(m->set_states(m->inst, x, m->nx))) return PD_FMI_ERROR;
    if (!FMI_OK(m->get_derivs(m->inst, dx, m->nx))) return PD_FMI_ERROR;
    ++*m->n_rhs;
    for (size_t i = 0; i < m->nx; i++)
        if (!isfinite(dx[i])) return PD_NOT_FINITE;
    return PD_OK;
}

/* Stages s = first..last-1 of an explicit RK tableau: K[s] = f(t + c_s h, x + h sum_j a_sj K[j]).
 * Row s of the tableau is A[(s - row0) * lda], its node C[s - row0]. */
static int stages(const Model *m, const double *A, int lda, const double *C, int row0, int first,
                  int last, const double *x, double t, double hh, double *K, double *xs) {
    size_t nx = m->nx, n = nx ? nx : 1;
    for (int s = first; s < last; s++) {
        const double *a = A + (size_t)(s - row0) * lda;
        for (size_t i = 0; i < nx; i++) {
            double acc = 0.0;
            for (int j = 0; j < s; j++) acc += a[j] * K[j * n + i];
            xs[i] = x[i] + hh * acc;
        }
        int rc = rhs(m, t + C[s - row0] * hh, xs, K + s * n);
        if (rc) return rc;
    }
    return PD_OK;
}

static double scale_of(double atol, double rtol, double a, double b, double peak) {
    return atol + rtol * fmax(fmax(fabs(a), fabs(b)), peak);
}

/* The periodicity check (see the top). */
typedef struct {
    int n_check;        /* output index compared with output 0; < 1: no check */
    double tol;         /* share of each quantity's range */
    double t_first, period;  /* the window checked: [t_first, t_first + period] */
    size_t nx, ny;
    const uint32_t *vr;
    double *x0, *lo, *hi;              /* states: at output 0, their range (nx each) */
    double *f2, *dlo, *dhi, *dmiss;    /* derivatives (nx each) */
    double *y1, *y2, *ylo, *yhi, *ymiss; /* outputs (ny each) */
    long n_steps;       /* accepted steps checked inside the window */
    bool spoiled;       /* a value one period later was not finite: no verdict */
    double mismatch;    /* out: the largest miss over its allowance */
    int returned;       /* out: 1 the response repeats, 2 its states and derivatives do
                           (free outputs): the run stopped after n_check; 0 neither */
    double *store;      /* n_check x nx: the states at outputs 0..n_check-1 (free outputs),
                           or NULL */
    int stop;           /* > n_check: a run whose response did not repeat stops after this
                           many outputs (the caller compares two periods); 0: it goes on */
} Check;

/* Fewer accepted steps than this inside the period sample its forcing too sparsely to
 * tell: such a run goes on to two periods (the caller compares them). */
#define CHECK_MIN_STEPS 64

static void widen(double *lo, double *hi, const double *v, size_t n, bool first) {
    for (size_t i = 0; i < n; i++) {
        lo[i] = first ? v[i] : fmin(lo[i], v[i]);
        hi[i] = first ? v[i] : fmax(hi[i], v[i]);
    }
}

/* The forcing's part of the check at an accepted step (t, x) with f = f(x, t) inside the
 * window: the derivatives and the outputs at the same state one period later must be the
 * same, or the model depends on time otherwise than through its period (a strike, a
 * ripple at a frequency of its own). */
static int check_step(Check *c, const Model *m, double t, const double *x, const double *f) {
    if (!c || c->spoiled || t < c->t_first || t > c->t_first + c->period) return PD_OK;
    bool first = c->dlo[0] > c->dhi[0];  /* still empty (set so in pd_integrate) */
    int rc;
    if (!FMI_OK(m->set_time(m->inst, t)) || !FMI_OK(m->set_states(m->inst, x, c->nx)))
        return PD_FMI_ERROR;
    rc = get_outputs(m, c->vr, c->ny, c->y1);
    if (rc == PD_OK) rc = rhs(m, t + c->period, x, c->f2);   /* sets the time and the state */
    if (rc == PD_OK) rc = get_outputs(m, c->vr, c->ny, c->y2);
    if (rc == PD_NOT_FINITE) {  /* the run itself may be fine: it goes on, unchecked */
        c->spoiled = true;
        return PD_OK;
    }
    if (rc) return rc;
    widen(c->dlo, c->dhi, f, c->nx, first);
    widen(c->ylo, c->yhi, c->y1, c->ny, first);
    for (size_t i = 0; i < c->nx; i++) c->dmiss[i] = fmax(c->dmiss[i], fabs(c->f2[i] - f[i]));
    for (size_t j = 0; j < c->ny; j++) c->ymiss[j] = fmax(c->ymiss[j], fabs(c->y2[j] - c->y1[j]));
    c->n_steps++;
    return PD_OK;
}

/* miss over its allowance: tol of the range, and ten times the integrator's error. */
static double ratio(double miss, double lo, double hi, double tol, double rtol, double atol) {
    double allowed = tol * (hi - lo) + 10.0 * (atol + rtol * fmax(fabs(lo), fabs(hi)));
    return miss == 0.0 ? 0.0 : miss / allowed;
}

/* The states' part, at output k (state s); true when the run may stop there. */
static bool check_state(Check *c, int k, const double *s, double rtol, double atol) {
    if (!c || k > c->n_check) return false;
    widen(c->lo, c->hi, s, c->nx, k == 0);
    if (k == 0) memcpy(c->x0, s, c->nx * sizeof(double));
    if (k < c->n_check) {
        if (c->store) memcpy(c->store + (size_t)k * c->nx, s, c->nx * sizeof(double));
        return false;
    }
    double states = 0.0, outputs = 0.0;
    for (size_t i = 0; i < c->nx; i++) {
        states = fmax(states, ratio(fabs(s[i] - c->x0[i]), c->lo[i], c->hi[i], c->tol, rtol, atol));
        states = fmax(states, ratio(c->dmiss[i], c->dlo[i], c->dhi[i], c->tol, rtol, atol));
    }
    for (size_t j = 0; j < c->ny; j++)
        outputs = fmax(outputs, ratio(c->ymiss[j], c->ylo[j], c->yhi[j], c->tol, rtol, atol));
    c->mismatch = fmax(states, outputs);
    bool judged = c->n_steps >= CHECK_MIN_STEPS && !c->spoiled;
    c->returned = !judged || states > 1.0 ? 0 : outputs <= 1.0 ? 1 : c->store ? 2 : 0;
    return c->returned != 0;
}

/* The run did not repeat and stops after output k (Check.stop). */
static bool stops(const Check *c, int k) {
    return c && c->stop > c->n_check && !c->returned && k + 1 >= c->stop;
}

/* Outputs k = first..n_out-1 read at their own times from the stored period's states
 * (free outputs, returned 2: see the top). */
static int outputs_from_period(const Model *m, const Check *c, int first, int n_out,
                               double t_first_out, double h_out, double *out) {
    for (int k = first; k < n_out; k++) {
        const double *s = c->store + (size_t)(k % c->n_check) * c->nx;
        if (!FMI_OK(m->set_time(m->inst, t_first_out + k * h_out))
                || !FMI_OK(m->set_states(m->inst, s, c->nx)))
            return PD_FMI_ERROR;
        int rc = get_outputs(m, c->vr, c->ny, out + (size_t)k * c->ny);
        if (rc) return rc;
    }
    return PD_OK;
}

/* DOP853 with dense output. */
static int integrate_dense(Model *m, double *x,
                           double t0, double t_first_out, double h_out, int n_out, size_t ny,
                           const uint32_t *vr, double *out, double rtol, double atol,
                           double h_max, long max_steps, long *n_steps, Check *check) {
    const int S = DOP853_STAGES, SE = DOP853_STAGES_EXTENDED, P = DOP853_INTERPOLATOR_POWER;
    size_t nx = m->nx, n = nx ? nx : 1;
    double *w = calloc((size_t)(SE + P + 4) * n, sizeof(double));
    if (!w) return PD_NO_MEMORY;
    double *K = w, *F = K + (size_t)SE * n, *xs = F + (size_t)P * n, *xn = xs + n,
           *peak = xn + n, *sc = peak + n;
    int rc = PD_OK;
    double t = t0, t_end = t_first_out + (n_out - 1) * h_out;
    int k = 0;
    for (size_t i = 0; i < nx; i++) peak[i] = fabs(x[i]);
    if (nx) rc = rhs(m, t, x, K);
    double h = fmin(h_out, h_max) * 0.1;
    /* outputs at or before the start */
    while (rc == PD_OK && k < n_out && t_first_out + k * h_out <= t + 1e-12 * fmax(1.0, fabs(t))) {
        double tk = t_first_out + k * h_out;
        if (!FMI_OK(m->set_time(m->inst, tk)) || (nx && !FMI_OK(m->set_states(m->inst, x, nx))))
            rc = PD_FMI_ERROR;
        else
            rc = get_outputs(m, vr, ny, out + (size_t)k * ny);
        if (rc == PD_OK && (check_state(check, k, x, rtol, atol) || stops(check, k)))
            n_out = k + 1;
        k++;
    }
    while (rc == PD_OK && k < n_out && nx) {
        if (*n_steps >= max_steps) { rc = PD_MAX_STEPS; break; }
        double hh = fmin(h, h_max);
        if (t + hh > t_end) hh = t_end - t;  /* never integrate past the last output */
        if ((rc = stages(m, &DOP853_A[0][0], S, DOP853_C, 0, 1, S, x, t, hh, K, xs))) break;
        for (size_t i = 0; i < nx; i++) {
            double acc = 0.0;
            for (int j = 0; j < S; j++) acc += DOP853_B[j] * K[j * n + i];
            xn[i] = x[i] + hh * acc;
        }
        if ((rc = rhs(m, t + hh, xn, K + S * n))) break;
        double e5 = 0.0, e3 = 0.0;
        for (size_t i = 0; i < nx; i++) {
            sc[i] = scale_of(atol, rtol, x[i], xn[i], peak[i]);
            double a5 = 0.0, a3 = 0.0;
            for (int j = 0; j <= S; j++) {
                a5 += DOP853_E5[j] * K[j * n + i];
                a3 += DOP853_E3[j] * K[j * n + i];
            }
            e5 += (a5 / sc[i]) * (a5 / sc[i]);
            e3 += (a3 / sc[i]) * (a3 / sc[i]);
        }
        double norm = (e5 == 0.0 && e3 == 0.0) ? 0.0 : fabs(hh) * e5 / sqrt((e5 + 0.01 * e3) * (double)nx);
        if (!isfinite(norm)) { rc = PD_NOT_FINITE; break; }
        double factor = norm > 0 ? 0.9 * pow(norm, -1.0 / 8) : 10.0;
        factor = fmin(10.0, fmax(0.2, factor));
        if (norm > 1.0) {
            h = hh * fmax(0.2, factor);
            if (h < 1e-14 * fmax(1.0, fabs(t))) { rc = PD_STEP_UNDERFLOW; break; }
            continue;
        }
        double t_new = t + hh;
        bool last = t_new >= t_end - 1e-12 * fmax(1.0, fabs(t_end));
        if (last) t_new = t_end;
        /* outputs inside (t, t_new]: interpolate */
        if (k < n_out && t_first_out + k * h_out <= t_new + 1e-12 * fmax(1.0, fabs(t_new))) {
            if ((rc = stages(m, &DOP853_A_EXTRA[0][0], SE, DOP853_C_EXTRA, S + 1, S + 1, SE, x, t,
                             hh, K, xs))) break;
            for (size_t i = 0; i < nx; i++) {
                double dy = xn[i] - x[i];
                F[0 * n + i] = dy;
                F[1 * n + i] = hh * K[i] - dy;
                F[2 * n + i] = 2 * dy - hh * (K[S * n + i] + K[i]);
                for (int r = 0; r < P - 3; r++) {
                    double acc = 0.0;
                    for (int j = 0; j < SE; j++) acc += DOP853_D[r][j] * K[j * n + i];
                    F[(3 + r) * n + i] = hh * acc;
                }
            }
            while (k < n_out && t_first_out + k * h_out <= t_new + 1e-12 * fmax(1.0, fabs(t_new))) {
                double tk = t_first_out + k * h_out;
                double u = (tk - t) / hh;
                for (size_t i = 0; i < nx; i++) {
                    double y = 0.0;
                    for (int r = P - 1, q = 0; r >= 0; r--, q++) {
                        y += F[r * n + i];
                        y *= (q % 2 == 0) ? u : 1.0 - u;
                    }
                    xs[i] = x[i] + y;
                }
                if (!FMI_OK(m->set_time(m->inst, tk)) || !FMI_OK(m->set_states(m->inst, xs, nx))) {
                    rc = PD_FMI_ERROR;
                    break;
                }
                if ((rc = get_outputs(m, vr, ny, out + (size_t)k * ny))) break;
                if (check_state(check, k, xs, rtol, atol) || stops(check, k)) n_out = k + 1;
                k++;
            }
            if (rc) break;
        }
        t = t_new;
        memcpy(x, xn, nx * sizeof(double));
        memcpy(K, K + S * n, nx * sizeof(double)); /* first same as last */
        for (size_t i = 0; i < nx; i++) peak[i] = fmax(peak[i], fabs(x[i]));
        ++*n_steps;
        if ((rc = completed_step(m))) break;
        if ((rc = check_step(check, m, t, x, K))) break;
        h = hh * factor;
    }
    free(w);
    return rc;
}

/* Dormand-Prince 5(4), each step clipped to land on the output grid. */
static int integrate_grid(Model *m, double *x,
                          double t0, double t_first_out, double h_out, int n_out, size_t ny,
                          const uint32_t *vr, double *out, double rtol, double atol,
                          double h_max, long max_steps, long *n_steps, Check *check) {
    const int S = DP5_STAGES;
    size_t nx = m->nx, n = nx ? nx : 1;
    /* K: S + 1 rows (the last is f at the new point, FSAL); xs, xn, peak */
    double *w = calloc((size_t)(S + 1 + 3) * n, sizeof(double));
    if (!w) return PD_NO_MEMORY;
    double *K = w, *xs = w + (S + 1) * n, *xn = xs + n, *peak = xn + n;
    int rc = PD_OK;
    double t = t0;
    for (size_t i = 0; i < nx; i++) peak[i] = fabs(x[i]);
    if (nx) rc = rhs(m, t, x, K);
    double h = fmin(h_out, h_max) * 0.1;
    for (int k = 0; k < n_out && rc == PD_OK; k++) {
        double target = t_first_out + k * h_out;
        while (nx && t < target - 1e-12 * fmax(1.0, fabs(target)) && rc == PD_OK) {
            if (*n_steps >= max_steps) { rc = PD_MAX_STEPS; break; }
            double hh = fmin(fmin(h, h_max), target - t);
            bool land = hh >= target - t;
            if ((rc = stages(m, &DP5_A[0][0], S, DP5_C, 0, 1, S, x, t, hh, K, xs))) break;
            for (size_t i = 0; i < nx; i++) {
                double acc = 0.0;
                for (int j = 0; j < S; j++) acc += DP5_B[j] * K[j * n + i];
                xn[i] = x[i] + hh * acc;
            }
            if ((rc = rhs(m, t + hh, xn, K + S * n))) break;
            double e = 0.0;
            for (size_t i = 0; i < nx; i++) {
                double a = 0.0;
                for (int j = 0; j <= S; j++) a += DP5_E[j] * K[j * n + i];
                a *= hh / scale_of(atol, rtol, x[i], xn[i], peak[i]);
                e += a * a;
            }
            double norm = sqrt(e / (double)nx);
            if (!isfinite(norm)) { rc = PD_NOT_FINITE; break; }
            double factor = norm > 0 ? 0.9 * pow(norm, -1.0 / 5) : 10.0;
            factor = fmin(10.0, fmax(0.2, factor));
            if (norm <= 1.0) {
                t = land ? target : t + hh;
                memcpy(x, xn, nx * sizeof(double));
                memcpy(K, K + S * n, nx * sizeof(double)); /* first same as last */
                for (size_t i = 0; i < nx; i++) peak[i] = fmax(peak[i], fabs(x[i]));
                ++*n_steps;
                if ((rc = completed_step(m))) break;
                if ((rc = check_step(check, m, t, x, K))) break;
                if (!land || factor < 1.0) h = hh * factor; /* keep h when only the grid cut it */
            } else {
                h = hh * fmax(0.2, factor);
                if (h < 1e-14 * fmax(1.0, fabs(t))) { rc = PD_STEP_UNDERFLOW; break; }
            }
        }
        if (rc) break;
        /* outputs at the grid point: the FMU holds a stage state, so set the accepted one */
        if (!FMI_OK(m->set_time(m->inst, target))) { rc = PD_FMI_ERROR; break; }
        if (nx && !FMI_OK(m->set_states(m->inst, x, nx))) { rc = PD_FMI_ERROR; break; }
        if ((rc = get_outputs(m, vr, ny, out + (size_t)k * ny))) break;
        if (check_state(check, k, x, rtol, atol) || stops(check, k)) break;
    }
    free(w);
    return rc;
}

int pd_integrate(void *inst, int fmi_version, void *p_set_time, void *p_set_states,
                 void *p_get_derivs, void *p_get_outputs, void *p_completed, int nx_, double *x,
                 double t0, double t_first_out, double h_out, int n_out, int ny_,
                 const uint32_t *vr, double *out, double rtol, double atol, double h_max,
                 long max_steps, int method, long *n_rhs, long *n_steps,
                 int n_check, double check_tol, double *check_work, double *store,
                 int n_stop, double *mismatch, int *returned) {
    Model m = {inst, fmi_version, (fn_set_time)p_set_time, (fn_set_states)p_set_states,
               (fn_get_derivs)p_get_derivs, p_get_outputs, p_completed, (size_t)nx_, n_rhs};
    size_t nx = (size_t)nx_, ny = (size_t)ny_;
    double *v = check_work;  /* 7 nx + 5 ny values (native_engine.py sizes it) */
    Check check = {n_check, check_tol, t_first_out, n_check * h_out, nx, ny, vr,
                   v, v + nx, v + 2 * nx, v + 3 * nx, v + 4 * nx, v + 5 * nx, v + 6 * nx,
                   v + 7 * nx, v + 7 * nx + ny, v + 7 * nx + 2 * ny, v + 7 * nx + 3 * ny,
                   v + 7 * nx + 4 * ny, 0, false, INFINITY, 0, store, n_stop};
    Check *c = n_check > 0 && n_check < n_out && nx ? &check : NULL;
    if (c) {  /* ranges empty (lo > hi) until the first step inside the window */
        for (size_t i = 0; i < nx; i++) { c->dlo[i] = 1.0; c->dhi[i] = 0.0; c->dmiss[i] = 0.0; }
        for (size_t j = 0; j < ny; j++) { c->ylo[j] = 1.0; c->yhi[j] = 0.0; c->ymiss[j] = 0.0; }
    }
    int rc;
    *n_rhs = 0;
    *n_steps = 0;
    if (fmi_version != 2 && fmi_version != 3) return PD_BAD_VERSION;
    if (method == 8)
        rc = integrate_dense(&m, x, t0, t_first_out, h_out, n_out, (size_t)ny_, vr, out, rtol,
                             atol, h_max, max_steps, n_steps, c);
    else if (method == 5)
        rc = integrate_grid(&m, x, t0, t_first_out, h_out, n_out, (size_t)ny_, vr, out, rtol,
                            atol, h_max, max_steps, n_steps, c);
    else
        return PD_BAD_METHOD;
    if (rc == PD_OK && check.returned == 2)
        rc = outputs_from_period(&m, &check, n_check + 1, n_out, t_first_out, h_out, out);
    *mismatch = check.mismatch;
    *returned = check.returned;
    return rc;
}
