/*
 * Integrate an FMI 3.0 Model-Exchange instance and sample its outputs, without
 * returning to Python between steps.
 *
 * The caller (pydiag/fastsim.py) instantiates, parameterises and initialises the FMU
 * with fmpy, enters continuous-time mode, then passes the instance and the addresses
 * of five fmi3 functions. Integration: explicit Dormand-Prince 5(4) with adaptive
 * steps, each step clipped to land on the output grid (no interpolation). Only FMUs
 * without event indicators qualify (the Python side checks).
 *
 * Error norm per state: |err_i| / (atol + rtol * max(|x_i|, |x_new_i|, peak_i)), where
 * peak_i is the largest |x_i| seen so far (a tolerance relative to the state's own
 * scale, so states in metres or micrometres are treated alike).
 */
#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef int (*fn_set_time)(void *, double);
typedef int (*fn_set_states)(void *, const double *, size_t);
typedef int (*fn_get_derivs)(void *, double *, size_t);
typedef int (*fn_get_f64)(void *, const uint32_t *, size_t, double *, size_t);
typedef int (*fn_completed)(void *, bool, bool *, bool *);

enum { PD_OK = 0, PD_FMI_ERROR = -1, PD_STEP_UNDERFLOW = -2, PD_NOT_FINITE = -3,
       PD_MAX_STEPS = -4, PD_NO_MEMORY = -5, PD_TERMINATED = -6 };

/* FMI status codes above fmi3Warning (1) are failures. */
#define FMI_OK(s) ((s) <= 1)

static int rhs(void *inst, fn_set_time set_time, fn_set_states set_states,
               fn_get_derivs get_derivs, double t, const double *x, double *dx, size_t nx,
               long *n_rhs) {
    if (!FMI_OK(set_time(inst, t))) return PD_FMI_ERROR;
    if (!FMI_OK(set_states(inst, x, nx))) return PD_FMI_ERROR;
    if (!FMI_OK(get_derivs(inst, dx, nx))) return PD_FMI_ERROR;
    ++*n_rhs;
    for (size_t i = 0; i < nx; i++)
        if (!isfinite(dx[i])) return PD_NOT_FINITE;
    return PD_OK;
}

/* Dormand-Prince 5(4) tableau. */
static const double C2 = 1.0 / 5, C3 = 3.0 / 10, C4 = 4.0 / 5, C5 = 8.0 / 9;
static const double A21 = 1.0 / 5;
static const double A31 = 3.0 / 40, A32 = 9.0 / 40;
static const double A41 = 44.0 / 45, A42 = -56.0 / 15, A43 = 32.0 / 9;
static const double A51 = 19372.0 / 6561, A52 = -25360.0 / 2187, A53 = 64448.0 / 6561,
                    A54 = -212.0 / 729;
static const double A61 = 9017.0 / 3168, A62 = -355.0 / 33, A63 = 46732.0 / 5247,
                    A64 = 49.0 / 176, A65 = -5103.0 / 18656;
static const double B1 = 35.0 / 384, B3 = 500.0 / 1113, B4 = 125.0 / 192, B5 = -2187.0 / 6784,
                    B6 = 11.0 / 84;
static const double E1 = 71.0 / 57600, E3 = -71.0 / 16695, E4 = 71.0 / 1920,
                    E5 = -17253.0 / 339200, E6 = 22.0 / 525, E7 = -1.0 / 40;

int pd_integrate(void *inst, void *p_set_time, void *p_set_states, void *p_get_derivs,
                 void *p_get_f64, void *p_completed, int nx_, double *x, double t0,
                 double t_first_out, double h_out, int n_out, int ny_, const uint32_t *vr,
                 double *out, double rtol, double atol, double h_max, long max_steps,
                 long *n_rhs, long *n_steps) {
    fn_set_time set_time = (fn_set_time)p_set_time;
    fn_set_states set_states = (fn_set_states)p_set_states;
    fn_get_derivs get_derivs = (fn_get_derivs)p_get_derivs;
    fn_get_f64 get_f64 = (fn_get_f64)p_get_f64;
    fn_completed completed = (fn_completed)p_completed;
    size_t nx = (size_t)nx_, ny = (size_t)ny_;
    double *w = calloc(11 * (nx ? nx : 1), sizeof(double));
    if (!w) return PD_NO_MEMORY;
    double *k1 = w, *k2 = w + nx, *k3 = w + 2 * nx, *k4 = w + 3 * nx, *k5 = w + 4 * nx,
           *k6 = w + 5 * nx, *k7 = w + 6 * nx, *xs = w + 7 * nx, *xn = w + 8 * nx,
           *peak = w + 9 * nx, *err = w + 10 * nx;
    int rc = PD_OK;
    double t = t0;
    *n_rhs = 0;
    *n_steps = 0;
    for (size_t i = 0; i < nx; i++) peak[i] = fabs(x[i]);
    if (nx) rc = rhs(inst, set_time, set_states, get_derivs, t, x, k1, nx, n_rhs);
    double h = fmin(h_out, h_max) * 0.1;
    for (int k = 0; k < n_out && rc == PD_OK; k++) {
        double target = t_first_out + k * h_out;
        while (nx && t < target - 1e-12 * fmax(1.0, fabs(target)) && rc == PD_OK) {
            if (*n_steps >= max_steps) { rc = PD_MAX_STEPS; break; }
            double hh = fmin(fmin(h, h_max), target - t);
            bool land = hh >= target - t;
#define STAGE(dst, ...)                                                                  \
            for (size_t i = 0; i < nx; i++) xs[i] = x[i] + hh * (__VA_ARGS__);           \
            if ((rc = rhs(inst, set_time, set_states, get_derivs, t, xs, dst, nx, n_rhs))) break;
            double tt = t;
            do {
                t = tt + C2 * hh; STAGE(k2, A21 * k1[i])
                t = tt + C3 * hh; STAGE(k3, A31 * k1[i] + A32 * k2[i])
                t = tt + C4 * hh; STAGE(k4, A41 * k1[i] + A42 * k2[i] + A43 * k3[i])
                t = tt + C5 * hh; STAGE(k5, A51 * k1[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i])
                t = tt + hh;
                STAGE(k6, A61 * k1[i] + A62 * k2[i] + A63 * k3[i] + A64 * k4[i] + A65 * k5[i])
                for (size_t i = 0; i < nx; i++)
                    xn[i] = x[i] + hh * (B1 * k1[i] + B3 * k3[i] + B4 * k4[i] + B5 * k5[i] + B6 * k6[i]);
                if ((rc = rhs(inst, set_time, set_states, get_derivs, tt + hh, xn, k7, nx, n_rhs))) break;
            } while (0);
#undef STAGE
            t = tt;
            if (rc) break;
            double norm = 0.0;
            for (size_t i = 0; i < nx; i++) {
                err[i] = hh * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] + E7 * k7[i]);
                double sc = atol + rtol * fmax(fmax(fabs(x[i]), fabs(xn[i])), peak[i]);
                double r = err[i] / sc;
                norm += r * r;
            }
            norm = sqrt(norm / (double)nx);
            if (!isfinite(norm)) { rc = PD_NOT_FINITE; break; }
            double factor = norm > 0 ? 0.9 * pow(norm, -0.2) : 5.0;
            factor = fmin(5.0, fmax(0.2, factor));
            if (norm <= 1.0) {
                t = land ? target : tt + hh;
                memcpy(x, xn, nx * sizeof(double));
                memcpy(k1, k7, nx * sizeof(double)); /* first same as last */
                for (size_t i = 0; i < nx; i++) peak[i] = fmax(peak[i], fabs(x[i]));
                ++*n_steps;
                bool enter_event = false, terminate = false;
                if (!FMI_OK(completed(inst, true, &enter_event, &terminate))) { rc = PD_FMI_ERROR; break; }
                if (terminate) { rc = PD_TERMINATED; break; }
                if (!land || factor < 1.0) h = hh * factor; /* keep h when only the grid cut it */
            } else {
                h = hh * fmax(0.2, factor);
                if (h < 1e-14 * fmax(1.0, fabs(t))) { rc = PD_STEP_UNDERFLOW; break; }
            }
        }
        if (rc) break;
        /* outputs at the grid point: the FMU holds a stage state, so set the accepted one */
        if (!FMI_OK(set_time(inst, target))) { rc = PD_FMI_ERROR; break; }
        if (nx && !FMI_OK(set_states(inst, x, nx))) { rc = PD_FMI_ERROR; break; }
        if (!FMI_OK(get_f64(inst, vr, ny, out + (size_t)k * ny, ny))) { rc = PD_FMI_ERROR; break; }
        for (size_t j = 0; j < ny; j++)
            if (!isfinite(out[(size_t)k * ny + j])) { rc = PD_NOT_FINITE; break; }
    }
    free(w);
    return rc;
}
