/* Contact-time cost: the closed-form quadratic (equal accelerations) against the GSL quartic
 * (different accelerations), over the same random pairs. Built by `make bench` only.
 *
 *   bench_predict [N]      N pairs (default 1000000); prints one line per variant
 *
 * Answers are checked first: every finite time must be a closing contact (|r(t)| = sigma to
 * 1e-9, r.r' < 0), the quartic with da = 0 must give the quadratic's bits, and the quartic must
 * agree with predict.c's GSL-free search on the first pairs. A failed check exits 1 before any
 * timing. Each variant is timed REPEATS times over all N pairs; the median is reported. */
#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "build_info.h"
#include "nbep/predict.h"
#include "predict_impl.h"
#include "bench_util.h"

enum { REPEATS = 5, CHECK_AGAINST_SEARCH = 20000 };

/* Residual a contact must meet, relative to sigma: far above round-off, far below any miss
 * that matters. */
#define CONTACT_RTOL 1e-9
/* Agreement with the GSL-free search; looser at grazing incidence, where the answer itself is
 * that sensitive (see predict.h). */
#define AGREE_RTOL 1e-8

typedef struct pair_case {
    nbep_vec3 dp, dv, da;
    double sigma;
} pair_case;

/* splitmix64: a fixed, portable sequence so every run times the same pairs. */
static uint64_t next_u64(uint64_t *s)
{
    uint64_t z = (*s += 0x9e3779b97f4a7c15u);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9u;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebu;
    return z ^ (z >> 31);
}

static double uniform(uint64_t *s, double lo, double hi)
{
    return lo + (hi - lo) * (double)(next_u64(s) >> 11) * 0x1.0p-53;
}

static nbep_vec3 uniform_vec(uint64_t *s, double half)
{
    return (nbep_vec3){uniform(s, -half, half), uniform(s, -half, half), uniform(s, -half, half)};
}

/* Pairs apart at t = 0 in a box a few diameters wide; half aimed roughly at each other so that
 * about half meet; accelerations of gravity's size. */
static void make_cases(pair_case *c, size_t n)
{
    uint64_t s = 20240611u;
    for (size_t i = 0; i < n; i++) {
        double sigma = uniform(&s, 0.1, 1.0);
        nbep_vec3 dp;
        do
            dp = uniform_vec(&s, 3.0);
        while (nbep_vec3_norm(dp) <= sigma);
        nbep_vec3 dv = uniform_vec(&s, 2.0);
        if (i % 2)
            dv = nbep_vec3_axpy(uniform_vec(&s, 0.3), -uniform(&s, 0.3, 1.5), dp);
        c[i] = (pair_case){dp, dv, uniform_vec(&s, 10.0), sigma};
    }
}

static bool is_closing_contact(const pair_case *c, nbep_vec3 da, double t)
{
    nbep_vec3 r = nbep_vec3_axpy(nbep_vec3_axpy(c->dp, t, c->dv), 0.5 * t * t, da);
    nbep_vec3 rdot = nbep_vec3_axpy(c->dv, t, da);
    return fabs(nbep_vec3_norm(r) - c->sigma) <= CONTACT_RTOL * c->sigma &&
           nbep_vec3_dot(r, rdot) < 0.0;
}

static int check_answers(const pair_case *c, size_t n, nbep_predict_ws *ws)
{
    const nbep_vec3 zero = {0.0, 0.0, 0.0};
    size_t bad = 0;
    for (size_t i = 0; i < n; i++) {
        double tq = nbep_predict_pair_quadratic(c[i].dp, c[i].dv, c[i].sigma);
        double t0 = nbep_predict_pair(c[i].dp, c[i].dv, zero, c[i].sigma, ws);
        double t4 = nbep_predict_pair(c[i].dp, c[i].dv, c[i].da, c[i].sigma, ws);
        bool ok = !isnan(tq) && !isnan(t4) && tq >= 0.0 && t4 >= 0.0 && t0 == tq;
        ok = ok && (isinf(tq) || is_closing_contact(&c[i], zero, tq));
        ok = ok && (isinf(t4) || is_closing_contact(&c[i], c[i].da, t4));
        if (ok && i < CHECK_AGAINST_SEARCH) {
            double ts = nbep__predict_pair_bracket(c[i].dp, c[i].dv, c[i].da, c[i].sigma);
            ok = ts == t4 || fabs(ts - t4) <= AGREE_RTOL * ts;
        }
        if (!ok && bad++ < 5)
            fprintf(stderr, "bench_predict: pair %zu: quadratic %.17g, quartic %.17g\n", i, tq,
                    t4);
    }
    return bad == 0 ? 0 : 1;
}

/* Median over REPEATS of the time per solve, in ns. The sum of finite answers is kept in
 * *sink so the compiler cannot drop the calls. */
static double time_variant(const pair_case *c, size_t n, bool quartic, nbep_predict_ws *ws,
                           double *sink)
{
    double ns[REPEATS];
    for (int r = 0; r < REPEATS; r++) {
        double sum = 0.0, t_start = nbep_now();
        for (size_t i = 0; i < n; i++) {
            double t = quartic ? nbep_predict_pair(c[i].dp, c[i].dv, c[i].da, c[i].sigma, ws)
                               : nbep_predict_pair_quadratic(c[i].dp, c[i].dv, c[i].sigma);
            sum += isfinite(t) ? t : 0.0;
        }
        ns[r] = 1e9 * (nbep_now() - t_start) / (double)n;
        *sink += sum;
    }
    qsort(ns, REPEATS, sizeof ns[0], bench_cmp_double);
    return ns[REPEATS / 2];
}

int main(int argc, char **argv)
{
    size_t n = argc > 1 ? (size_t)strtoull(argv[1], NULL, 10) : 1000000;
    if (n == 0) {
        fprintf(stderr, "usage: bench_predict [N > 0]\n");
        return 2;
    }
    gsl_set_error_handler_off();
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_predict_ws *ws = NULL;
    pair_case *c = malloc(n * sizeof *c);
    int rc = 1;
    if (!c || nbep_predict_ws_create(&ws, &d) != NBEP_OK) {
        nbep_diag_print(&d, stderr);
        goto done;
    }
    make_cases(c, n);
    if (check_answers(c, n, ws) != 0) {
        fprintf(stderr, "bench_predict: answers wrong; not timing\n");
        goto done;
    }
    double sink = 0.0;
    double ns_quad = time_variant(c, n, false, ws, &sink);
    double ns_quart = time_variant(c, n, true, ws, &sink);
    printf("bench_predict: %zu pairs, median of %d, 1 thread, %s\n", n, REPEATS,
           NBEP_BUILD_FLAGS);
    printf("quadratic: %.1f ns/solve\n", ns_quad);
    printf("quartic: %.1f ns/solve\n", ns_quart);
    printf("quartic/quadratic: %.1f (checksum %.6g)\n", ns_quart / ns_quad, sink);
    rc = 0;
done:
    free(c);
    nbep_predict_ws_destroy(&ws);
    nbep_diag_fini(&d);
    return rc;
}
