/* Contact-time solvers against a quad-precision reference, on random and adversarial pairs:
 * accuracy (relative error of the contact time, hit/miss disagreements) and cost (ns per
 * solve), every method on the same cases, side by side in one run. Built by `make bench` (and
 * `make accuracy`); run by scripts/accuracy.sh; results in docs/accuracy.md.
 *
 *   bench_contact [--quick] [--cases N] [--repeats R] [--csv FILE] [--dump FILE]
 *                 [--show METHOD]      (on stderr: METHOD's wrong answers, hex inputs)
 *
 * Methods. Equal accelerations (the quadratic):
 *   nbep-quadratic   nbep_predict_pair_quadratic (closed form, compensated gap)
 *   textbook         (-b - sqrt(b^2 - |dv|^2 c)) / |dv|^2 with c = |dp|^2 - sigma^2 plainly
 *   cross-disc       nbep's quadratic with the discriminant as |dv|^2 sigma^2 - |dp x dv|^2
 *                    when the pair is farther than sigma from its closest approach
 * Different accelerations (the quartic):
 *   nbep-gsl         nbep_predict_pair: GSL companion matrix on the rescaled quartic, Newton
 *                    polish, truncated-quadratic candidates, bracket fallback (what nbep runs)
 *   nbep-bracket     nbep__predict_pair_bracket: predict.c's GSL-free search alone
 *   gsl-raw          gsl_poly_complex_solve on the quartic's coefficients as they come, the
 *                    smallest real root >= 0 where the pair closes, no polish (the paper's way)
 *   quad-newton      Newton on the quartic from the truncated quadratic's first root (the
 *                    cheap shortcut: right when da changes little before contact)
 *   piece-newton     this file's alternative: the bracket search's structure (monotone pieces
 *                    of f from the roots of f'' and f'), each root found by safeguarded Newton
 *                    (Newton inside a shrinking bracket, bisection when Newton leaves it or
 *                    stalls) instead of bisection on bit patterns; compensated f as predict.c
 *   near-newton      nbep-gsl, except for pairs nearly touching and closing (which nbep sends
 *                    to the bracket search): quad-newton's root, accepted only when certified
 *                    to be the first (f' < 0 bounded on [0, t]), else nbep-gsl
 *
 * Reference: for each case the exact double inputs are carried into __float128 (113-bit
 * mantissa): the quadratic in closed form; the quartic by isolating the critical points of
 * f(t) = |dp + dv t + da t^2/2|^2 - sigma^2 (roots of f'' in closed form split [0, B] into
 * pieces where f' is monotone; f' changes sign at most once on each) and taking the first
 * monotone piece of f that reaches f <= 0, whose root is refined by safeguarded Newton to
 * 1e-30 relative. B bounds every root (Fujiwara). Every case starts apart (f(0) > 0 in quad),
 * so the contact is the first root of f. __float128 arithmetic comes from libgcc; sqrt is
 * Newton from the double sqrt, so no libquadmath is needed. --dump writes the cases and
 * reference times (hex, as hi + lo) for an independent check in 60-digit arithmetic
 * (scripts/accuracy.py contact-check FILE, mpmath polyroots).
 *
 * What is reported per class and method: the reference's hits, and how many cases are
 * ambiguous (a valley of f has its floor within the round-off of the inputs of contact, so a
 * one-ulp change of the inputs could flip hit and miss; see q_valley_at_round_off); the median,
 * 99th percentile and largest relative error of the contact time over the cases both call
 * hits; the largest ratio of that error to the reference's own sensitivity to one-ulp input
 * changes (about 1: as accurate as the data allow); "off": errors beyond both 1e-12 and 100
 * times that sensitivity (a wrong root or an unconverged one); wrong answers, hit for a miss
 * and miss for a hit, on unambiguous cases (+ disagreements on ambiguous ones, which are not
 * wrong); the median over repeats of ns per solve.
 *
 * Self-checks before any timing (exit 1 on failure): the reference against closed forms
 * (1-D motion, where the quartic factors into quadratics; a tiny da against da = 0).
 *
 * Timing: each class's cases are solved by every method in turn, REPEATS times (repeats
 * outermost), one thread; the median ns per solve is reported. */
#include <gsl/gsl_errno.h>
#include <gsl/gsl_poly.h>
#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "build_info.h"
#include "nbep/predict.h"
#include "predict_impl.h"
#include "bench_util.h"

/* GCC's binary128 type; __extension__ keeps -Wpedantic quiet (the one compiler extension of
 * this file, which is a benchmark, not library code). */
__extension__ typedef __float128 quad;

/* ---- cases --------------------------------------------------------------------------------- */

typedef struct pair_case {
    nbep_vec3 dp, dv, da;
    double sigma;
    double t_ref;            /* the reference contact time (rounded to double), or +inf */
    double t_ref_lo;         /* t_ref + t_ref_lo: the reference to about 32 digits */
    double sens;             /* the reference's relative change under 1-ulp input changes */
    bool ambiguous;          /* hit or miss flips under such a change: round-off decides */
} pair_case;

/* splitmix64: a fixed, portable sequence, so every run measures the same cases. */
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

/* 10^u, u uniform in [lo, hi]: log-uniform magnitudes. */
static double log_uniform(uint64_t *s, double lo_exp10, double hi_exp10)
{
    return pow(10.0, uniform(s, lo_exp10, hi_exp10));
}

static double sign(uint64_t *s)
{
    return (next_u64(s) & 1u) ? 1.0 : -1.0;
}

static nbep_vec3 unit(nbep_vec3 a)
{
    return nbep_vec3_scale(a, 1.0 / nbep_vec3_norm(a));
}

static nbep_vec3 rand_unit(uint64_t *s)
{
    for (;;) {
        nbep_vec3 a = {uniform(s, -1, 1), uniform(s, -1, 1), uniform(s, -1, 1)};
        double n2 = nbep_vec3_norm2(a);
        if (n2 > 0.01 && n2 <= 1.0)
            return unit(a);
    }
}

/* A random unit vector perpendicular to the unit vector u. */
static nbep_vec3 rand_perp(uint64_t *s, nbep_vec3 u)
{
    for (;;) {
        nbep_vec3 w = rand_unit(s);
        nbep_vec3 p = nbep_vec3_axpy(w, -nbep_vec3_dot(w, u), u);
        if (nbep_vec3_norm2(p) > 0.01)
            return unit(p);
    }
}

static nbep_vec3 rand_vec(uint64_t *s, double half)
{
    return (nbep_vec3){uniform(s, -half, half), uniform(s, -half, half), uniform(s, -half, half)};
}

/* The bench_predict mix: apart in a box a few diameters wide, half aimed at each other. */
static void random_pair(uint64_t *s, pair_case *c)
{
    c->sigma = uniform(s, 0.1, 1.0);
    do
        c->dp = rand_vec(s, 3.0);
    while (nbep_vec3_norm(c->dp) <= c->sigma * 1.01);
    c->dv = rand_vec(s, 2.0);
    if (next_u64(s) & 1u)
        c->dv = nbep_vec3_axpy(rand_vec(s, 0.3), -uniform(s, 0.3, 1.5), c->dp);
}

/* Lengths times L, times times T: every quantity keeps its units. */
static void rescale(pair_case *c, double L, double T)
{
    c->dp = nbep_vec3_scale(c->dp, L);
    c->sigma *= L;
    c->dv = nbep_vec3_scale(c->dv, L / T);
    c->da = nbep_vec3_scale(c->da, L / (T * T));
}

/* A pair that passes its closest point r_g (|r_g| = sigma (1 + eps), eps = +-1e-16..1e-12)
 * at t_g with velocity v_g perpendicular to r_g, accelerating at da: built backwards from
 * r(t) = r_g + v_g (t - t_g) + da (t - t_g)^2 / 2. With da = 0 that is the straight-line graze;
 * with da the n-component of da is made to keep t_g a local minimum of |r|. */
static void grazing_pair(uint64_t *s, pair_case *c, bool accel)
{
    c->sigma = uniform(s, 0.5, 2.0);
    nbep_vec3 n = rand_unit(s);
    double eps = sign(s) * log_uniform(s, -16.0, -12.0);
    nbep_vec3 rg = nbep_vec3_scale(n, c->sigma * (1.0 + eps));
    nbep_vec3 vg = nbep_vec3_scale(rand_perp(s, n), log_uniform(s, -1.0, 1.0));
    double tg = uniform(s, 0.1, 3.0);
    nbep_vec3 da = {0.0, 0.0, 0.0};
    if (accel) {
        da = nbep_vec3_scale(rand_unit(s), log_uniform(s, -1.0, 1.0));
        /* f''(t_g)/2 = |v_g|^2 + r_g.da > 0: a valley of |r| at t_g. */
        if (nbep_vec3_norm2(vg) + nbep_vec3_dot(rg, da) <= 0.0)
            da = nbep_vec3_axpy(da, -2.0 * nbep_vec3_dot(da, n), n);
    }
    c->da = da;
    c->dp = nbep_vec3_axpy(nbep_vec3_axpy(rg, -tg, vg), 0.5 * tg * tg, da);
    c->dv = nbep_vec3_axpy(vg, -tg, da);
}

/* Apart by a tiny gap g sigma (g = 1e-14..1e-10), closing at an angle within 80 degrees of
 * head-on; or (tangent) nearly sliding: the closing angle is eps = 1e-12..1e-2 rad from
 * tangential and the gap 1e-14..1e-6, so that hits and misses mix. */
static void near_contact_pair(uint64_t *s, pair_case *c, bool tangent)
{
    c->sigma = uniform(s, 0.5, 2.0);
    nbep_vec3 u = rand_unit(s), w = rand_perp(s, u);
    double g = tangent ? log_uniform(s, -14.0, -6.0) : log_uniform(s, -14.0, -10.0);
    c->dp = nbep_vec3_scale(u, c->sigma * (1.0 + g));
    double speed = log_uniform(s, -1.0, 1.0);
    double ang = tangent ? log_uniform(s, -12.0, -2.0) : uniform(s, 0.0, 1.4);
    /* closing component -sin(ang) along u for tangent, -cos(ang) for head-on-ish */
    double along = tangent ? -sin(ang) : -cos(ang), side = tangent ? cos(ang) : sin(ang);
    c->dv = nbep_vec3_scale(nbep_vec3_axpy(nbep_vec3_scale(u, along), side, w), speed);
}

typedef enum case_class {
    Q_RANDOM, Q_GRAZING, Q_TINY_GAP, Q_TANGENT, Q_SCALES,
    A_RANDOM, A_GRAZING, A_TINY_GAP, A_TANGENT, A_HUGE_ACCEL, A_TINY_ACCEL, A_PARALLEL,
    A_SCALES, A_RESTING, A_FROM_REST,
    N_CLASSES
} case_class;

static const struct class_info {
    const char *name;
    bool quartic;
    const char *what;
} CLASS[N_CLASSES] = {
    [Q_RANDOM] = {"q-random", false, "bench_predict's mix, da = 0"},
    [Q_GRAZING] = {"q-grazing", false, "impact parameter sigma (1 +- 1e-16..1e-12)"},
    [Q_TINY_GAP] = {"q-tiny-gap", false, "gap 1e-14..1e-10 sigma, closing within 80 deg"},
    [Q_TANGENT] = {"q-tangent", false, "gap 1e-14..1e-6 sigma, 1e-12..1e-2 rad off sliding"},
    [Q_SCALES] = {"q-scales", false, "q-random in units L, T = 1e-6..1e6 each"},
    [A_RANDOM] = {"a-random", true, "bench_predict's mix, |da| ~ 10"},
    [A_GRAZING] = {"a-grazing", true, "curved path, closest approach sigma (1 +- 1e-16..1e-12)"},
    [A_TINY_GAP] = {"a-tiny-gap", true, "q-tiny-gap with |da| = 1e-2..1e2"},
    [A_TANGENT] = {"a-tangent", true, "q-tangent with |da| = 1e-2..1e2"},
    [A_HUGE_ACCEL] = {"a-huge-accel", true, "|da| = 1e2..1e8 |dv|^2/|dp|"},
    [A_TINY_ACCEL] = {"a-tiny-accel", true, "|da| = 1e-12..1e-2 |dv|^2/|dp|"},
    [A_PARALLEL] = {"a-parallel", true, "da within 1e-12..1e-3 rad of +-dv"},
    [A_SCALES] = {"a-scales", true, "a-random in units L, T = 1e-6..1e6 each"},
    [A_RESTING] = {"a-resting", true, "gap 1e-16..1e-12, |dv| 1e-12..1e-6, da pressing"},
    [A_FROM_REST] = {"a-from-rest", true, "dv = 0 exactly, random dp and da"},
};

static void make_case(case_class k, uint64_t *s, pair_case *c)
{
    *c = (pair_case){{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, 1.0, 0.0, 0.0, 0.0, false};
    switch (k) {
    case Q_RANDOM:
    case A_RANDOM:
        random_pair(s, c);
        break;
    case Q_GRAZING:
    case A_GRAZING:
        grazing_pair(s, c, k == A_GRAZING);
        return;
    case Q_TINY_GAP:
    case A_TINY_GAP:
        near_contact_pair(s, c, false);
        break;
    case Q_TANGENT:
    case A_TANGENT:
        near_contact_pair(s, c, true);
        break;
    case Q_SCALES:
    case A_SCALES:
        random_pair(s, c);
        break;
    case A_HUGE_ACCEL:
    case A_TINY_ACCEL: {
        random_pair(s, c);
        double scale = nbep_vec3_norm2(c->dv) / nbep_vec3_norm(c->dp);
        double ratio = k == A_HUGE_ACCEL ? log_uniform(s, 2.0, 8.0) : log_uniform(s, -12.0, -2.0);
        c->da = nbep_vec3_scale(rand_unit(s), scale * ratio);
        return;
    }
    case A_PARALLEL: {
        random_pair(s, c);
        nbep_vec3 u = unit(c->dv), w = rand_perp(s, u);
        double ang = log_uniform(s, -12.0, -3.0);
        nbep_vec3 dir = nbep_vec3_axpy(nbep_vec3_scale(u, cos(ang)), sin(ang), w);
        c->da = nbep_vec3_scale(dir, sign(s) * log_uniform(s, -1.0, 1.0) *
                                         nbep_vec3_norm2(c->dv) / nbep_vec3_norm(c->dp));
        return;
    }
    case A_RESTING: {
        c->sigma = uniform(s, 0.5, 2.0);
        nbep_vec3 u = rand_unit(s);
        c->dp = nbep_vec3_scale(u, c->sigma * (1.0 + log_uniform(s, -16.0, -12.0)));
        c->dv = nbep_vec3_scale(rand_unit(s), log_uniform(s, -12.0, -6.0));
        /* pressing: the component of da along u points inwards (g pulls the top sphere down) */
        nbep_vec3 a = nbep_vec3_scale(rand_unit(s), uniform(s, 1.0, 20.0));
        if (nbep_vec3_dot(a, u) > 0.0)
            a = nbep_vec3_axpy(a, -2.0 * nbep_vec3_dot(a, u), u);
        c->da = a;
        return;
    }
    case A_FROM_REST:
        random_pair(s, c);
        c->dv = (nbep_vec3){0.0, 0.0, 0.0};
        c->da = nbep_vec3_scale(rand_unit(s), log_uniform(s, -1.0, 1.0));
        if (next_u64(s) & 1u)       /* half pulled roughly towards each other */
            c->da = nbep_vec3_axpy(nbep_vec3_scale(rand_unit(s), 0.3), -1.0, unit(c->dp));
        return;
    case N_CLASSES:
        break;
    }
    if (CLASS[k].quartic)
        c->da = nbep_vec3_scale(rand_unit(s), k == A_RANDOM || k == A_SCALES
                                                  ? uniform(s, 0.5, 17.0)
                                                  : log_uniform(s, -2.0, 2.0));
    if (k == Q_SCALES || k == A_SCALES)
        rescale(c, log_uniform(s, -6.0, 6.0), log_uniform(s, -6.0, 6.0));
}

/* ---- quad-precision reference --------------------------------------------------------------- */

#define QNEVER ((quad)INFINITY)

/* sqrt in binary128: two Newton steps from the double root (53 -> 106 -> 113+ bits). */
static quad q_sqrt(quad a)
{
    if (!(a > 0))
        return 0;
    quad x = sqrt((double)a);
    x = 0.5 * (x + a / x);
    x = 0.5 * (x + a / x);
    return x;
}

static quad q_abs(quad a)
{
    return a < 0 ? -a : a;
}

typedef struct qcase {
    quad p[3], v[3], a[3], s2;   /* dp, dv, da (exact), sigma^2 (exact) */
} qcase;

static qcase q_make(const pair_case *c)
{
    qcase q = {{c->dp.x, c->dp.y, c->dp.z}, {c->dv.x, c->dv.y, c->dv.z},
               {c->da.x, c->da.y, c->da.z}, (quad)c->sigma * (quad)c->sigma};
    return q;
}

static quad q_dot(const quad *x, const quad *y)
{
    return x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
}

/* f, f', f'' of f(t) = |r|^2 - sigma^2, r = p + v t + a t^2/2, from r(t) directly. */
static quad q_f(const qcase *q, quad t)
{
    quad r[3];
    for (int i = 0; i < 3; i++)
        r[i] = q->p[i] + t * (q->v[i] + 0.5 * t * q->a[i]);
    return q_dot(r, r) - q->s2;
}

static quad q_f1(const qcase *q, quad t)
{
    quad r[3], rd[3];
    for (int i = 0; i < 3; i++) {
        r[i] = q->p[i] + t * (q->v[i] + 0.5 * t * q->a[i]);
        rd[i] = q->v[i] + t * q->a[i];
    }
    return 2 * q_dot(r, rd);
}

static quad q_f2(const qcase *q, quad t)
{
    quad r[3], rd[3];
    for (int i = 0; i < 3; i++) {
        r[i] = q->p[i] + t * (q->v[i] + 0.5 * t * q->a[i]);
        rd[i] = q->v[i] + t * q->a[i];
    }
    return 2 * (q_dot(rd, rd) + q_dot(r, q->a));
}

typedef quad (*q_fun)(const qcase *, quad);

/* The sign change of F in (lo, hi] (F(lo) and F(hi) on opposite sides of zero, or F(hi) = 0)
 * to 1e-30 relative: Newton on F inside the bracket, a bisection whenever Newton would leave
 * it or has not halved it in two steps. */
static quad q_refine(const qcase *q, q_fun F, q_fun dF, quad lo, quad hi)
{
    bool lo_pos = F(q, lo) > 0;
    quad t = 0.5 * (lo + hi), width_before = hi - lo;
    for (int it = 0; it < 600; it++) {
        quad ft = F(q, t);
        if (ft == 0)
            return t;
        if ((ft > 0) == lo_pos)
            lo = t;
        else
            hi = t;
        if (hi - lo <= (quad)1e-30 * hi)
            break;
        quad tn = t - ft / dF(q, t);
        bool stalled = (it % 2 == 1) && (hi - lo) > 0.5 * width_before;
        if (it % 2 == 1)
            width_before = hi - lo;
        if (!(tn > lo && tn < hi) || stalled)
            tn = 0.5 * (lo + hi);
        else if (q_abs(tn - t) <= (quad)1e-32 * q_abs(t))
            return tn;
        t = tn;
    }
    return 0.5 * (lo + hi);
}

/* Real roots in (0, hi) of c2 t^2 + c1 t + c0, ascending (c2 may be 0). */
static int q_quadratic_roots(quad c2, quad c1, quad c0, quad hi, quad out[2])
{
    quad r[2];
    int n = 0;
    if (c2 == 0) {
        if (c1 != 0)
            r[n++] = -c0 / c1;
    } else {
        quad disc = c1 * c1 - 4 * c2 * c0;
        if (disc < 0)
            return 0;
        quad sq = q_sqrt(disc);
        quad qq = -0.5 * (c1 + (c1 < 0 ? -sq : sq));
        if (qq == 0) {
            r[n++] = 0;
        } else {
            r[n++] = qq / c2;
            r[n++] = c0 / qq;
        }
        if (n == 2 && r[0] > r[1]) {
            quad tmp = r[0];
            r[0] = r[1];
            r[1] = tmp;
        }
    }
    int m = 0;
    for (int i = 0; i < n; i++)
        if (r[i] > 0 && r[i] < hi)
            out[m++] = r[i];
    return m;
}

/* An upper bound on |root| of sum_k c[k] t^k (degree deg, c[deg] != 0): Fujiwara's
 * 2 max_k |c_k/c_deg|^(1/(deg-k)), computed in double with a margin of 2 for its rounding. */
static quad q_root_bound(const quad *c, int deg)
{
    double best = 0.0;
    for (int k = 0; k < deg; k++) {
        double ratio = fabs((double)(c[k] / c[deg]));
        if (k == 0)
            ratio *= 0.5;
        double b = pow(ratio, 1.0 / (deg - k));
        best = b > best ? b : best;
    }
    return (quad)(4.0 * best) + 1e-300;
}

static double ulp(double x)
{
    return x == 0.0 ? 0.0 : ldexp(1.0, ilogb(x) - (DBL_MANT_DIG - 1));
}

/* The most f(t) can move when every input moves by one ulp (zeros excepted), to first order:
 * df/dp = 2r, df/dv = 2r t, df/da = r t^2, df/dsigma = -2 sigma. At a valley of f (f' = 0)
 * this is also how far its floor can move, t itself moving only to second order. */
static quad q_round_off(const pair_case *c, const qcase *q, quad t)
{
    const double *p = &c->dp.x, *v = &c->dv.x, *a = &c->da.x;
    double td = (double)t, sum = 2.0 * c->sigma * ulp(c->sigma);
    for (int i = 0; i < 3; i++) {
        double r = fabs((double)(q->p[i] + t * (q->v[i] + 0.5 * t * q->a[i])));
        sum += r * (2.0 * ulp(p[i]) + 2.0 * td * ulp(v[i]) + td * td * ulp(a[i]));
    }
    return sum;
}

/* Does some valley of f in [0, t_last] (t = 0 included: the gap itself) have a floor within
 * round-off of contact, so that one-ulp changes of the inputs could turn it from a miss into a
 * hit or back? */
static bool q_valley_at_round_off(const pair_case *c, const qcase *q, const quad *t, int n)
{
    for (int i = 0; i < n; i++)
        if ((t[i] == 0 || q_f2(q, t[i]) > 0) && q_abs(q_f(q, t[i])) <= q_round_off(c, q, t[i]))
            return true;
    return false;
}

/* The reference: the first t > 0 with f(t) <= 0, for a pair apart at t = 0; +inf if none;
 * -1 if not apart. *round_off (may be NULL): whether round-off in the inputs decides hit or
 * miss (see q_valley_at_round_off). */
static quad q_contact_flag(const pair_case *c, bool *round_off)
{
    qcase q = q_make(c);
    quad f0 = q_f(&q, 0);
    bool dummy;
    round_off = round_off ? round_off : &dummy;
    *round_off = false;
    if (!(f0 > 0))
        return -1;           /* not apart: the generators exclude this */
    bool accel = c->da.x != 0.0 || c->da.y != 0.0 || c->da.z != 0.0;
    if (!accel) {
        quad b = q_dot(q.p, q.v), vv = q_dot(q.v, q.v);
        quad valley[2] = {0, vv > 0 && b < 0 ? -b / vv : 0};
        *round_off = q_valley_at_round_off(c, &q, valley, 2);
        if (!(b < 0))
            return QNEVER;
        quad disc = b * b - vv * f0;
        if (disc < 0)
            return QNEVER;
        return f0 / (-b + q_sqrt(disc));
    }
    /* f = sum a_k t^k; f' = sum k a_k t^(k-1); f''/2 as in q_f2 */
    quad a[5] = {f0, 2 * q_dot(q.p, q.v), q_dot(q.v, q.v) + q_dot(q.p, q.a), q_dot(q.v, q.a),
                 0.25 * q_dot(q.a, q.a)};
    quad d1[4] = {a[1], 2 * a[2], 3 * a[3], 4 * a[4]};
    quad B = q_root_bound(a, 4);
    quad B1 = q_root_bound(d1, 3);
    B = B1 > B ? B1 : B;
    /* pieces where f' is monotone: split at the roots of f'' = 12 a4 t^2 + 6 a3 t + 2 a2 */
    quad knot[4] = {0};
    int n_knot = 1;
    n_knot += q_quadratic_roots(12 * a[4], 6 * a[3], 2 * a[2], B, knot + 1);
    knot[n_knot++] = B;
    quad crit[6] = {0};
    int n_crit = 1;
    for (int i = 0; i + 1 < n_knot; i++) {
        quad gu = q_f1(&q, knot[i]), gw = q_f1(&q, knot[i + 1]);
        if ((gu < 0 && gw > 0) || (gu > 0 && gw < 0))
            crit[n_crit++] = q_refine(&q, q_f1, q_f2, knot[i], knot[i + 1]);
        else if (gw == 0 && i + 2 < n_knot)
            crit[n_crit++] = knot[i + 1];
    }
    crit[n_crit++] = B;
    for (int i = 0; i + 1 < n_crit; i++) {
        if (q_f(&q, crit[i + 1]) <= 0) {
            *round_off = q_valley_at_round_off(c, &q, crit, i + 2);
            return q_refine(&q, q_f, q_f1, crit[i], crit[i + 1]);
        }
    }
    *round_off = q_valley_at_round_off(c, &q, crit, n_crit - 1);
    return QNEVER;
}

static quad q_contact(const pair_case *c)
{
    return q_contact_flag(c, NULL);
}

/* The inputs moved by one ulp each, in a random direction (zeros stay zero, so that a pair
 * keeps its kind: da = 0 stays the quadratic). */
static pair_case perturbed(const pair_case *c, uint64_t *s)
{
    pair_case p = *c;
    double *v[10] = {&p.dp.x, &p.dp.y, &p.dp.z, &p.dv.x, &p.dv.y, &p.dv.z,
                     &p.da.x, &p.da.y, &p.da.z, &p.sigma};
    for (int i = 0; i < 10; i++)
        if (*v[i] != 0.0)
            *v[i] = nextafter(*v[i], (next_u64(s) & 1u) ? INFINITY : -INFINITY);
    return p;
}

/* How much the reference itself moves when the inputs move by an ulp (PERTURBATIONS random
 * draws): the accuracy a double-precision method can be asked for. A case is ambiguous when
 * a valley of f has its floor within round-off of contact (q_valley_at_round_off), or when
 * a perturbation flips hit and miss: round-off in the inputs decides it, so no answer is
 * wrong there. */
enum { PERTURBATIONS = 2 };

static void reference(pair_case *c, uint64_t *s)
{
    bool round_off;
    quad t = q_contact_flag(c, &round_off);
    c->t_ref = (double)t;
    c->t_ref_lo = isinf(c->t_ref) ? 0.0 : (double)(t - (quad)c->t_ref);
    c->ambiguous = round_off;
    c->sens = round_off ? INFINITY : 0.0;
    for (int k = 0; k < PERTURBATIONS; k++) {
        pair_case p = perturbed(c, s);
        quad tp = q_contact(&p);
        if (tp < 0 || isinf((double)tp) != isinf((double)t)) {
            c->ambiguous = true;
            c->sens = INFINITY;     /* any answer is as good as the data */
        } else if (!isinf((double)t) && !c->ambiguous) {
            double rel = t > 0 ? (double)(q_abs(tp - t) / t) : 0.0;
            c->sens = rel > c->sens ? rel : c->sens;
        }
    }
}

/* ---- the alternatives ----------------------------------------------------------------------- */

static double textbook_quadratic(nbep_vec3 dp, nbep_vec3 dv, double sigma)
{
    double b = nbep_vec3_dot(dp, dv);
    if (!(b < 0.0))
        return NBEP_NEVER;
    double c = nbep_vec3_dot(dp, dp) - sigma * sigma, vv = nbep_vec3_dot(dv, dv);
    if (c <= 0.0)
        return 0.0;
    double disc = b * b - vv * c;
    if (!(disc >= 0.0))
        return NBEP_NEVER;
    return (-b - sqrt(disc)) / vv;
}

/* nbep's quadratic with the discriminant in the form that cancels least. At grazing
 * incidence disc = b^2 - |dv|^2 c is a small difference; by Lagrange's identity it equals
 * |dv|^2 sigma^2 - |dp x dv|^2. With s the distance still to fly to the closest approach,
 * b^2 = |dv|^2 s^2: the first form subtracts two numbers of size |dv|^2 s^2 (b's own rounding
 * is eps |dp| |dv|), the second two of size |dv|^2 sigma^2. So the first is used while the pair
 * is within about sigma of its closest approach (b^2 < |dv|^2 sigma^2), the second farther
 * out, where it is better by (s / sigma)^2. */
static double cross_quadratic(nbep_vec3 dp, nbep_vec3 dv, double sigma)
{
    double b = nbep_vec3_dot(dp, dv);
    if (!(b < 0.0))
        return NBEP_NEVER;
    double pp = nbep_vec3_dot(dp, dp);
    double c = pp - sigma * sigma;
    if (!(c > 0.5 * pp))
        c = nbep__predict_gap2(dp, sigma);
    if (c <= 0.0)
        return 0.0;
    double vv = nbep_vec3_dot(dv, dv), vs = vv * (sigma * sigma), disc;
    if (b * b < vs) {
        disc = b * b - vv * c;
    } else {
        nbep_vec3 x = {dp.y * dv.z - dp.z * dv.y, dp.z * dv.x - dp.x * dv.z,
                       dp.x * dv.y - dp.y * dv.x};
        disc = vs - nbep_vec3_dot(x, x);
    }
    if (!(disc >= 0.0))
        return NBEP_NEVER;
    return c / (-b + sqrt(disc));
}

/* r(t), r'(t) in double. */
static nbep_vec3 r_at(const pair_case *c, double t)
{
    return nbep_vec3_axpy(nbep_vec3_axpy(c->dp, t, c->dv), 0.5 * t * t, c->da);
}

static bool closing_at(const pair_case *c, double t)
{
    return nbep_vec3_dot(r_at(c, t), nbep_vec3_axpy(c->dv, t, c->da)) < 0.0;
}

/* The quartic's coefficients, lowest degree first, plainly in double. */
static void quartic_coef(const pair_case *c, double a[5])
{
    a[4] = 0.25 * nbep_vec3_dot(c->da, c->da);
    a[3] = nbep_vec3_dot(c->dv, c->da);
    a[2] = nbep_vec3_dot(c->dv, c->dv) + nbep_vec3_dot(c->dp, c->da);
    a[1] = 2.0 * nbep_vec3_dot(c->dp, c->dv);
    a[0] = nbep_vec3_dot(c->dp, c->dp) - c->sigma * c->sigma;
}

/* A root whose imaginary part is below this fraction of its modulus counts as real (what a
 * user of gsl_poly_complex_solve without rescaling would pick). */
#define RAW_IMAG_TOL 1e-8

static double gsl_raw(const pair_case *c, gsl_poly_complex_workspace *w)
{
    double a[5], z[8];
    quartic_coef(c, a);
    if (gsl_poly_complex_solve(a, 5, w, z) != GSL_SUCCESS)
        return NBEP_NEVER;
    double best = NBEP_NEVER;
    for (int i = 0; i < 4; i++) {
        double x = z[2 * i], y = z[2 * i + 1];
        if (fabs(y) <= RAW_IMAG_TOL * hypot(x, y) && x >= 0.0 && x < best && closing_at(c, x))
            best = x;
    }
    return best;
}

/* f(t) exactly as predict.c evaluates it (compensated f(0), and for t > 0 the rounding of
 * dp + w carried): its own code, through predict_impl.h. */
static double f_comp(const pair_case *c, double t)
{
    return nbep__predict_f(c->dp, c->dv, c->da, c->sigma, t);
}

static double f1_d(const pair_case *c, double t)
{
    return 2.0 * nbep_vec3_dot(r_at(c, t), nbep_vec3_axpy(c->dv, t, c->da));
}

static double f2_d(const pair_case *c, double t)
{
    nbep_vec3 rd = nbep_vec3_axpy(c->dv, t, c->da);
    return 2.0 * (nbep_vec3_dot(rd, rd) + nbep_vec3_dot(r_at(c, t), c->da));
}

/* Newton polish of the quartic from t0, up to QN_MAX steps. */
enum { QN_MAX = 8 };

static double quad_newton(const pair_case *c)
{
    double a[5];
    quartic_coef(c, a);
    a[0] = nbep__predict_gap2(c->dp, c->sigma);
    /* first positive root of a2 t^2 + a1 t + a0 (the closing root when a2 > 0) */
    double t;
    if (a[2] != 0.0) {
        /* a2 > 0: both roots positive only when closing now (a1 < 0); a2 < 0: one positive */
        double disc = a[1] * a[1] - 4.0 * a[2] * a[0];
        if (!(disc >= 0.0) || (a[2] > 0.0 && !(a[1] < 0.0)))
            return NBEP_NEVER;
        t = 2.0 * a[0] / (-a[1] + sqrt(disc));
    } else {
        if (!(a[1] < 0.0))
            return NBEP_NEVER;
        t = a[0] / -a[1];
    }
    for (int k = 0; k < QN_MAX; k++) {
        double step = f_comp(c, t) / f1_d(c, t);
        if (!isfinite(step))
            break;
        t -= step;
        if (fabs(step) <= 4.0 * DBL_EPSILON * fabs(t))
            break;
    }
    return t >= 0.0 && isfinite(t) && closing_at(c, t) ? t : NBEP_NEVER;
}

/* nbep's near-contact threshold (NEAR_CONTACT_REL in predict.c): pairs this close go to its
 * bracket search. */
#define NEAR_CONTACT 1e-6
/* The certificate below asks the terms of f'/2 beyond a1/2 to add up to at most this fraction
 * of |a1|/2 on [0, t]: the coefficients' own rounding (a few ulps of their terms) is then
 * far below the margin. */
#define CERT_MARGIN 0.5

/* Near contact and closing (a0 <= NEAR_CONTACT sigma^2, a1 < 0), the contact is usually the
 * truncated quadratic's root, polished by Newton; it is certified when f' < 0 on [0, t_hi]
 * is guaranteed by max(0, a2 t) + 1.5 |a3| t^2 + 2 a4 t^3 <= CERT_MARGIN |a1|/2 (f'/2 = a1/2
 * + a2 t + 1.5 a3 t^2 + 2 a4 t^3): f then falls monotonically from f(0) > 0, so a root
 * bracketed by f(t_lo) > 0 >= f(t_hi) is the first. Anything else goes to nbep_predict_pair
 * unchanged. */
static double near_newton(const pair_case *c, nbep_predict_ws *ws)
{
    double a[5];
    quartic_coef(c, a);
    a[0] = nbep__predict_gap2(c->dp, c->sigma);
    if (a[0] > 0.0 && a[0] <= NEAR_CONTACT * c->sigma * c->sigma && a[1] < 0.0) {
        double disc = a[1] * a[1] - 4.0 * a[2] * a[0];
        double t = disc >= 0.0 ? 2.0 * a[0] / (-a[1] + sqrt(disc)) : a[0] / -a[1];
        double step = 0.0;
        for (int k = 0; k < QN_MAX; k++) {
            step = f_comp(c, t) / f1_d(c, t);
            if (!isfinite(step))
                break;
            t -= step;
            if (fabs(step) <= 4.0 * DBL_EPSILON * fabs(t))
                break;
        }
        double slack = fabs(step) + 4.0 * DBL_EPSILON * fabs(t);
        double t_lo = t - slack, t_hi = t + slack;
        /* a2 t is linear: on [0, t_hi] at most max(0, a2 t_hi); a pair pressed together
         * (a2 < 0) only closes faster */
        double rest = fmax(0.0, a[2] * t_hi) + 1.5 * fabs(a[3]) * t_hi * t_hi +
                      2.0 * a[4] * t_hi * t_hi * t_hi;
        if (t_lo >= 0.0 && rest <= CERT_MARGIN * 0.5 * -a[1] && f_comp(c, t_hi) <= 0.0 &&
            (t_lo == 0.0 || f_comp(c, t_lo) > 0.0))
            return t;
    }
    return nbep_predict_pair(c->dp, c->dv, c->da, c->sigma, ws);
}

typedef double (*d_fun)(const pair_case *, double);

/* The sign change of F in (lo, hi]: Newton inside a shrinking bracket, bisection when Newton
 * leaves it or has not halved it in two steps; stops at adjacent doubles or a Newton step
 * below 2 ulps. */
static double d_refine(const pair_case *c, d_fun F, d_fun dF, double lo, double hi)
{
    bool lo_pos = F(c, lo) > 0.0;
    double t = 0.5 * (lo + hi), width_before = hi - lo;
    for (int it = 0; it < 200; it++) {
        double ft = F(c, t);
        if (ft == 0.0)
            return t;
        if ((ft > 0.0) == lo_pos)
            lo = t;
        else
            hi = t;
        if (nextafter(lo, INFINITY) >= hi)
            return hi;
        double tn = t - ft / dF(c, t);
        bool stalled = (it % 2 == 1) && (hi - lo) > 0.5 * width_before;
        if (it % 2 == 1)
            width_before = hi - lo;
        if (!(tn > lo && tn < hi) || stalled)
            tn = 0.5 * (lo + hi);
        else if (fabs(tn - t) <= 2.0 * DBL_EPSILON * fabs(t))
            return tn;
        t = tn;
    }
    return hi;
}

static int d_quadratic_roots(double c2, double c1, double c0, double hi, double out[2])
{
    double big = fmax(fabs(c2), fmax(fabs(c1), fabs(c0)));
    if (!(big > 0.0))
        return 0;
    c2 /= big;
    c1 /= big;
    c0 /= big;
    double r[2];
    int n = 0;
    if (c2 == 0.0) {
        if (c1 != 0.0)
            r[n++] = -c0 / c1;
    } else {
        double disc = c1 * c1 - 4.0 * c2 * c0;
        if (!(disc >= 0.0))
            return 0;
        double qq = -0.5 * (c1 + copysign(sqrt(disc), c1));
        r[n++] = qq / c2;
        r[n++] = qq != 0.0 ? c0 / qq : 0.0;
        if (r[0] > r[1]) {
            double tmp = r[0];
            r[0] = r[1];
            r[1] = tmp;
        }
    }
    int m = 0;
    for (int i = 0; i < n; i++)
        if (r[i] > 0.0 && r[i] < hi)
            out[m++] = r[i];
    return m;
}

static double d_root_bound(const double *a, int deg)
{
    double best = 0.0;
    for (int k = 0; k < deg; k++) {
        double ratio = fabs(a[k] / a[deg]) * (k == 0 ? 0.5 : 1.0);
        double b = deg - k == 1 ? ratio : deg - k == 2 ? sqrt(ratio) : pow(ratio, 1.0 / (deg - k));
        best = b > best ? b : best;
    }
    return 2.0 * best * (1.0 + 1e-12);
}

static double piece_newton(const pair_case *c)
{
    double a[5];
    quartic_coef(c, a);
    a[0] = nbep__predict_gap2(c->dp, c->sigma);
    if (!(a[0] > 0.0))
        return a[1] < 0.0 ? 0.0 : nbep__predict_pair_bracket(c->dp, c->dv, c->da, c->sigma);
    if (!(a[4] > 0.0))
        return nbep_predict_pair_quadratic(c->dp, c->dv, c->sigma);
    double d1[4] = {a[1], 2.0 * a[2], 3.0 * a[3], 4.0 * a[4]};
    double B = fmax(d_root_bound(a, 4), d_root_bound(d1, 3));
    if (!isfinite(B))
        return NBEP_NEVER;
    double knot[4] = {0.0};
    int n_knot = 1;
    n_knot += d_quadratic_roots(12.0 * a[4], 6.0 * a[3], 2.0 * a[2], B, knot + 1);
    knot[n_knot++] = B;
    double crit[6] = {0.0};
    int n_crit = 1;
    for (int i = 0; i + 1 < n_knot; i++) {
        double gu = f1_d(c, knot[i]), gw = f1_d(c, knot[i + 1]);
        if ((gu < 0.0 && gw > 0.0) || (gu > 0.0 && gw < 0.0))
            crit[n_crit++] = d_refine(c, f1_d, f2_d, knot[i], knot[i + 1]);
    }
    crit[n_crit++] = B;
    for (int i = 0; i + 1 < n_crit; i++) {
        double u = crit[i], w = crit[i + 1];
        if (!(w > u))
            continue;
        if (f_comp(c, w) <= 0.0)
            return d_refine(c, f_comp, f1_d, u, w);
    }
    return NBEP_NEVER;
}

/* ---- methods table -------------------------------------------------------------------------- */

typedef enum method {
    M_NBEP_QUADRATIC, M_TEXTBOOK, M_CROSS,
    M_NBEP_GSL, M_NBEP_BRACKET, M_GSL_RAW, M_QUAD_NEWTON, M_PIECE_NEWTON, M_NEAR_NEWTON,
    N_METHODS
} method;

static const struct method_info {
    const char *name;
    bool quartic;
} METHOD[N_METHODS] = {
    [M_NBEP_QUADRATIC] = {"nbep-quadratic", false}, [M_TEXTBOOK] = {"textbook", false},
    [M_CROSS] = {"cross-disc", false},
    [M_NBEP_GSL] = {"nbep-gsl", true}, [M_NBEP_BRACKET] = {"nbep-bracket", true},
    [M_GSL_RAW] = {"gsl-raw", true}, [M_QUAD_NEWTON] = {"quad-newton", true},
    [M_PIECE_NEWTON] = {"piece-newton", true}, [M_NEAR_NEWTON] = {"near-newton", true},
};

typedef struct solver_ctx {
    nbep_predict_ws *ws;                /* borrowed */
    gsl_poly_complex_workspace *raw;    /* borrowed */
} solver_ctx;

static double solve(method m, const pair_case *c, const solver_ctx *x)
{
    switch (m) {
    case M_NBEP_QUADRATIC:
        return nbep_predict_pair_quadratic(c->dp, c->dv, c->sigma);
    case M_TEXTBOOK:
        return textbook_quadratic(c->dp, c->dv, c->sigma);
    case M_CROSS:
        return cross_quadratic(c->dp, c->dv, c->sigma);
    case M_NBEP_GSL:
        return nbep_predict_pair(c->dp, c->dv, c->da, c->sigma, x->ws);
    case M_NBEP_BRACKET:
        return nbep__predict_pair_bracket(c->dp, c->dv, c->da, c->sigma);
    case M_GSL_RAW:
        return gsl_raw(c, x->raw);
    case M_QUAD_NEWTON:
        return quad_newton(c);
    case M_PIECE_NEWTON:
        return piece_newton(c);
    case M_NEAR_NEWTON:
        return near_newton(c, x->ws);
    case N_METHODS:
        break;
    }
    return NAN;
}

/* ---- measuring ------------------------------------------------------------------------------ */

/* A relative error counts as "off" when it exceeds both OFF_RTOL and OFF_SENS times the
 * reference's own sensitivity to a one-ulp change of the inputs: a wrong root, or a root
 * not converged as far as the data allow. OFF_RTOL is nbep's acceptance threshold for a
 * polished root (ROOT_STEP_TOL in predict.c); a backward-stable method's error is a small
 * multiple of the sensitivity (a few ulps of input error per operation), 100 leaves room. */
#define OFF_RTOL 1e-12
#define OFF_SENS 100.0

typedef struct stats {
    size_t hits_ref, ambiguous, both, wrong_hit, wrong_miss, round_off, off, nan;
    double median, p99, max, max_excess;
    double ns;
} stats;

static stats measure_accuracy(const pair_case *c, size_t n, method m, const solver_ctx *x,
                              double *err, bool show)
{
    stats st = {0};
    size_t n_err = 0;
    for (size_t i = 0; i < n; i++) {
        double t = solve(m, &c[i], x);
        bool hit_ref = isfinite(c[i].t_ref), hit = isfinite(t);
        st.hits_ref += hit_ref;
        st.ambiguous += c[i].ambiguous;
        if (isnan(t)) {
            st.nan++;
            continue;
        }
        if (show && (hit_ref != hit || (hit && fabs(t - c[i].t_ref) > 1e-6 * c[i].t_ref)))
            fprintf(stderr, "%s case %zu: dp {%a, %a, %a} dv {%a, %a, %a} da {%a, %a, %a} "
                            "sigma %a: %.17g, reference %.17g (sensitivity %.2g%s)\n",
                    METHOD[m].name, i, c[i].dp.x, c[i].dp.y, c[i].dp.z, c[i].dv.x, c[i].dv.y,
                    c[i].dv.z, c[i].da.x, c[i].da.y, c[i].da.z, c[i].sigma, t, c[i].t_ref,
                    c[i].sens, c[i].ambiguous ? ", ambiguous" : "");
        if (hit_ref != hit) {
            if (c[i].ambiguous)
                st.round_off++;
            else if (hit)
                st.wrong_hit++;
            else
                st.wrong_miss++;
        } else if (hit) {
            double e = c[i].t_ref > 0.0 ? fabs(t - c[i].t_ref) / c[i].t_ref
                                        : (t == 0.0 ? 0.0 : INFINITY);
            err[n_err++] = e;
            double excess = c[i].ambiguous ? 0.0 : e / fmax(c[i].sens, DBL_EPSILON);
            st.max_excess = excess > st.max_excess ? excess : st.max_excess;
            st.off += e > OFF_RTOL && e > OFF_SENS * c[i].sens;
        }
    }
    st.both = n_err;
    if (n_err) {
        qsort(err, n_err, sizeof *err, bench_cmp_double);
        st.median = err[n_err / 2];
        st.p99 = err[(size_t)(0.99 * (double)(n_err - 1))];
        st.max = err[n_err - 1];
    }
    return st;
}

static double time_once(const pair_case *c, size_t n, method m, const solver_ctx *x,
                        double *sink)
{
    double sum = 0.0, t0 = nbep_now();
    for (size_t i = 0; i < n; i++) {
        double t = solve(m, &c[i], x);
        sum += isfinite(t) ? t : 1.0;
    }
    double ns = 1e9 * (nbep_now() - t0) / (double)n;
    *sink += sum;
    return ns;
}

/* ---- self-checks of the reference ----------------------------------------------------------- */

/* Collinear motion along u: r = x(t) u with x = x0 + v t + a t^2/2, so |r| = sigma at the
 * first root of x(t) = sigma (coming from x0 > sigma); x0 + v t + a t^2/2 - sigma = 0 in
 * closed form, in long double. */
static int check_reference(void)
{
    int bad = 0;
    const double cases[][3] = {{3.17, -1.43, 0.0}, {3.17, -1.43, 0.61}, {3.17, 0.83, -2.9},
                               {2.0, 0.0, -0.37}, {5.5, 1.2, 0.05}, {1.0 + 1e-12, -0.7, 3.3}};
    const nbep_vec3 slanted = unit((nbep_vec3){0.29, -1.13, 0.61}), axis = {0.0, 0.0, 1.0};
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        double x0 = cases[k][0], v = cases[k][1], a = cases[k][2], sigma = 1.0;
        /* Along a slanted u the inputs are x0 u etc. rounded, which moves the contact by
         * ~1e-16 relative; a gap of 1e-12 would magnify that 1e4 times, so that case runs
         * along an axis, where the inputs are exact. */
        nbep_vec3 u = x0 - sigma < 1e-6 ? axis : slanted;
        pair_case c = {nbep_vec3_scale(u, x0), nbep_vec3_scale(u, v), nbep_vec3_scale(u, a),
                       sigma, 0.0, 0.0, 0.0, false};
        long double X0 = (long double)x0, V = v, A = a;
        long double g = X0 - sigma, expect;
        if (A == 0.0L) {
            expect = V < 0.0L ? g / -V : INFINITY;
        } else {
            long double disc = V * V - 2.0L * A * g;
            if (disc < 0.0L)
                expect = INFINITY;
            else {
                long double qq = -(V + (V < 0 ? -sqrtl(disc) : sqrtl(disc)));
                long double r1 = qq / A, r2 = 2.0L * g / qq;
                long double lo = fminl(r1, r2), hi = fmaxl(r1, r2);
                expect = lo > 0.0L ? lo : (hi > 0.0L ? hi : INFINITY);
            }
        }
        double got = (double)q_contact(&c);
        bool ok = isinf((double)expect) ? isinf(got)
                                        : fabs(got - (double)expect) <= 1e-13 * (double)expect;
        if (!ok) {
            fprintf(stderr, "bench_contact: reference case %zu: %.17g, expected %.17Lg\n", k,
                    got, expect);
            bad++;
        }
    }
    /* A 3-D quartic with a tiny acceleration tends to the quadratic (the quad closed form). */
    pair_case c = {{2.93, -0.41, 0.77}, {-1.43, 0.2, -0.38}, {1e-9, -2e-9, 0.5e-9}, 0.83, 0.0,
                   0.0, 0.0, false};
    pair_case c0 = c;
    c0.da = (nbep_vec3){0.0, 0.0, 0.0};
    double tq = (double)q_contact(&c), t0 = (double)q_contact(&c0);
    if (!(fabs(tq - t0) <= 1e-7 * t0)) {
        fprintf(stderr, "bench_contact: reference: tiny da %.17g vs da = 0 %.17g\n", tq, t0);
        bad++;
    }
    return bad;
}

/* ---- main ----------------------------------------------------------------------------------- */

static void usage(void)
{
    fprintf(stderr, "usage: bench_contact [--quick] [--cases N] [--repeats R] [--csv FILE] "
                    "[--dump FILE] [--show METHOD]\n");
}

int main(int argc, char **argv)
{
    size_t n = 4000;
    int repeats = 7;
    const char *csv_path = NULL, *dump_path = NULL, *show_method = NULL;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--quick")) {
            n = 500;
            repeats = 3;
        } else if (!strcmp(argv[i], "--cases") && i + 1 < argc) {
            n = (size_t)strtoull(argv[++i], NULL, 10);
        } else if (!strcmp(argv[i], "--repeats") && i + 1 < argc) {
            repeats = atoi(argv[++i]);
        } else if (!strcmp(argv[i], "--csv") && i + 1 < argc) {
            csv_path = argv[++i];
        } else if (!strcmp(argv[i], "--dump") && i + 1 < argc) {
            dump_path = argv[++i];
        } else if (!strcmp(argv[i], "--show") && i + 1 < argc) {
            show_method = argv[++i];
        } else {
            usage();
            return 2;
        }
    }
    if (n == 0 || repeats < 1) {
        usage();
        return 2;
    }
    gsl_set_error_handler_off();
    if (check_reference() != 0) {
        fprintf(stderr, "bench_contact: the reference failed its checks; not measuring\n");
        return 1;
    }

    int rc = 1;
    nbep_diag d;
    nbep_diag_init(&d);
    solver_ctx x = {NULL, gsl_poly_complex_workspace_alloc(5)};
    pair_case *cases = malloc(N_CLASSES * n * sizeof *cases);
    double *err = malloc(n * sizeof *err);
    double *ns = malloc((size_t)repeats * N_CLASSES * N_METHODS * sizeof *ns);
    FILE *csv = NULL, *dump = NULL;
    if (!cases || !err || !ns || !x.raw || nbep_predict_ws_create(&x.ws, &d) != NBEP_OK) {
        nbep_diag_print(&d, stderr);
        fprintf(stderr, "bench_contact: out of memory\n");
        goto done;
    }
    if ((csv_path && !(csv = fopen(csv_path, "w"))) ||
        (dump_path && !(dump = fopen(dump_path, "w")))) {
        fprintf(stderr, "bench_contact: cannot write %s\n", csv ? dump_path : csv_path);
        goto done;
    }

    /* cases and their references */
    double t_ref_start = nbep_now();
    for (int k = 0; k < N_CLASSES; k++) {
        uint64_t s = 0x5eed0000u + (uint64_t)k;
        for (size_t i = 0; i < n; i++) {
            pair_case *c = &cases[(size_t)k * n + i];
            do
                make_case((case_class)k, &s, c);
            while (q_contact(c) < 0);       /* not apart at t = 0 (rounding): draw again */
            reference(c, &s);
            if (dump)
                fprintf(dump, "%s %a %a %a %a %a %a %a %a %a %a %a %a %a %d\n", CLASS[k].name,
                        c->dp.x, c->dp.y, c->dp.z, c->dv.x, c->dv.y, c->dv.z, c->da.x, c->da.y,
                        c->da.z, c->sigma, c->t_ref, c->t_ref_lo, c->sens, c->ambiguous);
        }
    }
    double t_ref_seconds = nbep_now() - t_ref_start;

    /* timing: repeats outermost, every method on every class in each repeat */
    double sink = 0.0;
    for (int r = 0; r < repeats; r++)
        for (int k = 0; k < N_CLASSES; k++)
            for (int m = 0; m < N_METHODS; m++)
                if (METHOD[m].quartic == CLASS[k].quartic)
                    ns[((size_t)r * N_CLASSES + (size_t)k) * N_METHODS + (size_t)m] =
                        time_once(&cases[(size_t)k * n], n, (method)m, &x, &sink);

    printf("<!-- bench_contact: %zu cases per class, median of %d timings, 1 thread, %s; "
           "reference (binary128) %.1f s; checksum %.6g -->\n",
           n, repeats, NBEP_BUILD_FLAGS, t_ref_seconds, sink);
    printf("| class | hits (ambiguous) | method | median rel. err | p99 | max | max err / sens "
           "| off | wrong: hit / miss (+ at round-off) | ns/solve |\n");
    printf("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n");
    if (csv)
        fprintf(csv, "class,cases,hits_ref,ambiguous,method,median_rel_err,p99_rel_err,"
                     "max_rel_err,max_err_over_sens,off,wrong_hit,wrong_miss,round_off,nan,"
                     "ns_per_solve\n");
    for (int k = 0; k < N_CLASSES; k++) {
        for (int m = 0; m < N_METHODS; m++) {
            if (METHOD[m].quartic != CLASS[k].quartic)
                continue;
            bool show = show_method && !strcmp(show_method, METHOD[m].name);
            stats st = measure_accuracy(&cases[(size_t)k * n], n, (method)m, &x, err, show);
            double t[64];
            int nr = repeats < 64 ? repeats : 64;
            for (int r = 0; r < nr; r++)
                t[r] = ns[((size_t)r * N_CLASSES + (size_t)k) * N_METHODS + (size_t)m];
            qsort(t, (size_t)nr, sizeof t[0], bench_cmp_double);
            st.ns = t[nr / 2];
            printf("| %s | %zu/%zu (%zu) | %s | %.1e | %.1e | %.1e | %.2g | %zu | %zu / %zu "
                   "(+%zu)%s | %.0f |\n",
                   CLASS[k].name, st.hits_ref, n, st.ambiguous, METHOD[m].name, st.median,
                   st.p99, st.max, st.max_excess, st.off, st.wrong_hit, st.wrong_miss,
                   st.round_off, st.nan ? " NaN!" : "", st.ns);
            if (csv)
                fprintf(csv, "%s,%zu,%zu,%zu,%s,%.3e,%.3e,%.3e,%.3e,%zu,%zu,%zu,%zu,%zu,%.1f\n",
                        CLASS[k].name, n, st.hits_ref, st.ambiguous, METHOD[m].name, st.median,
                        st.p99, st.max, st.max_excess, st.off, st.wrong_hit, st.wrong_miss,
                        st.round_off, st.nan, st.ns);
        }
    }
    printf("\nclasses:\n");
    for (int k = 0; k < N_CLASSES; k++)
        printf("- %s: %s\n", CLASS[k].name, CLASS[k].what);
    rc = 0;
done:
    if (csv)
        fclose(csv);
    if (dump)
        fclose(dump);
    free(cases);
    free(err);
    free(ns);
    nbep_predict_ws_destroy(&x.ws);
    if (x.raw)
        gsl_poly_complex_workspace_free(x.raw);
    nbep_diag_fini(&d);
    return rc;
}
