/* Contact times (paper Appendix 1; SPEC "Physics"). The only user of GSL.
 *
 * A pair's relative position r(t) = dp + dv t + da t^2/2 touches when
 * f(t) = |r(t)|^2 - sigma^2 = 0, and closes while f'(t) = 2 r.r' < 0. With equal accelerations
 * f is a quadratic, solved in closed form; otherwise a quartic, whose roots come from GSL's
 * companion-matrix solver and are then polished by Newton on f itself.
 *
 * Numerical choices, each for a measured failure of the obvious way:
 * - f(0) = |dp|^2 - sigma^2 is computed compensated (exact fma products, TwoSum additions):
 *   a gap of 1e-12 sigma would otherwise keep only about four digits.
 * - f is evaluated as |r(t)|^2 - sigma^2 from r(t), not from the expanded coefficients,
 *   which cancel when |dp| and |dv t| are large and nearly opposite.
 * - The quartic is handed to GSL in units of its largest root (found exactly as a power of
 *   two from the coefficients), so the companion matrix neither overflows nor loses a
 *   leading coefficient that is small in the caller's units.
 * - When da is small the quartic's roots come in two scales: two near the equal-acceleration
 *   answer and two of order |dv|/|da|. The companion matrix finds small roots only to an
 *   absolute accuracy set by the large ones, so the roots of the truncated quadratic
 *   f ~ a2 t^2 + a1 t + a0 are also polished as candidates; every candidate must pass the
 *   same residual, convergence and closing tests, so an extra candidate cannot produce a
 *   wrong answer.
 * - Near a double root (grazing incidence, near misses) Newton on f fails because f' ~ 0;
 *   such estimates go through the valley of f instead (Newton on f', see consider()).
 * - A GSL failure, an estimate that neither route can settle, and the rare pair that overlaps
 *   without closing at t = 0 go to a search that isolates the critical points of f and
 *   bisects on the sign of f: several times slower, but it cannot miss a root. It is also
 *   the independent check of this path in the tests (predict_impl.h).
 * Checked against 50-digit reference roots (mpmath) on random pairs of every kind: relative
 * error below 2e-15, and at grazing incidence below the answer's own sensitivity to a one-ulp
 * change of the inputs (~1e-11). */
#include "nbep/predict.h"

#include "predict_impl.h"

#include <assert.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_poly.h>

/* Coefficients of a quartic. */
enum { QUARTIC_TERMS = 5 };

/* A root of the quartic whose imaginary part is within round-off is taken as real. We solve in
 * units of the largest root, where a double real root (a grazing contact) splits under
 * round-off into a pair up to ~sqrt(DBL_EPSILON) = 1.5e-8 apart; 1e-6 leaves a margin. A truly
 * complex root let through only costs a look at the valley of f there (see consider()). */
/* |dp|^2 - sigma^2 below this fraction of sigma^2 (a gap under 5e-7 sigma) counts as nearly
 * touching: see nbep_predict_pair. */
/* |da| |dp| / |dv|^2 above which the acceleration bends the approach enough that the
 * bracketing search beats GSL's solver: see nbep_predict_pair. */
#define ACCEL_BENDS 1e-2
#define NEAR_CONTACT_REL 1e-6
#define IMAG_TOL 1e-6
/* In units of the largest root, GSL places a root only to within some ulps of 1; below
 * SMALL_ROOT its estimate may be too rough for Newton, while the truncated quadratic's
 * estimate is then good to about SMALL_ROOT relative. So a GSL root below it that does not
 * polish is not a sign of trouble. */
#define SMALL_ROOT 1e-8
/* Newton steps when polishing. From a GSL root (relative error below ~1e-8 unless the time
 * scales separate) two or three suffice; the rest let the truncated-quadratic estimates
 * converge when the scales do separate (their relative error is about |da||dp|/|dv|^2). */
#define NEWTON_MAX 8
/* Polishing stops once a step moves t by a few ulps: round-off in f dominates below that. */
#define NEWTON_STOP (4.0 * DBL_EPSILON)
/* A polished t is a root when |f(t)| is within the round-off of evaluating f there. f_val's
 * error is at most ~10 ulps of sigma |w(t)|, w = t (dv + t da/2) (the rest is compensated);
 * 64 ulps is several times that, and the DBL_EPSILON sigma^2 floor covers t = 0 itself. */
#define ROOT_TOL (64.0 * DBL_EPSILON)
/* A root is accepted only once Newton's next correction is below 1e-12 of t, so what the
 * GSL path returns is good to that (usually to 1e-15: the polish has converged). A contact so
 * grazing that round-off in f alone moves it further (impact parameter within ~5e-7 of
 * sigma, where f' ~ 0) goes to the bracket search, which bisects on the sign of f. */
#define ROOT_STEP_TOL 1e-12
/* The largest root scale, as a power of two, for which the quartic is solved. Beyond it
 * (|da| below ~1e-72 |dv| in any units) the acceleration changes no contact before 2^240
 * time units and the equal-acceleration quadratic is used; this also keeps t^2 |da| and the
 * bisection bound far from overflow. */
#define SCALE_EXP_MAX 240

struct nbep_predict_ws {
    gsl_poly_complex_workspace *gsl;          /* owned */
    double coef[QUARTIC_TERMS];               /* scaled quartic, lowest degree first */
    double root[2 * (QUARTIC_TERMS - 1)];     /* GSL's packed complex roots */
};

nbep_status nbep_predict_ws_create(nbep_predict_ws **out, nbep_diag *d)
{
    nbep_predict_ws *ws = calloc(1, sizeof *ws);
    if (!ws || !(ws->gsl = gsl_poly_complex_workspace_alloc(QUARTIC_TERMS))) {
        free(ws);
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for a quartic solver workspace");
    }
    *out = ws;
    return NBEP_OK;
}

size_t nbep_predict_ws_bytes(void)
{
    return sizeof(nbep_predict_ws);
}

void nbep_predict_ws_destroy(nbep_predict_ws **ws)
{
    if (!ws || !*ws)
        return;
    gsl_poly_complex_workspace_free((*ws)->gsl);
    free(*ws);
    *ws = NULL;
}

/* ---- compensated arithmetic ----------------------------------------------------------- */

/* s + err == a + b exactly (Knuth's TwoSum; needs no ordering of |a| and |b|). */
static void two_sum(double a, double b, double *s, double *err)
{
    double x = a + b;
    double bv = x - a;
    double av = x - bv;
    *s = x;
    *err = (a - av) + (b - bv);
}

/* |r|^2 - sigma^2 as accurately as if computed in twice the precision and rounded once: each
 * square is split exactly into high and low parts by fma, and the eight parts are summed with
 * TwoSum, the rounding errors accumulated separately (Ogita, Rump and Oishi's Sum2). */
static inline double gap2(nbep_vec3 r, double sigma)
{
    double px = r.x * r.x, py = r.y * r.y, pz = r.z * r.z, ps = sigma * sigma;
    double ex = fma(r.x, r.x, -px), ey = fma(r.y, r.y, -py), ez = fma(r.z, r.z, -pz),
           es = fma(sigma, sigma, -ps);
    double s, e1, e2;
    two_sum(px, py, &s, &e1);
    two_sum(s, pz, &s, &e2);
    /* The usual case, a near contact: |r|^2 within a factor 2 of sigma^2, so that s - ps is
     * exact (Sterbenz) and the exact result is it plus six terms each below an ulp of |r|^2,
     * whose plain sum is off by a few ulps of an ulp: half the work of the general sum. */
    if (s >= 0.5 * ps && s <= 2.0 * ps)
        return (s - ps) + (((ex + ey) + (ez + e1)) + (e2 - es));
    const double part[8] = {px, py, pz, -ps, ex, ey, ez, -es};
    double sum = part[0], lost = 0.0;
    for (int i = 1; i < 8; i++) {
        double err;
        two_sum(sum, part[i], &sum, &err);
        lost += err;
    }
    return sum + lost;
}

double nbep__predict_gap2(nbep_vec3 r, double sigma)
{
    return gap2(r, sigma);
}

/* ---- the pair's relative motion ------------------------------------------------------ */

typedef struct motion {
    nbep_vec3 p, v, a;          /* dp, dv, da */
    double sigma;
    double nv, na;              /* |dv|, |da|, for the residual's scale */
} motion;

static motion motion_make(nbep_vec3 dp, nbep_vec3 dv, nbep_vec3 da, double sigma)
{
    return (motion){dp, dv, da, sigma, nbep_vec3_norm(dv), nbep_vec3_norm(da)};
}

/* r(t) = p + t (v + t a/2) */
static nbep_vec3 motion_r(const motion *m, double t)
{
    double h = 0.5 * t;
    return (nbep_vec3){m->p.x + t * (m->v.x + h * m->a.x), m->p.y + t * (m->v.y + h * m->a.y),
                       m->p.z + t * (m->v.z + h * m->a.z)};
}

/* r'(t) = v + t a */
static nbep_vec3 motion_rdot(const motion *m, double t)
{
    return nbep_vec3_axpy(m->v, t, m->a);
}

/* f(t) = |r|^2 - sigma^2, with r = dp + w, w = t (v + t a/2). The rounding of the addition
 * dp + w is kept (TwoSum: r = hi + lo exactly) and carried through |hi + lo|^2 ~ |hi|^2
 * + 2 hi.lo, so that what is left is the rounding of w itself, an error proportional to t:
 * near t = 0 (a tiny gap) f keeps the accuracy of its compensated f(0). */
static double f_val(const motion *m, double t)
{
    double h = 0.5 * t;
    nbep_vec3 w = {t * (m->v.x + h * m->a.x), t * (m->v.y + h * m->a.y),
                   t * (m->v.z + h * m->a.z)};
    nbep_vec3 hi, lo;
    two_sum(m->p.x, w.x, &hi.x, &lo.x);
    two_sum(m->p.y, w.y, &hi.y, &lo.y);
    two_sum(m->p.z, w.z, &hi.z, &lo.z);
    return nbep__predict_gap2(hi, m->sigma) + 2.0 * nbep_vec3_dot(hi, lo);
}

/* f'(t)/2 = r.r': negative while closing. */
static double f_half_slope(const motion *m, double t)
{
    return nbep_vec3_dot(motion_r(m, t), motion_rdot(m, t));
}

/* The size of the round-off in f_val at t, over ROOT_TOL (see there). */
static double f_scale(const motion *m, double t)
{
    t = fabs(t);
    return m->sigma * (DBL_EPSILON * m->sigma + t * (m->nv + 0.5 * t * m->na));
}

/* ---- quartic set-up ------------------------------------------------------------------- */

typedef struct quartic {
    motion m;
    double a[QUARTIC_TERMS];   /* f(t) = sum a[k] t^k; a[0] compensated */
    int scale_exp;             /* every root of f and of f' lies within 2^(scale_exp + 1) */
    double t_start;            /* the search starts here: 0, or past a round-off dip (setup) */
} quartic;

typedef enum setup_kind {
    SETUP_APART,       /* f(0) > 0: solve */
    SETUP_CLOSING,     /* touching or overlapping and closing now: 0 */
    SETUP_OVERLAP,     /* touching or overlapping, not closing now: search */
    SETUP_NO_ACCEL,    /* da too small to matter (see SCALE_EXP_MAX): quadratic */
    SETUP_NONFINITE    /* coefficients overflowed: never */
} setup_kind;

/* ceil(num / den) for den > 0 */
static int ceil_div(int num, int den)
{
    return num >= 0 ? (num + den - 1) / den : -((-num) / den);
}

static setup_kind quartic_setup(nbep_vec3 dp, nbep_vec3 dv, nbep_vec3 da, double sigma,
                                quartic *q)
{
    q->m = motion_make(dp, dv, da, sigma);
    double *a = q->a;
    q->t_start = 0.0;
    a[4] = 0.25 * nbep_vec3_dot(da, da);
    a[3] = nbep_vec3_dot(dv, da);
    a[2] = nbep_vec3_dot(dv, dv) + nbep_vec3_dot(dp, da);
    a[1] = 2.0 * nbep_vec3_dot(dp, dv);
    a[0] = nbep__predict_gap2(dp, sigma);
    for (int k = 0; k < QUARTIC_TERMS; k++)
        if (!isfinite(a[k]))
            return SETUP_NONFINITE;
    if (!(a[4] > 0.0))
        return SETUP_NO_ACCEL;                  /* |da|^2 underflowed */

    /* Fujiwara's bound: every root has |t| <= 2 max_k (|a_k|/a_4)^(1/(4-k)). With
     * |a_k| < 2^(e_k), a_4 >= 2^(e_4 - 1), 2^scale_exp is at least the max, exactly a power
     * of two so that scaling by it is exact. f'/2 = 2a4 t^3 + 1.5 a3 t^2 + a2 t + a1/2 has
     * smaller ratios, so its roots obey the same bound. */
    int e4;
    (void)frexp(a[4], &e4);
    int scale = INT_MIN;
    for (int k = 0; k < 4; k++) {
        if (a[k] == 0.0)
            continue;
        int ek;
        (void)frexp(a[k], &ek);
        int sk = ceil_div(ek - e4 + 1, 4 - k);
        scale = sk > scale ? sk : scale;
    }
    if (scale == INT_MIN)
        scale = 0;                              /* f = a4 t^4: cannot happen with sigma > 0 */
    if (scale > SCALE_EXP_MAX)
        return SETUP_NO_ACCEL;
    q->scale_exp = scale;

    if (a[0] > 0.0)
        return SETUP_APART;
    if (!(a[1] < 0.0))
        return SETUP_OVERLAP;
    /* touching or overlapping and closing: now, unless only by round-off (NBEP_PREDICT_GRAZE,
     * as in the quadratic) while the accelerations do not press them together (a2 > 0): then
     * f dips by round-off until -a1 / (2 a2) and is back at f(0) at -a1 / a2, where the search
     * starts (it would call the dip "overlapping as it starts to close": now) */
    const double pp_vv = nbep_vec3_dot(dp, dp) * nbep_vec3_dot(dv, dv);
    if (a[2] > 0.0 && a[1] * a[1] <= 4.0 * NBEP_PREDICT_GRAZE * NBEP_PREDICT_GRAZE * pp_vv) {
        q->t_start = -a[1] / a[2];
        return SETUP_OVERLAP;
    }
    return SETUP_CLOSING;
}

/* ---- Newton polish and the acceptance tests ------------------------------------------- */

/* Newton on f from t; returns the iterate with the smallest |f| (the start included), so a
 * step that overshoots cannot make things worse. */
static double polish(const motion *m, double t)
{
    double ft = f_val(m, t);
    double best = t, best_abs = fabs(ft);
    for (int k = 0; k < NEWTON_MAX && best_abs > 0.0; k++) {
        double step = ft / (2.0 * f_half_slope(m, t));
        if (!isfinite(step))
            break;                              /* flat: f' = 0 */
        t -= step;
        ft = f_val(m, t);
        if (fabs(ft) < best_abs) {
            best = t;
            best_abs = fabs(ft);
        }
        if (fabs(step) <= NEWTON_STOP * fabs(t))
            break;
    }
    return best;
}

/* f''(t)/2 = |r'|^2 + r.a: positive at a valley of f. */
static double f_half_curv(const motion *m, double t)
{
    nbep_vec3 rd = motion_rdot(m, t);
    return nbep_vec3_dot(rd, rd) + nbep_vec3_dot(motion_r(m, t), m->a);
}

/* Newton on f' from t towards a minimum of f; NAN if f is not convex on the way. */
static double valley(const motion *m, double t)
{
    for (int k = 0; k < NEWTON_MAX; k++) {
        double curv = f_half_curv(m, t);
        if (!(curv > 0.0))
            return NAN;
        double step = f_half_slope(m, t) / curv;
        t -= step;
        if (fabs(step) <= NEWTON_STOP * fabs(t))
            break;
    }
    return t;
}

typedef enum verdict {
    VERDICT_TAKEN,       /* a closing root below the best so far: now the best */
    VERDICT_PASSED,      /* nothing earlier there: a root later than the best or not closing,
                            or a valley that stays above contact (a near miss) */
    VERDICT_NOT_ROOT,    /* neither Newton nor the valley reached a verdict */
    VERDICT_UNSURE       /* a valley dips below contact, but its entry was not certified */
} verdict;

/* Is t a root of f at t >= 0 where the pair closes, below *best? A root: |f(t)| within
 * round-off, and the Newton correction f/f' within ROOT_STEP_TOL of t. */
static verdict judge(const motion *m, double t, double *best)
{
    double ft = f_val(m, t);
    if (!(fabs(ft) <= ROOT_TOL * f_scale(m, t)) ||
        !(fabs(ft) <= ROOT_STEP_TOL * fabs(t) * fabs(2.0 * f_half_slope(m, t))))
        return VERDICT_NOT_ROOT;
    if (!(t >= 0.0 && t < *best) || !(f_half_slope(m, t) < 0.0))
        return VERDICT_PASSED;                  /* past, later, separating or grazing */
    *best = t;
    return VERDICT_TAKEN;
}

/* Polishes the estimate t0 and lowers *best to it if it is a root at t >= 0 where the pair
 * closes. A negative estimate within round-off of 0 is polished from 0.
 * Near a double root (a grazing contact or a near miss) f' ~ 0 throws Newton off; there the
 * valley of f is found instead (Newton on f', whose root is simple): if its floor stays above
 * zero the pair misses, else the entry root lies left of it, at about tc - d with
 * d = sqrt(-2 f(tc) / f''(tc)) (the parabola through the floor); Newton from tc - 2d
 * approaches it from outside the valley, where convexity makes the steps monotone. That is
 * done when Newton fails, and at once for a complex estimate (in_valley), whose real part
 * sits at the floor of the valley. */
static verdict consider(const motion *m, double t0, bool in_valley, double *best)
{
    t0 = t0 > 0.0 ? t0 : 0.0;
    if (!in_valley) {
        verdict v = judge(m, polish(m, t0), best);
        if (v != VERDICT_NOT_ROOT)
            return v;
    }
    double tc = valley(m, t0);
    if (!isfinite(tc))
        return VERDICT_NOT_ROOT;
    double fc = f_val(m, tc);
    if (fc > 0.0 || tc < 0.0)
        return VERDICT_PASSED;                  /* floor above contact, or in the past */
    double d = sqrt(-fc / f_half_curv(m, tc));
    verdict v = judge(m, polish(m, tc - 2.0 * d), best);
    return v == VERDICT_NOT_ROOT ? VERDICT_UNSURE : v;
}

/* ---- the GSL-free search -------------------------------------------------------------- */

static uint64_t double_bits(double x)
{
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    return u;
}

static double bits_double(uint64_t u)
{
    double x;
    memcpy(&x, &u, sizeof x);
    return x;
}

/* f'(t) = 2 r.r' */
static double f_slope(const motion *m, double t)
{
    return 2.0 * f_half_slope(m, t);
}

/* The tries of a critical point's search that also look for f <= 0 (bisect's dip). Where the
 * pair touches (a pile's), the first such try finds it in most searches (3.0 M of 5.3 M on a
 * 300-sphere pour); where it misses (most random pairs), each look is an f for nothing: with
 * no limit random classes of bench_contact took 1.1 to 1.25 times as long. */
#define DIP_TRIES 1

/* For 0 <= lo < hi where (g <= 0) differs between lo and hi (ga and gb: g there, which the
 * caller has), with dg its derivative: the first double in (lo, hi] at which g has hi's
 * value, g monotone in between. Keeps a bracket of bit patterns (ordered like the values for
 * non-negative doubles) that ends at adjacent doubles. A try is a Newton step from the last
 * try (g and dg there) where that step lands inside the bracket, g's slope there has the sign
 * g takes from lo to hi, and the step is at most a quarter of the last Newton step (Newton
 * converging: near a double root, as at a resting contact, it only halves its step each time,
 * and false position does better). Otherwise it is the false-position point of the bracket's
 * ends (Illinois: an end that stays twice in a row counts its value half), or, after a false
 * position try that did not halve the bracket's bit span, the span's midpoint. Either try is
 * pushed 4^k ulps farther from the end that the last k + 1 tries all moved (k >= 1): once that
 * end lies within rounding of the root, the tries land on it or just short of it again and
 * again, and the push brings the other end in instead. With g monotone the answer is the one
 * double where g turns, whatever the tries: plain bisection's. On a settling pile (300
 * spheres, 700 steps) the tries per search went from 26 (critical points) and 24 (contacts) on
 * average with false position alone to 11 and 12, the most 116 (docs/accuracy.md).
 * dip (NULL: none): g is f'/2 on a stretch where f falls until g turns (lo's side: f' <= 0);
 * the first DIP_TRIES tries where f' < 0, short of the turn, also take f there, and the first
 * at which f <= 0 ends the search: that try is returned and *dip set to f there (else *dip is
 * left alone). */
static double bisect(const motion *m, double (*g)(const motion *, double),
                     double (*dg)(const motion *, double), double lo, double hi, double ga,
                     double gb, double *dip)
{
    const bool lo_side = ga <= 0.0;
    uint64_t a = double_bits(lo), b = double_bits(hi);
    double ta = lo, tb = hi;
    int moved = 0; /* the end the last try moved: -1 a, 1 b, 0 none yet */
    int run = 0;   /* the tries before it that moved the same end */
    bool halve = false;
    double tl = 0.0, gl = 0.0, dl = 0.0; /* the last try, g and dg there (moved != 0) */
    double step = INFINITY;              /* the last Newton step's length */
    int dip_tries = DIP_TRIES;           /* f taken at this many tries at most (dip) */
    while (b - a > 1) {
        const uint64_t span = b - a;
        /* Newton from the last try, if g's slope there has the sign g takes from a to b, its
         * step lands inside the bracket, and it is at most a quarter of the last one */
        double t = NAN;
        bool newton = false;
        if (moved != 0 && (lo_side ? dl > 0.0 : dl < 0.0)) {
            const double tn = tl - gl / dl;
            if (tn > ta && tn < tb && fabs(tn - tl) <= 0.25 * step) {
                step = fabs(tn - tl);
                t = tn;
                newton = true;
            }
        }
        if (!newton && !halve && ga != gb)
            t = ta + (tb - ta) * (ga / (ga - gb));
        uint64_t c = a + span / 2;
        if (t >= ta && t <= tb) { /* NaN (none, or halving): the midpoint */
            const uint64_t push = run > 0 ? (uint64_t)1 << (2 * run < 62 ? 2 * run : 62) : 0;
            uint64_t ct = double_bits(t);
            if (moved == -1) /* a keeps moving up: past the point, towards b */
                ct = b - ct > push ? ct + push : b - 1;
            else if (moved == 1) /* b keeps moving down: short of it, towards a */
                ct = ct - a > push ? ct - push : a + 1;
            c = ct <= a ? a + 1 : ct >= b ? b - 1 : ct; /* strictly inside */
        }
        const double tc = bits_double(c), gc = g(m, tc);
        tl = tc;
        gl = gc;
        dl = dg(m, tc);
        if ((gc <= 0.0) == lo_side) {
            if (dip && dip_tries > 0 && gc < 0.0) { /* closing (not flat: f' = 0 in round-off) */
                dip_tries--;
                const double fc = f_val(m, tc);
                if (fc <= 0.0) {
                    *dip = fc;
                    return tc;
                }
            }
            a = c;
            ta = tc;
            ga = gc;
            if (moved == -1) {
                gb *= 0.5;
                run++;
            } else {
                run = 0;
            }
            moved = -1;
        } else {
            b = c;
            tb = tc;
            gb = gc;
            if (moved == 1) {
                ga *= 0.5;
                run++;
            } else {
                run = 0;
            }
            moved = 1;
        }
        halve = !newton && b - a > span / 2;
    }
    return bits_double(b);
}

/* Real roots in (0, hi) of c2 t^2 + c1 t + c0 with c2 > 0, ascending; returns how many. */
static int quadratic_roots_in(double c2, double c1, double c0, double hi, double out[2])
{
    /* Scaled to the largest coefficient, so that the squares below cannot overflow or
     * underflow whatever the units (the coefficients are products of up to four lengths). */
    double big = fmax(c2, fmax(fabs(c1), fabs(c0)));
    c2 /= big;
    c1 /= big;
    c0 /= big;
    double disc = c1 * c1 - 4.0 * c2 * c0;
    if (!(disc >= 0.0))
        return 0;
    /* q has the sign of -c1, so c1 and the root never cancel. */
    double q = -0.5 * (c1 + copysign(sqrt(disc), c1));
    double r[2] = {q / c2, q != 0.0 ? c0 / q : 0.0};
    if (r[0] > r[1]) {
        double tmp = r[0];
        r[0] = r[1];
        r[1] = tmp;
    }
    int n = 0;
    for (int i = 0; i < 2; i++)
        if (r[i] > 0.0 && r[i] < hi)
            out[n++] = r[i];
    return n;
}

/* The earliest t >= 0 at which the pair touches or overlaps (f <= 0) while closing (f
 * decreasing): the same double whatever t_max when it comes before t_max, NBEP_NEVER or a
 * time at or past t_max otherwise. The inflection points of f (roots of f''/2 = 1.5|a|^2 t^2
 * + 3 v.a t + |v|^2 + p.a) split [0, tb] into knot pieces on which f' is monotone, so each
 * holds at most one critical point of f; those split [0, tb] into pieces on which f is
 * monotone, which are walked in order, each critical point found (bisecting f') as the walk
 * reaches it. No root lies beyond tb, and f > 0 there.
 * Past t_max: where the next critical point w lies beyond t_max (f' at t_max still has the
 * sign it had at its knot piece's start, or no knot piece turns), f is monotone on [u, t_max],
 * so f > 0 at u and f clear of its round-off above 0 at t_max (f_scale: near a slowly crossing
 * root the computed f turns sign every few ulps, and a review found the search stopped with a
 * root left before t_max in 5 % of pairs at 1 ulp past it when f(t_max) > 0 was all it asked)
 * mean no root before t_max, here or in the pieces after w: the search stops without finding
 * w (a pile's pairs, slowly closing under different accelerations, spent most of their time
 * finding critical points far beyond their sphere's next event). Otherwise the walk goes on
 * exactly as it would without t_max, so a root before t_max is found by the same bisections.
 * Where f falls until w, w's bisection stops at its first try past the root (f <= 0 there:
 * bisect's dip), which brackets the root as well as w does; that depends on the pair alone,
 * not on t_max, so the same-double promise holds. */
static double bracket_search(const quartic *q, double t_max)
{
    const motion *m = &q->m;
    const double tb = ldexp(1.0, q->scale_exp + 1);
    double knot[4] = {q->t_start};
    int n_knot = 1;
    double r[2];
    int n_r = quadratic_roots_in(1.5 * nbep_vec3_dot(m->a, m->a), 3.0 * nbep_vec3_dot(m->v, m->a),
                                 nbep_vec3_dot(m->v, m->v) + nbep_vec3_dot(m->p, m->a), tb, r);
    for (int k = 0; k < n_r; k++)
        if (r[k] > q->t_start)
            knot[n_knot++] = r[k];
    knot[n_knot++] = tb;

    double slope[4]; /* f'/2 at each knot, each found once */
    for (int k = 0; k < n_knot; k++)
        slope[k] = f_half_slope(m, knot[k]);
    double u = q->t_start; /* the start of the piece walked next */
    for (int i = 0;; i++) {
        /* the knot piece i holding the next critical point (none: the piece ends at tb) */
        while (i + 1 < n_knot && (slope[i] <= 0.0) == (slope[i + 1] <= 0.0))
            i++;
        const bool last = i + 1 >= n_knot;
        if (!(u < t_max))
            return NBEP_NEVER;
        if (t_max < tb &&
            (last || t_max < knot[i] ||
             (t_max < knot[i + 1] && (f_half_slope(m, t_max) <= 0.0) == (slope[i] <= 0.0))) &&
            f_val(m, u) > 0.0 && f_val(m, t_max) > ROOT_TOL * f_scale(m, t_max))
            return NBEP_NEVER;
        /* where f falls until w, the search for w stops at the first try past the root (f
         * <= 0 there, short of w: the root lies between u and it) */
        double fz = 1.0;
        const double w = last ? tb
                              : bisect(m, f_half_slope, f_half_curv, knot[i], knot[i + 1],
                                       slope[i], slope[i + 1], slope[i] <= 0.0 ? &fz : NULL);
        if (fz <= 0.0) {
            const double fu = f_val(m, u);
            return fu <= 0.0 ? u : bisect(m, f_val, f_slope, u, w, fu, fz, NULL);
        }
        if (w > u && f_half_slope(m, 0.5 * (u + w)) < 0.0) { /* f decreases here */
            const double fu = f_val(m, u);
            if (fu <= 0.0)
                return u;                       /* overlapping as it starts to close */
            const double fw = f_val(m, w);
            if (fw <= 0.0)
                return bisect(m, f_val, f_slope, u, w, fu, fw, NULL);
        }
        if (last)
            return NBEP_NEVER;
        u = w;
    }
}

double nbep__predict_f(nbep_vec3 dp, nbep_vec3 dv, nbep_vec3 da, double sigma, double t)
{
    motion m = motion_make(dp, dv, da, sigma);
    return f_val(&m, t);
}

double nbep__predict_pair_bracket(nbep_vec3 dp, nbep_vec3 dv, nbep_vec3 da, double sigma)
{
    quartic q;
    switch (quartic_setup(dp, dv, da, sigma, &q)) {
    case SETUP_APART:
    case SETUP_OVERLAP:
        return bracket_search(&q, INFINITY);
    case SETUP_CLOSING:
        return 0.0;
    case SETUP_NO_ACCEL:
        return nbep_predict_pair_quadratic(dp, dv, sigma);
    case SETUP_NONFINITE:
        break;
    }
    return NBEP_NEVER;
}

/* ---- public entry points -------------------------------------------------------------- */

NBEP_FMA_CLONES double nbep_predict_pair_quadratic(nbep_vec3 dp, nbep_vec3 dv, double sigma)
{
    assert(sigma > 0.0); /* dp and dv finite: the caller's (this is the innermost loop) */
    double b = nbep_vec3_dot(dp, dv);
    if (!(b < 0.0))
        return NBEP_NEVER;                      /* receding or at rest */
    /* |dp|^2 - sigma^2 > 0 while apart. Plainly computed it loses digits only when the two
     * squares are close; when it exceeds half of |dp|^2 its relative error is below 4 ulps,
     * which is all the root below needs, so the compensated form is kept for near contacts
     * (most pairs of a dilute gas are far apart, and this is the innermost loop). */
    double pp = nbep_vec3_dot(dp, dp);
    double c = pp - sigma * sigma;
    if (!(c > 0.5 * pp))
        c = gap2(dp, sigma);
    if (c <= 0.0) /* touching or overlapping: closing now, unless only by round-off */
        return b * b > NBEP_PREDICT_GRAZE * NBEP_PREDICT_GRAZE * (pp * nbep_vec3_dot(dv, dv))
                   ? 0.0
                   : NBEP_NEVER;
    /* At grazing incidence disc = b^2 - |dv|^2 c is a small difference; by Lagrange's identity
     * it equals |dv|^2 sigma^2 - |dp x dv|^2. With s the distance still to fly to the closest
     * approach, b^2 = |dv|^2 s^2: the first form subtracts two numbers of size |dv|^2 s^2, the
     * second two of size |dv|^2 sigma^2. So the first serves while the pair is within about
     * sigma of its closest approach, the second farther out, where it is better by
     * (s / sigma)^2 (bench_contact: 51 of 4000 grazing hit/miss verdicts wrong before, 0
     * after, at the same cost). */
    double vv = nbep_vec3_dot(dv, dv), vs = vv * (sigma * sigma), disc;
    if (b * b < vs) {
        disc = b * b - vv * c;
    } else {
        nbep_vec3 x = {dp.y * dv.z - dp.z * dv.y, dp.z * dv.x - dp.x * dv.z,
                       dp.x * dv.y - dp.y * dv.x};
        disc = vs - nbep_vec3_dot(x, x);
    }
    if (!(disc >= 0.0))
        return NBEP_NEVER;                      /* they miss */
    /* The smaller root (-b - sqrt(disc))/vv, rewritten so that nothing cancels. */
    return c / (-b + sqrt(disc));
}

double nbep_predict_pair(nbep_vec3 dp, nbep_vec3 dv, nbep_vec3 da, double sigma,
                         nbep_predict_ws *ws)
{
    return nbep_predict_pair_within(dp, dv, da, sigma, INFINITY, ws);
}

double nbep_predict_pair_within(nbep_vec3 dp, nbep_vec3 dv, nbep_vec3 da, double sigma,
                                double t_max, nbep_predict_ws *ws)
{
    if (da.x == 0.0 && da.y == 0.0 && da.z == 0.0)
        return nbep_predict_pair_quadratic(dp, dv, sigma);
    assert(nbep_vec3_isfinite(dp) && nbep_vec3_isfinite(dv) && nbep_vec3_isfinite(da));
    assert(sigma > 0.0 && ws);

    quartic q;
    switch (quartic_setup(dp, dv, da, sigma, &q)) {
    case SETUP_APART:
        break;
    case SETUP_CLOSING:
        return 0.0;
    case SETUP_OVERLAP:
        return bracket_search(&q, t_max);
    case SETUP_NO_ACCEL:
        return nbep_predict_pair_quadratic(dp, dv, sigma);
    case SETUP_NONFINITE:
        return NBEP_NEVER;
    }
    /* Nearly touching: GSL's roots carry an absolute error of about eps times the largest
     * root, and a contact that starts within a hair's gap can be many orders of magnitude
     * sooner than that (a sphere at rest on another, pulled onto it by a different
     * acceleration, touches again after ~1e-9 s). The search has no such scale; pairs this
     * close are rare (resting contacts), so its cost does not matter. */
    if (q.a[0] <= NEAR_CONTACT_REL * sigma * sigma)
        return bracket_search(&q, t_max);
    /* Both solvers are right everywhere (bench_contact, against a quad-precision reference);
     * which is faster depends on how much the acceleration bends the approach: where
     * |da| |dp| >= 1e-2 |dv|^2 the search takes 0.36-0.58 of GSL's time (random, large,
     * from-rest and grazing cases), below it GSL takes half the search's (the search's root
     * bound grows as da vanishes). */
    if (nbep_vec3_norm(da) * nbep_vec3_norm(dp) >= ACCEL_BENDS * nbep_vec3_norm2(dv))
        return bracket_search(&q, t_max);

    /* Monic in units of 2^scale_exp: b_k = a_k / (a_4 2^(scale_exp (4-k))), |b_k| <= 1,
     * formed from mantissas and exponents so that no intermediate overflows. */
    const double *a = q.a;
    int e4;
    double m4 = frexp(a[4], &e4);
    for (int k = 0; k < 4; k++) {
        int ek;
        double mk = frexp(a[k], &ek);
        ws->coef[k] = ldexp(mk / m4, ek - e4 - q.scale_exp * (4 - k));
    }
    ws->coef[4] = 1.0;

    if (gsl_poly_complex_solve(ws->coef, QUARTIC_TERMS, ws->gsl, ws->root) != GSL_SUCCESS)
        return bracket_search(&q, t_max); /* QR did not converge: never seen, but safe */

    double best = NBEP_NEVER;
    bool lost = false;
    for (int i = 0; i < QUARTIC_TERMS - 1; i++) {
        double x = ws->root[2 * i], y = ws->root[2 * i + 1];
        if (fabs(y) > IMAG_TOL * (1.0 + fabs(x)) || x < -SMALL_ROOT || y < 0.0)
            continue;                           /* complex, in the past, or a conjugate */
        verdict v = consider(&q.m, ldexp(x, q.scale_exp), y != 0.0, &best);
        lost |= v == VERDICT_UNSURE || (v == VERDICT_NOT_ROOT && fabs(x) >= SMALL_ROOT);
    }
    /* The truncated quadratic a2 t^2 + a1 t + a0: its roots, or its vertex when they are
     * complex (a valley, maybe grazing), are the small roots' estimates when the two time
     * scales separate. */
    double lower[2];
    int n_lower = 0;
    if (a[2] != 0.0) {
        double s2 = a[2] > 0.0 ? 1.0 : -1.0;    /* make the leading coefficient positive */
        n_lower = quadratic_roots_in(s2 * a[2], s2 * a[1], s2 * a[0], INFINITY, lower);
        if (n_lower == 0 && a[2] > 0.0 && a[1] < 0.0)
            lost |= consider(&q.m, -a[1] / (2.0 * a[2]), true, &best) == VERDICT_UNSURE;
    } else if (a[1] < 0.0) {
        lower[n_lower++] = a[0] / -a[1];
    }
    for (int i = 0; i < n_lower; i++)
        lost |= consider(&q.m, lower[i], false, &best) == VERDICT_UNSURE;
    /* Some estimate could not be settled: a grazing contact, or a near miss, where f' ~ 0
     * makes Newton unreliable (a GSL root that does not polish is one too, unless it is a
     * small root, which the truncated quadratic covers; see SMALL_ROOT). Only the search can
     * tell which, and where. */
    if (lost)
        return bracket_search(&q, t_max);
    return best;
}

double nbep_predict_plane(double gap, double vn, double an)
{
    assert(isfinite(gap) && isfinite(vn) && isfinite(an));
    if (gap <= 0.0) {
        if (vn < 0.0 || (vn == 0.0 && an < 0.0))
            return 0.0;                         /* touching or in, and closing (or pressed) */
        if (!(an < 0.0))
            return NBEP_NEVER;                  /* leaving, or at rest without a push */
    } else if (!(vn < 0.0) && !(an < 0.0)) {
        return NBEP_NEVER;                      /* apart and never turning back */
    }
    /* Roots of (an/2) t^2 + vn t + gap; disc = vn^2 - 2 an gap. */
    double disc = vn * vn - 2.0 * an * gap;
    if (vn < 0.0) {
        /* Apart and approaching (gap > 0): the first root, in the form without
         * cancellation. disc >= vn^2 when an <= 0; when an > 0 they may miss. */
        if (!(disc >= 0.0))
            return NBEP_NEVER;
        return 2.0 * gap / (-vn + sqrt(disc));
    }
    /* vn >= 0 and an < 0: moving away (or not at all), then pulled back. */
    if (!(disc > 0.0))
        return vn / -an;                        /* still overlapping at the turn (gap <= 0) */
    return (vn + sqrt(disc)) / -an;             /* the root where it comes back down */
}

double nbep_predict_plane_contact(double gap, double vn, double an, double speed)
{
    if (gap <= 0.0 && vn < 0.0 && -vn <= NBEP_PREDICT_GRAZE_PLANE * speed)
        vn = 0.0;
    return nbep_predict_plane(gap, vn, an);
}
