#!/usr/bin/env python3
"""make mutate: small deliberate bugs put into a scratch copy of the tree one at a time, each
checked against the tests that should catch it (README "Tests").

Each mutant names a file, an exact snippet of it that must occur exactly once, its replacement,
and the test programs that should fail. A snippet that no longer occurs exactly once (the core
changed) makes the mutant "stale": it is reported loudly and makes the run fail, so the list is
kept up to date rather than silently thinned. Equivalent mutants (no observable change) carry
the reason and are not run.

Usage: python3 scripts/mutate.py [--jobs N] [--timeout S] [--only ID[,ID...]] [--list] [--stale]
(--stale: only the staleness check, which make check runs, so that a change to the core that
leaves a mutant behind fails at once.)
Prints one row per mutant and ends with exactly one line
"mutants: K killed, S survived, E equivalent". Exit 0 when none survived and none is stale.
"""
import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

SIM = ["test_run_contract", "test_sim", "test_extremes"]
PRED = ["test_predict"]
CELLS = ["test_sim"]  # its cells-mode tests: exact against all pairs, dense fluid, pile
TEAM = ["test_periodic"]  # the team loop's tests: one thread's frames, counts and sums
# the window's apartness: checked at each place's joining (deterministic), then the results
APART = ["test_evloop_apart", "test_periodic"]
GRAN = ["test_granular"]
ORDER = ["test_order"]  # run.order = "step", the paper's step
WAYS = ["test_pred_ways"]  # the schedule of the ways a step's events run, for given costs
LISTS = ["test_evloop_lists"]  # the cells engine's lists against a search of every sphere
# the engine's ways out of a stall or a failed walk, forced by its own copy's hooks
FAULTS = ["test_team_faults"]

# (id, file, original, replacement, tests, equivalent-reason or None)
MUTANTS = [
    # ---- physics ----
    ("phys-restitution", "src/physics.c", "double k = c * (1.0 + e) / (m1 + m2);",
     "double k = c * (1.0 + 0.5 * e) / (m1 + m2);", ["test_physics"], None),
    ("phys-mass-swap", "src/physics.c", "*v1 = nbep_vec3_axpy(*v1, -m2 * k, n);",
     "*v1 = nbep_vec3_axpy(*v1, -m1 * k, n);", ["test_physics"], None),
    ("phys-receding", "src/physics.c",
     "if (!(nbep_vec3_dot(d, nbep_vec3_sub(*v2, *v1)) < 0.0))\n        return false;                       /* receding",
     "if (!(nbep_vec3_dot(d, nbep_vec3_sub(*v2, *v1)) > 0.0))\n        return false;                       /* receding",
     ["test_physics"], None),
    ("phys-plane-e", "src/physics.c", "*v = nbep_vec3_axpy(*v, -(1.0 + e) * vn, n);",
     "*v = nbep_vec3_axpy(*v, -(2.0) * vn, n);", ["test_physics"], None),
    ("phys-potential-sign", "src/physics.c", "pe -= m * nbep_vec3_dot(s->acc[i], s->pos[i]);",
     "pe += m * nbep_vec3_dot(s->acc[i], s->pos[i]);", ["test_physics"], None),
    ("phys-kinetic-half", "src/physics.c", "ke += 0.5 * m * nbep_vec3_dot(s->vel[i], s->vel[i]);",
     "ke += m * nbep_vec3_dot(s->vel[i], s->vel[i]);", ["test_physics"], None),
    # ---- contact times ----
    ("bisect-keeps-wrong-side", "src/predict.c", "        if ((gc <= 0.0) == lo_side) {",
     "        if ((gc <= 0.0) != lo_side) {", PRED, None),
    ("bisect-newton-half-slope", "src/predict.c", "    return 2.0 * f_half_slope(m, t);\n}",
     "    return f_half_slope(m, t);\n}", PRED,
     "Newton's tries only choose which doubles the bisection tries; the bracket, not the tries, "
     "decides the answer (the double where f turns), so a wrong derivative costs tries, not "
     "answers: speed is bench_contact's to measure, not a test's"),
    ("quad-root-sign", "src/predict.c", "return c / (-b + sqrt(disc));",
     "return c / (-b - sqrt(disc));", PRED, None),
    ("quad-miss", "src/predict.c", "if (!(disc >= 0.0))\n        return NBEP_NEVER;                      /* they miss */",
     "if (!(disc > 0.0))\n        return NBEP_NEVER;                      /* they miss */", PRED,
     "differs only when disc is exactly 0: a pair that touches for one instant with no normal "
     "velocity, to which the response gives no impulse (c = 0), so no velocity or counter changes"),
    ("quad-receding", "src/predict.c", "if (!(b < 0.0))\n        return NBEP_NEVER;                      /* receding or at rest */",
     "if (!(b < INFINITY))\n        return NBEP_NEVER;                      /* receding or at rest */", PRED, None),
    ("plane-root", "src/predict.c", "return 2.0 * gap / (-vn + sqrt(disc));",
     "return gap / (-vn + sqrt(disc));", PRED, None),
    ("plane-comeback", "src/predict.c", "return (vn + sqrt(disc)) / -an;             /* the root where it comes back down */",
     "return (vn - sqrt(disc)) / -an;             /* the root where it comes back down */", PRED, None),
    ("quartic-accel-bends", "src/predict.c",
     "if (nbep_vec3_norm(da) * nbep_vec3_norm(dp) >= ACCEL_BENDS * nbep_vec3_norm2(dv))\n        return bracket_search(&q, t_max);",
     "if (nbep_vec3_norm(da) * nbep_vec3_norm(dp) >= ACCEL_BENDS * nbep_vec3_norm2(dv))\n        return 2.0 * bracket_search(&q, t_max);", PRED, None),
    ("bracket-overlap-start", "src/predict.c", "if (fu <= 0.0)\n                return u;",
     "if (fu <= 0.0)\n                return w;", PRED,
     "since the dip stop (84fe58e) a pair overlapping where f starts to fall is answered on the "
     "dip's path (bracket-dip-overlap-start, killed): w's search tries a point short of w with "
     "f' < 0 and f below f(u) <= 0. This branch is left where no try lands short of w: w within "
     "an ulp of the inflection that starts the knot piece, f' changing sign where f'' = 0 (a "
     "triple root of the cubic f', a double one of f'', or round-off); no test aims at that, "
     "and the branch stays as the safe answer"),
    ("bracket-dip-is-root", "src/predict.c",
     "return fu <= 0.0 ? u : bisect(m, f_val, f_slope, u, w, fu, fz, NULL);",
     "return fu <= 0.0 ? u : w;", PRED, None),
    ("bracket-dip-overlap-start", "src/predict.c",
     "return fu <= 0.0 ? u : bisect(m, f_val, f_slope, u, w, fu, fz, NULL);",
     "return fu <= 0.0 ? w : bisect(m, f_val, f_slope, u, w, fu, fz, NULL);", PRED, None),
    ("bracket-dip-flat", "src/predict.c", "            if (dip && dip_tries > 0 && gc < 0.0) {",
     "            if (dip && dip_tries > 0 && gc <= 0.0) {", PRED, None),
    ("quartic-lost", "src/predict.c", "    if (lost)\n        return bracket_search(&q, t_max);\n    return best;",
     "    return best;", PRED, None),
    ("within-one-end", "src/predict.c",
     "            f_val(m, u) > 0.0 && f_val(m, t_max) > ROOT_TOL * f_scale(m, t_max))",
     "            f_val(m, u) > 0.0)", PRED, None),
    ("within-end-in-noise", "src/predict.c",
     "            f_val(m, u) > 0.0 && f_val(m, t_max) > ROOT_TOL * f_scale(m, t_max))",
     "            f_val(m, u) > 0.0 && f_val(m, t_max) > 0.0)", PRED, None),
    ("within-crit-unchecked", "src/predict.c",
     "             (t_max < knot[i + 1] && (f_half_slope(m, t_max) <= 0.0) == (slope[i] <= 0.0))) &&",
     "             (t_max < knot[i + 1])) &&", PRED, None),
    ("within-start-past-half", "src/predict.c", "        if (!(u < t_max))\n            return NBEP_NEVER;",
     "        if (!(u < 0.5 * t_max))\n            return NBEP_NEVER;", PRED, None),
    ("earliest-quad-bound-late", "src/pred_find.c",
     "        return lb == NBEP_NEVER ? NBEP_NEVER : T0 + (r->t0 + lb);\n    }",
     "        return lb == NBEP_NEVER ? NBEP_NEVER : T0 + (r->t0 + 1.5 * lb);\n    }",
     CELLS + GRAN + SIM, None),
    # the free-flight partner loop's gathered partners (cells_pairs_free): a partner's own
    # radius, and its own local time, must be the ones its bound is computed from
    ("bounds-partner-radius-own", "src/pred_cells.c", "        g->rj[k] = mono ? ri : radius[j];",
     "        g->rj[k] = ri;", CELLS + TEAM, None),
    ("bounds-partner-time-own", "src/pred_cells.c", "        g->tj[k] = tau[j];",
     "        g->tj[k] = ti;", CELLS + TEAM, None),
    # the closing pairs kept without a branch: the one with the lowest bound taken first must
    # be one that closes, and the count must step only for those
    ("pairs-kept-counts-all", "src/pred_cells.c", "            n += lb < INFINITY;",
     "            n += 1;", CELLS + TEAM,
     "a pair kept that does not close has bound +inf, which the root loop's test skips unless "
     "the best so far is +inf too, and then its root is NBEP_NEVER, which changes nothing"),
    ("pairs-kept-last-closing-dropped", "src/pred_cells.c", "            n += lb < INFINITY;",
     "            n += lb < INFINITY && k + 1 < k1;", CELLS + TEAM, None),
    ("pairs-kept-lowest-first-lost", "src/pred_cells.c",
     "            first = lb < first_lb ? n : first;", "            first = first;", CELLS + TEAM,
     "which pair's root comes first changes only how many others its time prunes, not the "
     "winner: every pair whose bound is not later than the best so far is still tried"),
    ("beat-cap-short", "src/pred_find.c", "    const double d = best->time - T0 - t0;",
     "    const double d = 0.5 * (best->time - T0 - t0);", CELLS + GRAN, None),
    # the cap exactly at the best time so far, without the tie margin: a pair that ties with
    # a plane found first, its time rounded down to the plane's, is cut off and the plane wins
    ("beat-cap-no-margin", "src/pred_find.c",
     "    return d + 16.0 * DBL_EPSILON * (fabs(best->time) + fabs(T0) + fabs(t0));",
     "    return d;", CELLS + GRAN, None),
    # ---- event queue ----
    ("feq-earlier", "src/feq.c", "return a->time < b->time;", "return a->time > b->time;",
     ["test_feq"] + SIM, None),
    ("feq-version", "src/feq.c", "return a->ver_self > b->ver_self;", "return a->ver_self < b->ver_self;",
     ["test_feq"], None),
    ("feq-min-bound", "src/feq.c", "if (s->kind != NBEP_EVENT_NONE && s->time < t_end)",
     "if (s->kind != NBEP_EVENT_NONE && s->time <= t_end)", ["test_feq"] + SIM, None),
    # ---- barrier ----
    ("barrier-rearm-after-round", "src/barrier.c",
     "        atomic_store_explicit(&b->left, b->n, memory_order_relaxed);\n"
     "        NBEP_BARRIER_BETWEEN_STORES();\n"
     "        /* Release (and sequentially consistent, for the sleepers below): passes on everything\n"
     "         * the last arrival acquired (all threads' writes) and the rearmed `left`; pairs with\n"
     "         * the waiters' acquire loads. */\n"
     "        atomic_store_explicit(&b->round, r + 1u, memory_order_seq_cst);",
     "        atomic_store_explicit(&b->round, r + 1u, memory_order_seq_cst);\n"
     "        NBEP_BARRIER_BETWEEN_STORES();\n"
     "        atomic_store_explicit(&b->left, b->n, memory_order_relaxed);",
     ["test_barrier_rearm", "test_barrier"], None),  # test_barrier_rearm: every run
    ("barrier-last-arrival", "src/barrier.c", "memory_order_acq_rel) == 1) {",
     "memory_order_acq_rel) == 0) {", ["test_barrier"], None),
    ("barrier-round-step", "src/barrier.c", "atomic_store_explicit(&b->round, r + 1u, memory_order_seq_cst);",
     "atomic_store_explicit(&b->round, r, memory_order_seq_cst);", ["test_barrier"], None),
    ("barrier-no-wake", "src/barrier.c", "            nbep_word_wake_all(&b->round);",
     "            (void)0;", ["test_barrier"], None),
    ("barrier-sleeper-uncounted", "src/barrier.c",
     "        atomic_fetch_add_explicit(&b->sleepers, 1u, memory_order_seq_cst);", "",
     ["test_barrier"], None),
    ("barrier-never-sleeps", "src/barrier.c", "for (unsigned k = 1; k < NBEP_BARRIER_SPINS; k++) {",
     "for (unsigned k = 1;; k++) {", ["test_barrier"], None),
    # ---- claims ----
    ("claim-max", "src/algo_predictive.c", "while (key < cur &&", "while (key > cur &&", SIM, None),
    ("claim-one-side", "src/algo_predictive.c",
     "        if (ev->kind == NBEP_EVENT_SPHERE &&\n            atomic_load_explicit(&c->claim[par][hi], memory_order_relaxed) != key)\n            continue;\n",
     "", SIM, None),
    # ---- periodic geometry (periodic.c, periodic.h): minimum image, wrap and image counts ----
    # its unit tests are the first of test_periodic's (the geometry module)
    ("periodic-image-floor", "src/periodic.c", "double m = round(d / len);",
     "double m = floor(d / len);", ["test_periodic"], None),
    ("periodic-wrap-image-sign", "src/periodic.c", "*image += (int32_t)m;", "*image -= (int32_t)m;",
     ["test_periodic"], None),
    ("periodic-wrap-image-wrong-axis", "src/periodic.c",
     "wrap_1(&p->z, pb->lo[2], pb->len[2], &image[2]);",
     "wrap_1(&p->z, pb->lo[2], pb->len[2], &image[1]);", ["test_periodic"], None),
    # the two corrections of a floor that rounding put one period off: the step taken, the count not
    ("periodic-wrap-high-fix-uncounted", "src/periodic.c", "        y -= len;\n        m += 1.0;",
     "        y -= len;", ["test_periodic"], None),
    ("periodic-wrap-low-fix-uncounted", "src/periodic.c", "        y += len;\n        m -= 1.0;",
     "        y += len;", ["test_periodic"], None),
    # a step up that rounds onto the upper face, which belongs to the next copy: left there, or
    # moved to lo without the period counted (the wrap's bug until 4858b7a)
    ("periodic-wrap-face-left", "src/periodic.c", "    if (y >= lo + len) {\n        y = lo;\n        m += 1.0;\n    }\n",
     "", ["test_periodic"], None),
    ("periodic-wrap-face-uncounted", "src/periodic.c", "        y = lo;\n        m += 1.0;", "        y = lo;",
     ["test_periodic"], None),
    ("periodic-nearest-sign", "src/periodic.c", "cells[k] = pb->axis[k] ? -(int)round(x[k] / pb->len[k]) : 0;",
     "cells[k] = pb->axis[k] ? (int)round(x[k] / pb->len[k]) : 0;", ["test_periodic"] + SIM, None),
    ("periodic-reach-half", "src/periodic.c", "r = fmin(r, (0.5 * pb->len[k] - sigma) / 4.0);",
     "r = fmin(r, (0.5 * pb->len[k] - sigma) / 2.0);", ["test_periodic"], None),
    ("periodic-reach-walls-count", "src/periodic.c", "        if (pb->axis[k])\n            r = fmin",
     "        r = fmin", ["test_periodic"], None),
    # the inline nearest image and shift of the collision response and the cells engine
    ("periodic-half-whole-period", "src/periodic.c", "pb.half[k] = pb.axis[k] ? 0.5 * pb.len[k] : INFINITY;",
     "pb.half[k] = pb.axis[k] ? pb.len[k] : INFINITY;", ["test_periodic"] + CELLS, None),
    ("periodic-near-image-sign", "include/nbep/periodic.h",
     "return d > half ? d - len : d < -half ? d + len : d;",
     "return d > half ? d - len : d < -half ? d - len : d;", ["test_periodic"] + CELLS, None),
    ("periodic-near-shift-one-side", "include/nbep/periodic.h",
     "d.y > pb->half[1] ? -pb->len[1] : d.y < -pb->half[1] ? pb->len[1] : 0.0,",
     "d.y > pb->half[1] ? -pb->len[1] : 0.0,", ["test_periodic"] + CELLS + LISTS, None),
    # random placement in a periodic box (scene_place.c): a region past a face wraps its places
    # into the box, so a random sphere keeps clear by the nearest image, looked up wrapped and
    # across the faces it is near
    ("place-periodic-plain-distance", "src/scene_place.c",
     "    if (q->pb)\n        d = nbep_periodic_image(q->pb, d);\n", "", ["test_scene"], None),
    ("place-periodic-no-copies", "src/scene_place.c", "    for (int m = 0; m < 8; m++) {\n        if (((m & 1) && near[0] == 0.0)",
     "    for (int m = 0; m < 1; m++) {\n        if (((m & 1) && near[0] == 0.0)", ["test_scene"], None),
    ("place-periodic-cells-unwrapped", "src/scene_place.c",
     "    if (g->pb) {\n        int32_t image[3] = {0, 0, 0};\n        nbep_periodic_wrap(g->pb, &p, image);\n    }\n",
     "", ["test_scene"], None),
    # ---- grid reach ----
    ("grid-no-partner-travel", "src/pred_find.c", "0.5 * nbep_vec3_norm(ai) * H * H + V * H + 0.5 * c->amax * H * H;",
     "0.5 * nbep_vec3_norm(ai) * H * H + 0.5 * c->amax * H * H;", SIM, None),
    ("grid-no-own-speed", "src/pred_find.c", "double reach = s->radius[i] + c->rmax + nbep_vec3_norm(s->vel[i]) * H +",
     "double reach = s->radius[i] + c->rmax +", SIM, None),
    ("grid-place-past-own-cells", "src/grid.c",
     "        if (c >= c_lo && c < c_hi)\n            g->item[g->fill[c]++] = (uint32_t)i;",
     "        if (c >= c_lo)\n            g->item[g->fill[c]++] = (uint32_t)i;", ["test_grid"] + SIM, None),
    ("grid-offset-own-sum", "src/algo_predictive.c", "    for (int t = 0; t < tid; t++)\n        offset += c->ws[t].grid_sum;",
     "    for (int t = 0; t <= tid; t++)\n        offset += c->ws[t].grid_sum;", SIM, None),
    ("grid-horizon-long", "src/algo_predictive.c", "double k = step_travel > 0.0 ? floor(0.5 * c->grid.h / step_travel) : 64.0;",
     "double k = step_travel > 0.0 ? floor(8.0 * c->grid.h / step_travel) : 64.0;", SIM, None),
    ("grid-block-lo", "src/grid.c", "lo[k] = axis_cell(x[k] - reach, o[k], g->inv_h, g->dim[k]);",
     "lo[k] = axis_cell(x[k], o[k], g->inv_h, g->dim[k]);", SIM + ["test_output"], None),
    # a block reaching past the last cell names one cell too many (outside the grid)
    ("grid-clamp-past-last", "src/grid.c", "return c >= (double)dim ? dim - 1 : (size_t)c;",
     "return c > (double)dim ? dim - 1 : (size_t)c;", ["test_grid"] + SIM, None),
    # a rebuild counts on top of the last build's counts
    ("grid-count-not-cleared", "src/grid.c", "        g->fill[c] = 0;\n", "", ["test_grid"] + SIM, None),
    ("grid-bounds-y-from-x", "src/grid.c", "l.y = p.y < l.y ? p.y : l.y", "l.y = p.x < l.y ? p.x : l.y",
     ["test_grid"] + SIM, None),
    # the cells counted for the room one short per axis: a sparse cloud gets more than it holds
    ("grid-size-undercount", "src/grid.c", "cells *= floor(ext[k] / h) + 1.0;",
     "cells *= floor(ext[k] / h);", ["test_grid"] + SIM, None),
    # ---- BVH ----
    ("bvh-skip-owner", "src/bvh.c", "if (nd->max_id <= i || !boxes_touch", "if (nd->max_id < i || !boxes_touch",
     ["test_bvh"], None),
    ("bvh-touch-axis", "src/bvh.c", "alo.z <= bhi.z && blo.z <= ahi.z;", "alo.z <= bhi.z;", ["test_bvh"], None),
    ("bvh-leaf-max", "src/bvh.c", "max_id = b->order[m] > max_id ? b->order[m] : max_id;",
     "max_id = b->order[m] < max_id ? b->order[m] : max_id;", ["test_bvh"], None),
    ("bvh-touch-strict-x", "src/bvh.c", "return alo.x <= bhi.x && blo.x <= ahi.x",
     "return alo.x < bhi.x && blo.x <= ahi.x", ["test_bvh"], None),
    # equal codes split one off instead of at the median: a chain as deep as the run is long
    ("bvh-equal-codes-split-first", "src/bvh.c", "return lo + (hi - lo) / 2;", "return lo + 1;",
     ["test_bvh"], None),
    # only the lowest digit sorted: the splits are made on unsorted codes
    ("bvh-sort-one-pass", "src/bvh.c", "if (h[(b->code[0] >> shift) & (RADIX_BUCKETS - 1)] == n)",
     "if (p > 0 || h[(b->code[0] >> shift) & (RADIX_BUCKETS - 1)] == n)", ["test_bvh"], None),
    # ---- detection loops ----
    ("detect-touching", "src/algo_detect.c", "if (d2 < sigma * sigma) {", "if (d2 < 0.98 * sigma * sigma) {",
     SIM, None),
    ("detect-pair-loop", "src/algo_detect.c", "for (size_t j = i + 1; j < n; j++)\n                test_pair",
     "for (size_t j = i + 2; j < n; j++)\n                test_pair", SIM, None),
    ("detect-checks-off-by-one", "src/algo_detect.c", "checks += n - 1 - i;", "checks += n - i;", SIM, None),
    ("detect-plane-gap", "src/algo_detect.c", "if (gap < 0.0) {\n                push_contact",
     "if (gap < -1e-3 * s->radius[i]) {\n                push_contact", SIM, None),
    # ---- jams (run.max_reactions) ----
    ("jam-count-never-reset", "src/pred_react.c", "        if (j->step != w->jam_step)",
     "        if (j->step == UINT32_MAX)", ["tests/test_jam.sh"], None),
    ("jam-rounds-not-checked", "src/algo_predictive.c", "                if (jammed) {\n                    if (tid == 0)",
     "                if (0) {\n                    if (tid == 0)", ["tests/test_jam.sh"], None),
    ("jam-evloop-stop-ignored", "src/evloop.c", "        if (w->stop) {\n            *t_stuck = t;",
     "        if (0) {\n            *t_stuck = t;",
     ["tests/test_jam.sh"], None),
    ("jam-limit-off-by-one-more", "src/pred_react.c", "if (++j->n > c->jam_max &&",
     "if (++j->n > c->jam_max + 1 &&", ["tests/test_jam.sh"],
     "one reaction later on a jammed sphere changes nothing a test can see: the line names the limit, not the count"),
    # ---- granular: cages, round-off grazing, rest speed (issue 9) ----
    ("cage-never", "src/pred_react.c", "    if (!opposed)\n        return false;",
     "    if (1)\n        return false;", GRAN, None),
    ("cage-no-time-window", "src/pred_react.c", "        if (f[j].who != who && t_abs - f[j].t <= tc &&",
     "        if (f[j].who != who && f[j].t > -INFINITY &&", GRAN + ["tests/test_settle.sh"], None),
    ("cage-not-facing", "src/pred_react.c", "            opposed = opposed || nbep_vec3_dot(f[j].n, n) < 0.0;",
     "            opposed = true;", GRAN, None),
    ("cage-last-face-only", "src/pred_react.c", "    for (int j = 0; j < CAGE_FACES; j++)\n        if (f[j].who != who",
     "    for (int j = 0; j < 1; j++)\n        if (f[j].who != who", GRAN, None),
    ("lean-normal-never", "src/pred_react.c", "    if (c->rest) {\n        const double len = nbep_vec3_norm(r12);",
     "    if (!c->rest) {\n        const double len = nbep_vec3_norm(r12);", GRAN, None),
    ("lean-never-noted", "src/pred_react.c", "    *leans |= k > 0;", "    (void)k;", GRAN, None),
    ("jam-hold-off", "src/pred_react.c", "    if (jam_hold(c, s, w, k, j, dt))\n        return;\n", "", GRAN, None),
    ("jam-hold-late", "src/pred_react.c", "#define JAM_HOLD ((uint32_t)NBEP_JAM_HOLD)", "#define JAM_HOLD ((uint32_t)NBEP_JAM_HOLD * 100u)", GRAN, None),
    ("jam-hold-slow-only", "src/pred_react.c",
     "    const double vs = settle_speed(s, k, dt), amag = nbep_vec3_norm(s->acc[k]);\n    rest_set r",
     "    const double vs = settle_speed(s, k, dt), amag = nbep_vec3_norm(s->acc[k]);\n    if (!(nbep_vec3_norm(s->vel[k]) <= vs))\n        return false;\n    rest_set r", GRAN, None),
    ("carry-off", "src/pred_react.c", " ||\n            carried(c, s, w, j, k, -u, nbep_vec3_scale(d, -1.0), sc->carry_drop, dt)) {", ") {", GRAN, None),
    ("carry-any-speed", "src/pred_react.c",
     "    if (!(carry_drop > 0.0) || !(amag > 0.0) ||\n        !(u <= sqrt(2.0 * amag * carry_drop * s->radius[j])))",
     "    if (!(carry_drop > 0.0) || !(amag > 0.0))", GRAN, None),
    ("carry-any-way", "src/pred_react.c",
     "    return nbep_vec3_norm(nbep_contact_project(m, n, r->n, &act)) <=\n           HOLD_SLOPE * nbep_vec3_norm(m);",
     "    (void)nbep_contact_project(m, n, r->n, &act);\n    return true;", GRAN, None),
    ("carry-own-faces-only", "src/pred_react.c",
     "    pocket_gather(c, s, w, j, k, reach, false, &r);\n    pocket_planes(s, j, reach, &r);\n",
     "    (void)w, (void)reach;\n", GRAN, None),
    ("carry-drop-ignored", "src/pred_react.c", "nbep_vec3_scale(d, -1.0), sc->carry_drop, dt)) {",
     "nbep_vec3_scale(d, -1.0), NBEP_CARRY_DROP, dt)) {", GRAN, None),
    ("carry-no-planes", "src/pred_react.c",
     "    pocket_planes(s, j, reach, &r);\n    return faces_take", "    return faces_take", GRAN, None),
    ("jam-hold-pairs-off", "src/pred_react.c",
     "        if (!c->rest[k].still && supported(c, k) && jam_hold(c, s, w, k, NO_SPHERE, dt)) {",
     "        if (0) {", GRAN, None),
    ("hold-slope-exact", "src/pred_react.c", "(spheres ? HOLD_SLOPE : NBEP_CONTACT_TOL) * amag",
     "NBEP_CONTACT_TOL * amag", GRAN, None),
    ("hold-slope-planes-too", "src/pred_react.c", "(spheres ? HOLD_SLOPE : NBEP_CONTACT_TOL) * amag",
     "HOLD_SLOPE * amag", GRAN, None),
    ("graze-tolerance-off", "src/predict.c",
     "return b * b > NBEP_PREDICT_GRAZE * NBEP_PREDICT_GRAZE * (pp * nbep_vec3_dot(dv, dv))",
     "return b * b > 0.0 * (pp * nbep_vec3_dot(dv, dv))", PRED, None),
    ("graze-quartic-off", "src/predict.c",
     "    if (a[2] > 0.0 && a[1] * a[1] <= 4.0 * NBEP_PREDICT_GRAZE",
     "    if (0 && a[1] * a[1] <= 4.0 * NBEP_PREDICT_GRAZE", PRED, None),
    ("graze-quartic-pressed", "src/predict.c",
     "    if (a[2] > 0.0 && a[1] * a[1] <= 4.0 * NBEP_PREDICT_GRAZE",
     "    if (a[1] * a[1] <= 4.0 * NBEP_PREDICT_GRAZE", PRED, None),
    ("graze-quartic-dip", "src/predict.c", "        q->t_start = -a[1] / a[2];",
     "        q->t_start = 0.0;", PRED, None),
    ("graze-plane-off", "src/predict.c", "-vn <= NBEP_PREDICT_GRAZE_PLANE * speed)",
     "-vn <= 0.0 * speed)", PRED, None),
    ("settle-off", "src/pred_settle.c", "    x->cand = !x->still && x->slow >= SETTLE_STEPS;",
     "    x->cand = false;", GRAN + ["tests/test_settle.sh"], None),
    ("settle-window-1", "src/pred_impl.h", "#define SETTLE_STEPS 10u", "#define SETTLE_STEPS 1u",
     GRAN + ["tests/test_settle.sh"], None),
    ("settle-any-support", "src/pred_settle.c",
     "    if (j == g->i || !(y->still || (y->cand && (g->par < 0 || y->live[g->par]))))",
     "    if (j == g->i)",
     GRAN + ["tests/test_settle.sh"], None),
    ("settle-stamp-early", "src/pred_settle.c",
     "            r->ver[k] = r->who[k] < 0 ? c->ver[-1 - r->who[k]] : 0;",
     "            r->ver[k] = r->who[k] < 0 ? c->ver[-1 - r->who[k]] - 1 : 0;",
     GRAN + ["tests/test_settle.sh"], None),
    # a candidate held on candidates whose own supports do not settle (the rounds that drop
    # them never run, or keep them): a sphere on one that rests on a sliding sphere hangs in
    # the air once that one slides off
    ("settle-rounds-off", "src/pred_settle.c", "        if (lost == 0)\n            break;",
     "        if (1)\n            break;", GRAN, None),
    ("settle-recheck-keeps", "src/pred_settle.c",
     "c->settle[-1 - who].still || c->settle[-1 - who].live[prev])",
     "c->settle[-1 - who].still || c->settle[-1 - who].cand)", GRAN, None),
    # a candidate whose support list was cut at NBEP_CONTACT_MAX only drops the kept supports
    # that lost theirs instead of gathering again: a live support beyond the cut is never seen
    ("settle-recheck-no-regather", "src/pred_settle.c",
     "    if (x->more)\n        return settle_gather(c, s, i, dt, prev);\n", "", GRAN, None),
    ("cage-moved-off", "src/pred_react.c", "CAGE_TOUCH_REL * s->radius[k]) {",
     "INFINITY) {", GRAN, None),
    ("pocket-off", "src/pred_react.c", "        if (!held) { /* a pocket:", "        if (0) { /* a pocket:",
     GRAN, None),
    ("pocket-planes-off", "src/pred_react.c",
     "            pocket_planes(s, k, v_rest * v_rest / amag, &r);\n", "", GRAN, None),
    ("pocket-rounds-off", "src/pred_react.c",
     "    for (size_t m = 0; m < s->n && r->n < NBEP_CONTACT_MAX; m++)",
     "    for (size_t m = 0; m < 0; m++)", GRAN, None),
    ("leave-held-off", "src/pred_react.c",
     "    if (!(len > 0.0) || !(nbep_vec3_dot(d, s->vel[k]) < 0.0))\n        return;",
     "    if (1)\n        return;", GRAN + ["tests/test_settle.sh"], None),
    ("rest-speed-tiny", "src/pred_impl.h",
     "    return amag > 0.0 ? amag * min_bounce_time(s->radius[i], amag, dt) : 0.0;",
     "    return amag > 0.0 ? 1e-2 * amag * min_bounce_time(s->radius[i], amag, dt) : 0.0;",
     ["tests/test_settle.sh"], None),
    ("rest-squeezed-plane-off", "src/pred_react.c",
     "(e_pl != e && vn <= rest_speed(s, lo, -an, dt))", "(0 && vn <= rest_speed(s, lo, -an, dt))",
     ["tests/test_settle.sh"], None),
    # ---- event calendar (cells mode) ----
    ("cal-time-order", "include/nbep/calendar.h", "if (a.time != b.time)\n        return a.time < b.time;",
     "if (a.time != b.time)\n        return a.time > b.time;", ["test_calendar"] + CELLS, None),
    ("cal-tie-key", "include/nbep/calendar.h", "return a.key < b.key;", "return a.key > b.key;",
     ["test_calendar"] + CELLS, None),
    ("cal-sift-down-child", "src/calendar.c",
     "if (child + 1 < c->heap_len && before(c, c->heap[child + 1], c->heap[child]))",
     "if (child + 1 < c->heap_len && before(c, c->heap[child], c->heap[child + 1]))",
     ["test_calendar"] + CELLS, None),
    ("cal-remove-hole-up", "src/calendar.c",
     "if (k > 0 && before(c, last, c->heap[(k - 1) / 2]))\n        sift_up(c, k, last);",
     "if (0 && before(c, last, c->heap[(k - 1) / 2]))\n        sift_up(c, k, last);",
     ["test_calendar"] + CELLS, None),
    ("cal-lap-no-overflow", "src/calendar.c",
     "            if (c->ovf_min <= c->cur + (int64_t)c->nb)\n                redistribute(c);",
     "            (void)0;", ["test_calendar"] + CELLS, None),
    ("cal-ring-one-too-far", "src/calendar.c", "    return ab > c->cur && ab - c->cur <= (int64_t)c->nb;",
     "    return ab > c->cur && ab - c->cur <= (int64_t)c->nb + 1;", ["test_calendar"] + CELLS, None),
    # the lists' links by selects: the back link of the item after, and a head's link
    ("cal-unlink-back-lost", "src/calendar.c", "    *link_back(c, x->next) = x->prev;\n}",
     "    (void)0;\n}", ["test_calendar"] + CELLS, None),
    ("cal-push-back-lost", "src/calendar.c", "    *link_back(c, x->next) = item;",
     "    (void)0;", ["test_calendar"] + CELLS, None),
    ("cal-head-link-first-slot", "src/calendar.c",
     "    return prev < c->n ? &c->node[prev].next : &c->head[prev - c->n];",
     "    return prev < c->n ? &c->node[prev].next : &c->head[0];", ["test_calendar"] + CELLS,
     None),
    # the last bucket's entries drawn into the heap (parked): a later set of an earlier bucket
    ("cal-parked-kept", "src/calendar.c", "    if (c->parked && ab < INT64_MAX) {",
     "    if (0) {", ["test_calendar"], None),
    ("cal-parked-unchecked", "src/calendar.c",
     "        else if (c->parked && bucket_of(c, c->node[item].time) != INT64_MAX)\n            bad++;",
     "", ["test_calendar"],
     "the check's rule for parked heaps finds nothing while the calendar keeps it: only a bug it guards against could break it"),
    ("cal-retune-untrimmed", "src/calendar.c",
     "        const size_t k = m - (size_t)(RETUNE_TRIM * (double)m); /* at least one */",
     "        const size_t k = m;", ["test_calendar"], None),
    # ---- cell lists ----
    ("cells-block-lo", "src/cells.c", "        if (xyz[k] > 0) {\n            b->idx[k][m] = xyz[k] - 1;", "        if (0) {\n            b->idx[k][m] = xyz[k] - 1;",
     ["test_cells"] + CELLS, None),
    ("cells-block-hi", "src/cells.c", "        if (xyz[k] + 1 < g->dim[k]) {", "        if (0) {", ["test_cells"] + CELLS, None),
    # sides a hundredth short of the reach: places within reach can lie two cells apart
    ("cells-side-below-reach", "src/cells.c", "reach > 0.0 && isfinite(reach) ? reach :",
     "reach > 0.0 && isfinite(reach) ? 0.99 * reach :", ["test_cells"] + CELLS, None),
    # two cells along a periodic axis: the one neighbour is both below and above
    ("cells-periodic-two-cells", "src/cells.c", "if (g->periodic[k] && cells < 3.0)\n            cells = 3.0;",
     "if (g->periodic[k] && cells < 2.0)\n            cells = 2.0;", ["test_cells"] + CELLS, None),
    ("cells-clamp-past-last", "src/cells.c", "return c >= (double)dim ? dim - 1 : (size_t)c;",
     "return c > (double)dim ? dim - 1 : (size_t)c;", ["test_cells"] + CELLS, None),
    ("cells-place-no-move", "src/cells.c", "    if (c != g->m[i].cell)\n        move_member(g, i, c);", "",
     ["test_cells"] + LISTS + CELLS, None),
    # ---- the cells event loop ----
    # every scene taken for equal masses: a pair of unequal masses reacts with the first's
    ("mass-all-any", "src/algo_predictive.c", "same_mass &= sim->st.mass[i] == sim->st.mass[0];",
     "same_mass &= true;", SIM, None),
    # ---- cells mode without a box: the cells fitted to the spheres' extent ----
    # a long step in a periodic box: all-pairs mode's reactions take the touching image of
    # stored positions periods apart; cells mode's expiries keep stored positions current
    ("allpairs-sep-near-image", "src/pred_impl.h",
     "return c->image_horizon ? nbep_periodic_image(&c->pb, d) : nbep_periodic_near_image(&c->pb, d);",
     "return nbep_periodic_near_image(&c->pb, d);", ["test_periodic"], None),
    ("cells-expiry-not-brought", "src/pred_cells.c",
     "    x->s->pos[i] = *p;\n    x->s->vel[i] = *v;\n    x->c->tau[i] = t - x->T0;\n    if (!nbep_periodic_inside(&x->c->pb, *p)) {",
     "    if (!nbep_periodic_inside(&x->c->pb, *p)) {\n    x->s->pos[i] = *p;\n    x->s->vel[i] = *v;\n    x->c->tau[i] = t - x->T0;",
     ["test_periodic"], None),
    ("fit-never-outgrown", "src/pred_cells.c",
     "    return lo.x < c->fit_lo.x || lo.y < c->fit_lo.y || lo.z < c->fit_lo.z ||",
     "    return false;\n    return lo.x < c->fit_lo.x || lo.y < c->fit_lo.y || lo.z < c->fit_lo.z ||",
     CELLS, None),
    ("fit-bounds-thread-0", "src/pred_impl.h",
     "    for (int t = 1; t < c->nt; t++) {\n        const thread_ws *u = &c->ws[t];\n        l = ",
     "    for (int t = 1; t < 1; t++) {\n        const thread_ws *u = &c->ws[t];\n        l = ",
     CELLS, None),
    ("fit-pad-fixed", "src/pred_cells.c", "fmax(floor_pad, 0.125 * (hi.x - lo.x))",
     "fmax(floor_pad, 0.0 * (hi.x - lo.x))", CELLS, None),
    ("cells-cap-all-axes", "src/cells.c", "        side[widest] *= 2.0;",
     "        side[0] *= 2.0, side[1] *= 2.0, side[2] *= 2.0;", ["test_cells"], None),
    ("cells-refit-no-room", "src/cells.c", "    if (g->n_cells > g->cap_cells) {",
     "    if (0) {", ["test_cells"], None),
    ("cells-refit-old-layout", "src/cells.c", "    assert(!g->periodic[0] && !g->periodic[1] && !g->periodic[2]);\n    lay_out(g, lo, hi, reach);",
     "    assert(!g->periodic[0] && !g->periodic[1] && !g->periodic[2]);", ["test_cells"], None),
    ("evloop-next-item-left", "src/evloop.c", "    w->n_next = (uint8_t)(n + 1);",
     "    w->n_next = (uint8_t)n;", CELLS, None),
    ("evloop-next-all-lost", "src/evloop.c", "            nbep__evloop_schedule_one(e, w->changed[k]);",
     "            (void)0;", CELLS + GRAN, None),
    ("evloop-changed-unpredicted", "src/evloop.c",
     "            if (w->changed[k] != i)\n                predict_one(e, ops, u, w->changed[k], t);",
     "            if (w->changed[k] != i && 0)\n                predict_one(e, ops, u, w->changed[k], t);",
     CELLS, None),
    ("evloop-react-stale", "src/evloop.c", "    if (ops->fresh(u, i, ev)) {", "    if (1) {", CELLS, None),
    ("evloop-list-skipped", "src/evloop.c",
     "    if (m > 0)\n        ops->pairs(u, i, js, m, near_face(e, ci), &best);\n",
     "", CELLS, None),
    ("evloop-exit-after-event", "src/evloop.c",
     "(best.kind == NBEP_EVENT_NONE || t_exit < best.time)",
     "(best.kind == NBEP_EVENT_NONE || t_exit > best.time)", CELLS, None),
    ("evloop-stray-whole-skin", "src/evloop.c", "e->stray = 0.5 * skin;", "e->stray = 1.5 * skin;",
     CELLS, None),
    ("evloop-rebuild-no-attach", "src/evloop.c",
     "        if (w->gain[k] && !nbep_nblist_append(&e->nl, w->near[k], i))",
     "        if (0 && !nbep_nblist_append(&e->nl, w->near[k], i))", CELLS, None),
    ("evloop-stray-accel-late", "src/evloop.c",
     "return 2.0 * left / (sv + sqrt(sv * sv + 2.0 * sa * left));",
     "return 4.0 * left / (sv + sqrt(sv * sv + 2.0 * sa * left));", CELLS + GRAN, None),
    ("evloop-rebuild-keeps-lost", "src/evloop.c",
     "            nbep_nblist_drop(&e->nl, w->was[k], i);", "            (void)0;", CELLS, None),
    ("evloop-rebuild-drops-kept", "src/evloop.c", "        w->kept[k] = 1;",
     "        (void)0;", CELLS, None),
    ("evloop-list-centred-behind", "src/evloop.c",
     "nbep_vec3_add(p, nbep_vec3_scale(v, NBEP_NBLIST_LEAD * e->stray / speed))",
     "nbep_vec3_add(p, nbep_vec3_scale(v, -NBEP_NBLIST_LEAD * e->stray / speed))", TEAM, None),
    ("evloop-stray-not-nearest", "src/evloop.c",
     "        d = nbep_vec3_add(d, nbep_periodic_near_shift(&e->pb, d));", "        (void)0;",
     TEAM, None),
    ("periodic-inside-closed-top", "include/nbep/periodic.h",
     "in &= !pb->axis[k] || (u >= 0.0 && u < pb->len[k]);",
     "in &= !pb->axis[k] || (u >= 0.0 && u <= pb->len[k]);", TEAM, None),
    ("periodic-inside-every-axis", "include/nbep/periodic.h",
     "in &= !pb->axis[k] || (u >= 0.0 && u < pb->len[k]);",
     "in &= (u >= 0.0 && u < pb->len[k]);", TEAM, None),
    ("cells-wrap-centre-unwrapped", "src/pred_cells.c",
     "        *p = x->s->pos[i];\n    }\n}", "    }\n}",
     LISTS + TEAM,
     "the flight returned is the expiring list's new centre only, and list_centre (evloop.c) "
     "wraps that centre into the box itself: an unwrapped flight gives the same centre but for "
     "the rounding of one period's shift, below what any list or event resolves"),
    ("cells-wrap-never", "src/pred_cells.c",
     "    if (!nbep_periodic_inside(&x->c->pb, *p)) {\n        nbep_periodic_wrap(",
     "    if (false) {\n        nbep_periodic_wrap(", TEAM, None),
    ("evloop-walk-no-images", "src/evloop.c",
     "a[k][q] = b.per[k][q] ? c[k] - b.per[k][q] * e->pb.len[k] : c[k];",
     "a[k][q] = c[k];", LISTS + TEAM, None),
    ("evloop-walk-prunes-rows", "src/evloop.c", "            if (!(gyz < cut2))",
     "            if (!(gyz < 0.5 * cut2))", LISTS + CELLS, None),
    ("evloop-walk-prunes-cells", "src/evloop.c", "                if (!(gyz + gap2[0][x] < cut2))",
     "                if (!(gyz + gap2[0][x] < 0.7 * cut2))", LISTS + CELLS, None),
    # the lists' skin by the scene's packing fraction (nblist.h), and the engine taking it
    ("skin-dilute-never", "include/nbep/nblist.h",
     "    if (phi <= NBEP_NBLIST_PHI_DILUTE)\n        return NBEP_NBLIST_SKIN_DILUTE;",
     "    if (phi <= NBEP_NBLIST_PHI_DILUTE)\n        return NBEP_NBLIST_SKIN;",
     ["test_nblist", "test_periodic"], None),
    ("skin-accelerating-dilute", "include/nbep/nblist.h",
     "    if (!flies_free || !(phi >= 0.0) || phi >= NBEP_NBLIST_PHI_DENSE)",
     "    if (!(phi >= 0.0) || phi >= NBEP_NBLIST_PHI_DENSE)", ["test_nblist"], None),
    ("skin-between-jumps", "include/nbep/nblist.h",
     "    return NBEP_NBLIST_SKIN_DILUTE + f * (NBEP_NBLIST_SKIN - NBEP_NBLIST_SKIN_DILUTE);",
     "    return NBEP_NBLIST_SKIN;", ["test_nblist"] + LISTS, None),
    ("skin-acceleration-unseen", "src/scene.c",
     "nbep_scene_packing_fraction(sc, st), nbep_state_free_flight(st));",
     "nbep_scene_packing_fraction(sc, st), true);", ["tests/test_cli.sh"], None),
    ("skin-engine-fixed", "src/evloop.c", "    double skin = skin_frac * reach;",
     "    double skin = NBEP_NBLIST_SKIN * reach;", LISTS + ["test_periodic"], None),
    # the walk's members kept without a branch and passed on in batches
    ("evloop-walk-lists-itself", "src/evloop.c",
     "            nn += (dx * dx + dy * dy + dz * dz < cut2) & (j != i);",
     "            nn += (dx * dx + dy * dy + dz * dz < cut2);", LISTS + CELLS, None),
    ("evloop-walk-full-batch-lost", "src/evloop.c",
     "            if (nn == NEAR_BATCH) {\n                for (size_t k = 0; k < nn; k++)\n                    f(e, i, near[k], arg);",
     "            if (nn == NEAR_BATCH) {\n                for (size_t k = 0; k < 0; k++)\n                    f(e, i, near[k], arg);",
     LISTS, None),
    ("evloop-walk-last-batch-lost", "src/evloop.c",
     "    for (size_t k = 0; k < nn; k++)\n        f(e, i, near[k], arg);\n}",
     "    for (size_t k = 0; k + 1 < nn; k++)\n        f(e, i, near[k], arg);\n}", LISTS + CELLS,
     None),
    ("evloop-walk-kept-first-of-list", "src/evloop.c",
     "        k = w->was[q] == j ? q : k;", "        k = w->was[q] == j ? 0 : k;", CELLS + LISTS,
     None),
    ("evloop-place-old-cell", "src/evloop.c", "nbep_cells_place(&e->cells, i, w->at, w->at_cell);",
     "nbep_cells_place(&e->cells, i, w->at, e->cells.m[i].cell);", LISTS + CELLS, None),
    # the cells laid out for less than the cutoff (as before the hysteresis went, cut / 1.125
    # with no side factor to cancel it): a walk misses centres two cells away
    ("evloop-cells-below-cut", "src/evloop.c",
     "nbep_cells_init(&e->cells, lo, hi, e->cut, n, periodic, d);",
     "nbep_cells_init(&e->cells, lo, hi, e->cut / 1.125, n, periodic, d);", LISTS + CELLS, None),
    ("evloop-refit-below-cut", "src/evloop.c", "nbep_cells_refit(&e->cells, lo, hi, e->cut, d);",
     "nbep_cells_refit(&e->cells, lo, hi, e->cut / 1.125, d);", LISTS + CELLS, None),
    ("evloop-rebuild-list-short", "src/evloop.c", "e->failed ? 0 : w->n_near", "e->failed ? 0 : w->n_near - (w->n_near > 0)",
     LISTS + CELLS, None),
    ("cells-gap-slab-shrunk", "include/nbep/cells.h", "s = g->h[k] / 64.0;", "s = -g->h[k] / 8.0;",
     ["test_cells"] + LISTS, None),
    ("cells-gap-wall-closed", "include/nbep/cells.h", "    const double lo = idx > 0 || g->periodic[k] ? o + (double)idx * g->h[k] - s : -INFINITY;",
     "    const double lo = o + (double)idx * g->h[k] - s;", ["test_cells"] + LISTS, None),
    ("nblist-set-short", "src/nblist.c", "        l->sp[i].cnt = (uint32_t)m;", "        l->sp[i].cnt = (uint32_t)m - (m > 0);",
     ["test_nblist"] + LISTS, None),
    ("nblist-set-past-room", "src/nblist.c", "    if (m <= l->sp[i].cap) {", "    if (m <= l->sp[i].cap + 2) {",
     ["test_nblist"], None),
    ("overlap-check-no-images", "src/state.c", "        if (per > 0.0 && x[a] + per - reach <= hi)",
     "        if (0)", TEAM, None),
    ("frame-overlap-leader-only", "src/sim.c",
     "    nbep_state_overlap_part(&sim->st, &sim->overlap_grid, sim->overlap_rmax, own.lo, own.hi,",
     "    nbep_state_overlap_part(&sim->st, &sim->overlap_grid, sim->overlap_rmax, own.lo, tid ? own.lo : own.hi,",
     TEAM, None),
    ("frame-overlap-not-merged", "src/sim.c", "    m->overlap = fmax(m->overlap, best.max);",
     "    (void)0;", TEAM, None),
    ("frame-overlap-grid-unsorted", "src/sim.c", "    nbep_barrier_wait(bar);\n    nbep_overlap best",
     "    nbep_overlap best", TEAM, None),
    ("overlap-check-skips-shallow", "src/state.c", "if (d2 > sum * sum * (1.0 + 1e-12))",
     "if (d2 > sum * sum * (1.0 - 1e-6))", TEAM, None),
    # ---- the cells team loop (two threads, events handled ahead and committed in order) ----
    ("team-helper-takes-an-old-end", "src/evloop_team.c",
     "        if (atomic_load_explicit(&e->quit, memory_order_acquire) == call) {",
     "        const uint64_t q_ = atomic_load_explicit(&e->quit, memory_order_acquire);\n        if (q_ != atomic_load_explicit(&e->done[t].word, memory_order_relaxed) && (call = q_)) {",
     TEAM, None),
    ("team-handled-by-two", "src/evloop_team.c", "    for (int t = 1; t < e->crew; t++)\n        if (atomic_load_explicit(&e->ws[t][k].place",
     "    for (int t = 1; t < 2; t++)\n        if (atomic_load_explicit(&e->ws[t][k].place", TEAM, None),
    ("team-apart-unwrapped", "src/evloop_team.c", "        dx = dx > hx ? lx - dx : dx; /* half",
     "        dx = dx; /* half", APART, None),
    ("team-apart-other-unwrapped", "src/evloop_team.c", "        ex = ex > hx ? lx - ex : ex;",
     "        ex = ex;", APART, None),
    ("team-apart-halved", "src/evloop_team.c", "    const float near2 = e->near2;",
     "    const float near2 = 0.01f * e->near2;", APART, None),
    ("team-walks-not-apart", "src/evloop_team.c",
     "    return e->batch_walks[a] && e->batch_walks[k] &&\n           !cells_apart(e, e->batch_cell[a], e->batch_cell[k]);",
     "    return false;", APART, None),
    ("pair-bound-no-shortfall", "include/nbep/predict.h",
     "    const double g = d - sigma - 1e-12 * d;", "    const double g = d - sigma;", PRED, None),
    ("pair-bound-any-scale", "include/nbep/predict.h",
     "        if (!nbep__predict_bound_scale(c[k]))\n            return 0.0;", "", PRED, None),
    ("pair-bound-no-accel", "include/nbep/predict.h",
     "    const double t_all = 2.0 * g / (v + sqrt(vv + 2.0 * a * g));",
     "    const double t_all = 2.0 * g / (v + sqrt(vv + 0.0 * a * g));", PRED, None),
    ("pair-bound-line-no-cap", "include/nbep/predict.h",
     "    t_line = t_line < t_cap ? t_line : t_cap;\n", "", PRED, None),
    ("pair-bound-line-push-apart", "include/nbep/predict.h",
     "    const double ac = p2 < 0.0 ? -p2 : 0.0;", "    const double ac = -p2;", PRED, None),
    ("pair-bound-line-no-accel", "include/nbep/predict.h",
     "        t_line = 2.0 * g / (-p1 + sqrt(p1 * p1 + 2.0 * ac * g));",
     "        t_line = 2.0 * g / (-p1 + sqrt(p1 * p1 + 0.0 * ac * g));", PRED, None),
    ("pair-bound-never-loose", "include/nbep/predict.h",
     "vv + pa >= e4 * (vv + pa_size) && va >= e4 * va_size)",
     "vv + pa >= e4 * (vv + pa_size))", PRED, None),
    ("grid-horizon-hides-planes", "src/pred_find.c",
     "    if (best.kind == NBEP_EVENT_NONE || !(best.time <= c->horizon))\n        best = (nbep_event){c->horizon, 0, NBEP_EVENT_HORIZON, c->ver[i], 0};",
     "    best = (nbep_event){c->horizon, 0, NBEP_EVENT_HORIZON, c->ver[i], 0};", SIM + GRAN,
     None),
    ("grid-horizon-late", "src/pred_find.c",
     "    if (best.kind == NBEP_EVENT_NONE || !(best.time <= c->horizon))\n        best = (nbep_event){c->horizon, 0, NBEP_EVENT_HORIZON, c->ver[i], 0};",
     "    if (best.kind == NBEP_EVENT_NONE || !(best.time <= c->horizon))\n        best = (nbep_event){c->horizon + 1e-3, 0, NBEP_EVENT_HORIZON, c->ver[i], 0};", SIM + GRAN,
     None),
    # all-pairs mode's image horizons (periodic box) that fall inside a step: a sphere that
    # strays more than its image reach in one step (test_periodic's tiny box at dt = 0.25)
    ("image-horizon-in-step-dropped", "src/algo_predictive.c",
     "(best.kind == NBEP_EVENT_HORIZON && c->image_horizon)))\n                add_cand(c, w, i);",
     "(best.kind == NBEP_EVENT_HORIZON && false)))\n                add_cand(c, w, i);",
     ["test_periodic"], None),
    ("image-horizon-react-no-op", "src/pred_react.c",
     "        fire(c, w, s, lo, still_lo);\n        return;\n    }\n    if (ev->kind == NBEP_EVENT_PLANE) {",
     "        return;\n    }\n    if (ev->kind == NBEP_EVENT_PLANE) {",
     ["test_periodic"], None),
    ("grid-crew-takes-no-candidates", "src/algo_predictive.c",
     "                    memcpy(w->cand, w->redo, w->n_redo * sizeof *w->cand);\n                    w->n_cand = w->n_redo;\n",
     "", GRAN, None),
    ("grid-crew-replaces-lists-early", "src/algo_predictive.c",
     "                    nbep_barrier_wait(bar); /* every list read before any is replaced */\n", "",
     GRAN, None),
    ("grid-woken-recounted", "src/algo_predictive.c",
     "            uint64_t seen_woken = c->seen_before;",
     "            uint64_t seen_woken = 0;\n            for (int t = 0; t < nt; t++)\n                seen_woken += c->ws[t].woken;",
     GRAN, None),
    ("grid-jam-crew-only", "src/algo_predictive.c",
     "    for (int t = 0; t < c->nt; t++)\n        if (c->ws[t].jammed && (!jammed || c->ws[t].jammed < jammed))",
     "    for (int t = 0; t < 2; t++)\n        if (c->ws[t].jammed && (!jammed || c->ws[t].jammed < jammed))",
     ["tests/test_jam.sh"], None),
    ("grid-jam-after-letgo-unseen", "src/algo_predictive.c",
     "                    let_go_phase(c, s, mine, bar, sim->dt, t_min - T0, w);\n                    jammed = lowest_jammed(c);",
     "                    let_go_phase(c, s, mine, bar, sim->dt, t_min - T0, w);", ["tests/test_jam.sh"], None),
    ("grid-crew-quit-unshared", "src/algo_predictive.c",
     "                quit = c->crew_quit;\n", "", ["tests/test_jam.sh"], None),
    ("grid-crew-tmin-all", "src/algo_predictive.c",
     "                for (int t = 0; t < k_all; t++)\n                    t_min = fmin(t_min, c->ws[t].t_min);",
     "                for (int t = 0; t < nt; t++)\n                    t_min = fmin(t_min, c->ws[t].t_min);", GRAN, None),
    ("grid-crew-fired-all", "src/algo_predictive.c",
     "        for (int t = 0; t < crew; t++) {\n            const thread_ws *o = &c->ws[t];\n            for (size_t k = 0; k < o->n_fired; k++) {",
     "        for (int t = 0; t < c->nt; t++) {\n            const thread_ws *o = &c->ws[t];\n            for (size_t k = 0; k < o->n_fired; k++) {", GRAN, None),
    ("cells-pairs-first-twice", "src/pred_find.c",
     "        const size_t k = q == 0 ? first : q == first ? 0 : q;",
     "        const size_t k = q == 0 ? first : q;", CELLS + GRAN, None),
    ("team-other-forgotten", "src/evloop_team.c",
     "    e->batch_other[k] = other < e->n ? other : NO_SPHERE;",
     "    e->batch_other[k] = NO_SPHERE;", APART, None),
    ("team-expiry-unseen", "src/evloop_team.c", "    const bool walks = nbep__evloop_key_expiry(c.key, c.item);",
     "    const bool walks = false;", APART, None),
    ("team-plane-zero-walks", "src/evloop_impl.h", "        b = UINT32_MAX - 1 - ev->partner;",
     "        b = UINT32_MAX - ev->partner;", APART, None),
    ("team-walks-3-cells-apart", "src/evloop_team.c", "        if (d >= 4)\n            return true;",
     "        if (d >= 3)\n            return true;", APART, None),
    ("team-cells-unwrapped", "src/evloop_team.c",
     "        if (e->cells.periodic[k] && d > e->cells.dim[k] - d)", "        if (0)", APART, None),
    ("team-undo-nothing", "src/evloop_team.c",
     "        ops->restore(uk, w->kept_id[k], &w->kept_motion[k]);\n        nbep_feq_put(e->q, w->kept_id[k], w->kept_slot[k]);",
     "        (void)0;", TEAM, None),
    ("team-commit-unchecked", "src/evloop_team.c",
     "            if (nbep_calendar_first(e->cal, &top) &&\n                nbep_calendar_before(top, e->batch_entry[k])) {",
     "            if (0) {", TEAM, None),
    ("team-keeps-one-sphere", "src/evloop_team.c",
     "    if (e->batch_other[k] != NO_SPHERE)\n        w->kept_id[w->n_kept++] = e->batch_other[k];\n",
     "", TEAM, None),
    ("team-other-not-put-back", "src/evloop_team.c",
     "    nbep__evloop_schedule_one(e, e->batch[k]);\n    if (e->batch_other[k] != NO_SPHERE)\n        nbep__evloop_schedule_one(e, e->batch_other[k]);",
     "    nbep__evloop_schedule_one(e, e->batch[k]);", TEAM,
     "equivalent: an undone pair's other comes after its place in the calendar's order, and the place's commit sets the other's entry before its turn"),
    ("team-undo-entries-lost", "src/evloop_team.c", "        put_back(e, p);", "        (void)0;", TEAM, None),
    ("team-commit-other-lost", "src/evloop_team.c",
     "        if (e->batch_other[k] != NO_SPHERE && !nbep__evloop_commit_sets(w, e->batch_other[k]))",
     "        if (0)", TEAM, None),
    # a cooling gas on the team loop: the TC clocks and reaction counts undone with the motion,
    # and a reaction's stop heeded once it stands
    ("team-tc-clock-not-put-back", "src/pred_cells.c",
     "    if (x->c->t_last)\n        memcpy(&x->c->t_last[i], &m->own[0], sizeof *x->c->t_last);",
     "    (void)0;", TEAM, None),
    ("team-jam-count-not-put-back", "src/pred_cells.c",
     "    if (x->c->jam)\n        memcpy(&x->c->jam[i], &m->own[1], sizeof *x->c->jam);",
     "    (void)0;", ["tests/test_jam.sh"], None),
    ("team-stop-unheeded", "src/evloop_team.c", "        if (w->stop) { /* its reaction stopped the run",
     "        if (0) { /* its reaction stopped the run", ["tests/test_jam.sh"] + TEAM, None),
    ("team-stop-next-kept", "src/evloop_team.c",
     "            undo_from(e, ops, u, us, s + 1);\n            nbep_calendar_set(e->cal, e->batch[k],",
     "            undo_from(e, ops, u, us, s + 2);\n            nbep_calendar_set(e->cal, e->batch[k],",
     TEAM, None),
    ("team-off-at-dissipation", "src/algo_predictive.c",
     "const bool can_team = nt >= 2 && p.free_flight;",
     "const bool can_team = nt >= 2 && p.free_flight && !p.jam_model;", TEAM, None),
    ("team-jammed-carried-over", "src/pred_cells.c",
     "    w->jammed = 0;", "    (void)0;", ["tests/test_jam.sh"],
     "equivalent in practice: a speculative reaction that passed the limit and was undone is "
     "handled again from the same count, and passes it again, unless an earlier reaction took "
     "its sphere elsewhere and none of the sphere's later ones in the step does; no scene of the "
     "tests has one"),
    ("team-intruder-taken", "src/evloop_team.c", "        if (!nbep_calendar_before(e->cur, c)) {",
     "        if (0) {", TEAM, None),
    ("team-ring-half-unseen", "src/evloop_team.c", "    return near_span(e, a, b, 0, 2 * WINDOW);",
     "    return near_span(e, a, b, 0, WINDOW);", APART, None),
    ("pocket-gathers-what-rests-on-it", "src/pred_react.c",
     "        (x->holds && leans_on(x->c, m, x->k)))",
     "        0)", ["tests/test_settle.sh"], None),
    ("land-on-what-rests-on-it", "src/pred_react.c",
     "        r.n < NBEP_CONTACT_MAX && !leans_on(c, j, k)) {",
     "        r.n < NBEP_CONTACT_MAX) {", GRAN + ["tests/test_settle.sh"], None),
    ("land-keeps-what-rests-on-it", "src/pred_react.c",
     "    rest_set r = c->rest[k];\n    drop_leaning(c, k, &r);\n    const double amag",
     "    rest_set r = c->rest[k];\n    const double amag", ["tests/test_settle.sh"],
     "equivalent: land_on_held's k is the sphere of the pair that is not held, and a sphere "
     "that is not held names no sphere among its contacts, so drop_leaning has nothing to "
     "drop: every change to a rest set is a hold (try_hold, land_on_held, jam_hold, "
     "settle_hold: still set) or goes through rest_solve (update_rest, let_go, a plane's "
     "rest, a resume), which keeps sphere contacts only when it returns held and otherwise "
     "solves the planes alone; settling's stamps change versions only. An instrumented build "
     "(every fire, landing and jam hold) found no free sphere with a sphere contact in "
     "test_granular, test_settle.sh's scenes and 30-sphere pours in grid and cells mode"),
    # ---- exact sums (xsum.c) and the step's sums over threads ----
    ("xsum-no-sticky", "src/xsum.c", "        v = ldexp((double)(w | (uint64_t)sticky),",
     "        v = ldexp((double)w,", ["test_xsum"], None),
    ("xsum-merge-no-carry", "src/xsum.c", "    if (a->adds >= BATCH)\n        carry(a);",
     "    (void)0;", ["test_xsum"], None),
    ("xsum-negative-off-by-one", "src/xsum.c", "    uint64_t one = 1; /* -D = ~D + 1 */",
     "    uint64_t one = 0; /* -D = ~D + 1 */", ["test_xsum"], None),
    ("step-sums-by-thread", "src/sim.c",
     "        nbep_xsum_merge(&virial, &tm->virial);\n        nbep_xsum_clear(&tm->virial);\n    }\n    row.virial = nbep_xsum_value(&virial);",
     "        row.virial += nbep_xsum_value(&tm->virial);\n        nbep_xsum_clear(&tm->virial);\n    }",
     GRAN, None),
    ("team-merge-drops-counts", "src/pred_cells.c", "        x->cnt->c[k] += h->cnt->c[k];",
     "        (void)0;", TEAM, None),
    ("team-merge-drops-virial", "src/pred_cells.c", "    nbep_xsum_merge(&a->virial, &b->virial);",
     "    (void)0;", TEAM, None),
    ("team-merge-drops-walls", "src/pred_cells.c", "        nbep_xsum_merge(&a->wall[p], &b->wall[p]);",
     "        (void)0;", TEAM, None),
    ("team-counts-not-cleared", "src/pred_cells.c", "        h->cnt->c[k] = 0;",
     "        (void)0;", TEAM, None),
    ("team-undone-counts-kept", "src/evloop_team.c", "    ops->clear(us[k]); /* its counts from zero, on this thread */",
     "    (void)0;", TEAM, None),
    ("team-settle-undone", "src/evloop_team.c",
     "    if (w->stood == atomic_load_explicit(&w->place, memory_order_relaxed))\n        ops->merge(own, uw);",
     "    ops->merge(own, uw);", TEAM, None),
    ("team-stood-unmarked", "src/evloop_team.c", "        w->stood = s;\n        if (w->stop) {",
     "        (void)0;\n        if (w->stop) {", TEAM, None),
    ("team-take-unsettled", "src/evloop_team.c", "    settle(ops, w, own, us[k]);\n    if (!e->batch_first[k])",
     "    if (!e->batch_first[k])", TEAM, None),
    ("team-helper-end-unsettled", "src/evloop_team.c",
     "            settle_all(e, ops, u, us, t); /* the leader wrote every `stood` before quit */",
     "            (void)0;", TEAM, None),
    ("team-leader-end-unsettled", "src/evloop_team.c", "    settle_all(e, ops, u, us, 0);\n",
     "", TEAM, None),
    ("team-helper-taken-as-leader", "src/evloop_team.c",
     "        if (atomic_load_explicit(&e->ws[t][k].place, memory_order_acquire) == s)\n            return t;",
     "        if (atomic_load_explicit(&e->ws[t][k].place, memory_order_acquire) == s)\n            return 0;",
     TEAM, None),
    # a walk's workspace grown past the 64 lists it starts with (lists of 260 in
    # test_evloop_lists' two sizes: no other test has lists that long)
    ("walk-grows-once", "src/evloop.c", "    while (m > w->cap)\n        if (!grow_ws(w)) {",
     "    if (m > w->cap)\n        if (!grow_ws(w)) {", LISTS, None),
    ("walk-room-uncounted", "src/evloop.c", "    w->cap = cap;\n    return true;",
     "    return true;", LISTS, None),
    # the ways out of a fault (test_team_faults: a stall, a walk out of memory, from a time
    # on): the team stops where the one thread does, with its state
    ("team-stall-stuck-kept", "src/evloop_team.c",
     "                undo_from(e, ops, u, us, s);\n                tally->events++;",
     "                undo_from(e, ops, u, us, s + 1);\n                tally->events++;", FAULTS, None),
    ("team-failed-ahead-kept", "src/evloop_team.c",
     "        if (e->failed) {\n            undo_from(e, ops, u, us, s + 1);",
     "        if (e->failed) {\n            (void)0;", FAULTS, None),
    ("team-failed-walk-goes-on", "src/evloop_team.c",
     "        if (e->failed) {\n            undo_from(e, ops, u, us, s + 1);\n            return false;",
     "        if (e->failed) {\n            undo_from(e, ops, u, us, s + 1);\n            e->failed = false;",
     FAULTS, None),
    ("evloop-failed-walk-committed", "src/evloop.c", "    if (w->oom)\n        e->failed = true;",
     "    (void)0;", FAULTS, None),
    ("evloop-stall-after-handling", "src/evloop.c",
     "        tally->events++;\n        if (!nbep__evloop_advances(stall, t)) {\n            *t_stuck = t;\n            return false;\n        }\n        nbep__evloop_handle(e, w, ops, u, i, &ev, t, true);",
     "        tally->events++;\n        nbep__evloop_handle(e, w, ops, u, i, &ev, t, true);\n        if (!nbep__evloop_advances(stall, t)) {\n            *t_stuck = t;\n            return false;\n        }",
     FAULTS, None),
    # the progress within a long step (live on a terminal: test_signals.sh under script(1))
    ("progress-within-cells-unlooked", "src/evloop_impl.h",
     "        if (st->on_look)\n            st->on_look(st->look_ctx, t);", "", ["tests/test_signals.sh"], None),
    ("progress-within-rounds-unlooked", "src/algo_predictive.c",
     "                if (look && tid == 0) /* the progress within a long step */",
     "                if (0) /* the progress within a long step */", ["tests/test_signals.sh"], None),
    ("progress-within-part-dropped", "src/sim.c",
     "    const double at = (double)(step - 1) + (part > 0.0 ? fmin(part, 0.99) : 0.0);",
     "    const double at = (double)(step - 1);", ["tests/test_signals.sh"], None),
    # a resume from frame 0 predicts afresh, as the uninterrupted run did (its step 1 row)
    ("resume-zero-imported", "src/sim.c",
     "opt->resume->has_events && opt->resume->step > 0 && algo->import_events)",
     "opt->resume->has_events && algo->import_events)", ["tests/test_resume.sh"], None),
    # a signal during a step's events abandons the step (test_team_faults: raised at a time,
    # on every thread count; test_signals.sh: a step of minutes, SIGTERM, every loop)
    ("stop-never-looked", "src/evloop_impl.h",
     "        if (st->stop && atomic_load_explicit(st->stop, memory_order_relaxed) != 0) {",
     "        if (0) {", FAULTS + ["tests/test_signals.sh"], None),
    ("stop-look-not-rearmed", "src/evloop_impl.h",
     "    if (++st->looks >= NBEP_EVLOOP_STOP_EVERY) {\n        st->looks = 0;",
     "    if (++st->looks == NBEP_EVLOOP_STOP_EVERY) {", ["tests/test_signals.sh"], None),
    ("stop-taken-for-stall", "src/pred_cells.c", "    if (fail && stall->stopped) {",
     "    if (0) {", FAULTS + ["tests/test_signals.sh"], None),
    ("stop-not-abandoned", "src/sim.c",
     "    sim->status = nbep_sim_stop_status(sim->opt.stop_signal);\n    sim->abandoned = true;",
     "    sim->status = nbep_sim_stop_status(sim->opt.stop_signal);", FAULTS + ["tests/test_signals.sh"],
     None),
    ("stop-rounds-never-looked", "src/algo_predictive.c",
     "                if (look && tid == 0 && nbep_sim_stop_status(sim->opt.stop_signal) != NBEP_OK)",
     "                if (0)", ["tests/test_signals.sh"], None),
    ("stop-rounds-thread0-alone", "src/algo_predictive.c",
     "                if (look && atomic_load_explicit(&c->round_stop, memory_order_relaxed)) {",
     "                if (look && tid == 0 && atomic_load_explicit(&c->round_stop, memory_order_relaxed)) {",
     ["tests/test_signals.sh"], None),
    ("stop-progress-left-open", "src/sim.c",
     "    if (sim->abandoned || sim->line_open)\n        progress(sim, sim->steps_done, true);", "",
     ["tests/test_signals.sh"], None),
    # a signal within a naive or seminaive step (test_detect_stop: raised at a row, on every
    # thread count; test_signals.sh: a long pass, SIGTERM, the live line within it)
    ("detect-stop-never-looked", "src/algo_detect.c",
     "            if (nbep_sim_stop_status(sim->opt.stop_signal) != NBEP_OK) {",
     "            if (0) {", ["test_detect_stop", "tests/test_signals.sh"], None),
    ("detect-stop-looks-once", "src/algo_detect.c", "            look = done + LOOK_COST;",
     "            look = UINT64_MAX;", ["tests/test_signals.sh"], None),
    ("detect-stop-not-put-back", "src/algo_detect.c",
     "                    s->pos[i] = ctx->pos0[i];\n                    s->vel[i] = ctx->vel0[i];",
     "                    (void)0;", ["test_detect_stop"], None),
    ("detect-stop-velocity-not-put-back", "src/algo_detect.c",
     "                    s->vel[i] = ctx->vel0[i];", "                    (void)0;",
     ["test_detect_stop"], None),
    ("detect-stop-thread0-alone", "src/algo_detect.c",
     "            if (atomic_load_explicit(&ctx->quit, memory_order_relaxed)) {",
     "            if (tid == 0 && atomic_load_explicit(&ctx->quit, memory_order_relaxed)) {",
     ["test_detect_stop"], None),
    ("detect-stop-abandon-unsaid", "src/algo_detect.c",
     "                if (tid == 0)\n                    nbep__sim_abandon(sim);", "",
     ["test_detect_stop", "tests/test_signals.sh"], None),
    ("detect-progress-part-dropped", "src/algo_detect.c",
     "nbep__sim_progress_part(sim, step, (double)done / (double)l->cost);",
     "nbep__sim_progress_part(sim, step, 0.0);", ["tests/test_signals.sh"], None),
    ("detect-overlap-not-kept", "src/algo_detect.c",
     "            mx->overlap = fmax(mx->overlap, deep.overlap);", "", ["test_detect_stop"] + SIM,
     None),
    ("detect-overlap-rel-not-kept", "src/algo_detect.c",
     "            mx->overlap_rel = fmax(mx->overlap_rel, deep.overlap_rel);", "",
     ["test_detect_stop"] + SIM, None),
    # the first predictions' progress, and its live line ended by a signal among them
    ("setup-progress-dropped", "src/algo_predictive.c",
     "            nbep__sim_progress_setup(setup, (double)end / (double)total);", "            (void)0;",
     ["tests/test_signals.sh"], None),
    ("setup-progress-left-open", "src/sim.c", "    if (sim->abandoned || sim->line_open)",
     "    if (sim->abandoned)", ["tests/test_signals.sh"], None),
    ("stop-frame-last-unset", "src/sim.c", "    if (st == NBEP_OK)\n        sim->frame_last = step;",
     "    (void)0;", FAULTS, None),
    # ---- the ways a step's events run (pred_ways.c): the schedule for given costs ----
    ("team-way-one-slot", "src/pred_ways.c",
     "    int *next = &w->way[(step + 1) & 1], *probe = &w->probe[(step + 1) & 1];",
     "    int *next = &w->way[step & 1], *probe = &w->probe[(step + 1) & 1];", WAYS + TEAM, None),
    ("team-probe-one-slot", "src/pred_ways.c",
     "    int *next = &w->way[(step + 1) & 1], *probe = &w->probe[(step + 1) & 1];",
     "    int *next = &w->way[(step + 1) & 1], *probe = &w->probe[step & 1];", WAYS + TEAM, None),
    ("ways-probe-period", "src/pred_ways.c", "#define TEAM_PROBE 8\n", "#define TEAM_PROBE 16\n",
     WAYS, None),
    ("ways-probe-far-period", "src/pred_ways.c", "#define TEAM_PROBE_FAR 64\n",
     "#define TEAM_PROBE_FAR 32\n", WAYS, None),
    ("ways-clear-threshold", "src/pred_ways.c", "#define TEAM_CLEAR 1.25\n",
     "#define TEAM_CLEAR 2.5\n", WAYS, None),
    ("ways-mean-not-kept", "src/pred_ways.c", "*m = *m > 0.0 && !probe ? 0.5 * (*m + per) : per;",
     "*m = per;", WAYS, None),
    ("ways-probe-averaged", "src/pred_ways.c", "*m = *m > 0.0 && !probe ? 0.5 * (*m + per) : per;",
     "*m = *m > 0.0 ? 0.5 * (*m + per) : per;", WAYS, None),
    ("ways-no-events-measured", "src/pred_ways.c", "    if (events > 0) {\n        const double per",
     "    if (events >= 0) {\n        const double per", WAYS, None),
    ("ways-ties-to-fewer-threads", "src/pred_ways.c", "(w->cost[k] < w->cost[best] || w->cost[best] == 0.0)",
     "(w->cost[k] <= w->cost[best] || w->cost[best] == 0.0)", WAYS, None),
    ("ways-unmeasured-smallest-first", "src/pred_ways.c",
     "    for (int k = w->n - 1; k >= 0; k--)\n        if (w->cost[k] == 0.0) {",
     "    for (int k = 0; k < w->n; k++)\n        if (w->cost[k] == 0.0) {", WAYS, None),
    ("ways-probes-one-way", "src/pred_ways.c",
     "    const int other = (best + 1 + k) % w->n;", "    const int other = (best + 1) % w->n;",
     WAYS, None),
    ("ways-cycle-up", "src/pred_ways.c", "        *next = way > 0 ? way - 1 : w->n - 1;",
     "        *next = way < w->n - 1 ? way + 1 : 0;", WAYS, None),
    # a probe a whole step again (before 584504d), or a first way measured on a whole step
    ("ways-probe-whole-step", "src/pred_ways.c", "    if (parts)\n        *probe = other;",
     "    if (0)\n        *probe = other;", WAYS, None),
    ("ways-unmeasured-whole-step", "src/pred_ways.c", "            if (parts && k != best) {",
     "            if (0) {", WAYS, None),
    ("ways-unmeasured-taken-best", "src/pred_ways.c",
     "        if (w->cost[k] > 0.0 && (w->cost[k] < w->cost[best] || w->cost[best] == 0.0))",
     "        if (w->cost[k] < w->cost[best])", WAYS, None),
    ("ways-part-averaged", "src/pred_cells.c",
     "        nbep__pred_ways_note(&c->ways, way, true, tally.events, nbep_now() - t_loop);",
     "        nbep__pred_ways_note(&c->ways, way, false, tally.events, nbep_now() - t_loop);",
     WAYS, "the part's figure is a running mean with the way's last instead of replacing it: "
     "which way a step takes changes, never its results, and no test times a run"),
    ("ways-cycle-unsplit", "src/pred_ways.c",
     "        if (parts && w->n > 1)\n            *probe", "        if (0)\n            *probe",
     WAYS, None),
    # the parts of a step: a helper of the second part joins before the first has ended
    ("team-parts-no-barrier", "src/pred_cells.c",
     "u.T0 + PRED_WAYS_PART * sim->dt, &stall, step, &c->part_failed);\n            nbep_barrier_wait(&c->bar);",
     "u.T0 + PRED_WAYS_PART * sim->dt, &stall, step, &c->part_failed);", TEAM, None),
    ("team-parts-first-part-to-end", "src/pred_cells.c",
     "u.T0 + PRED_WAYS_PART * sim->dt, &stall, step, &c->part_failed);",
     "T_end, &stall, step, &c->part_failed);", TEAM,
     "the first part runs the whole step's events and the second none: the same events in the "
     "same order, so the same results (what the part's length changes is only what a probe "
     "measures)"),
    ("ways-count-not-capped", "src/pred_ways.c",
     "k < NBEP_EVLOOP_TEAM_MAX ? (int)k : NBEP_EVLOOP_TEAM_MAX;", "(int)k;", WAYS, None),
    ("ways-first-step-never-ignored", "src/pred_ways.c",
     "w->way[0] = w->way[1] = force == PRED_WAYS_NEVER || n < 1 ? 0 : n - 1;",
     "w->way[0] = w->way[1] = n < 1 ? 0 : n - 1;", WAYS, None),
    ("ways-crew-times-a-change", "src/pred_ways.c",
     "    if (way != w->last && w->force != PRED_WAYS_CYCLE) {",
     "    if (way != w->last && w->force == PRED_WAYS_NEVER) {", WAYS, None),
    # ---- the run takes the scene's arrays (nbep_state_take): the scene's must not be freed too ----
    ("state-take-leaves-src", "src/state.c", "    src->pos = src->vel = src->acc = NULL;\n", "",
     ["test_threads", "tests/test_cli.sh"], None),
    # ---- neighbour lists ----
    ("nblist-drop-keeps-count", "src/nblist.c", "theirs[q] = theirs[--l->sp[i].cnt];",
     "theirs[q] = theirs[l->sp[i].cnt - 1];", ["test_nblist"] + CELLS, None),
    ("nblist-move-loses-entries", "src/nblist.c",
     "memcpy(l->pool + l->pool_len, l->pool + l->sp[i].off, l->sp[i].cnt * sizeof *l->pool);",
     "l->sp[i].cnt = 0;", ["test_nblist"] + CELLS, None),
    ("nblist-compact-spread-forward", "src/nblist.c", "    for (size_t k = l->n; k-- > 0;) {",
     "    for (size_t k = 0; k < l->n; k++) {", ["test_nblist"], None),
    ("nblist-compact-unsorted", "src/nblist.c", "    qsort(ord, l->n, sizeof *ord, by_key);\n", "",
     ["test_nblist"], None),
    ("nblist-compact-pack-rooms", "src/nblist.c", "        at += sp->cnt;\n", "        at += sp->cap;\n",
     ["test_nblist"], None),
    ("nblist-detach-keeps-own", "src/nblist.c",
     "        nbep_nblist_drop(l, mine[k], i);\n    nbep_nblist_clear(l, i);",
     "        nbep_nblist_drop(l, mine[k], i);", ["test_nblist"] + CELLS, None),
    ("nblist-compact-late", "src/nblist.c", "if (4u * l->pool_len > 5u * fresh && !compact(l, fresh, grown))",
     "if (2u * l->pool_len > 3u * fresh && !compact(l, fresh, grown))", ["test_nblist"], None),
    ("nblist-need-scratch-short", "include/nbep/nblist.h", "+ 5u * m + 8u;", "+ 4u * m + 8u;",
     ["test_nblist"], None),
    ("nblist-need-gain-unmoved", "include/nbep/nblist.h",
     "return n_gain * (size_t)nbep_nblist_grown(l->cap_max) + 5u * m + 8u;",
     "return n_gain * (size_t)l->cap_max + 5u * m + 8u;", ["test_nblist"], None),
    # ---- the root-free bound of the straight-flight kernel ----
    ("floor-bound-loose", "include/nbep/predict.h", "const double q = c / den * (1.0 - 1e-12);",
     "const double q = c / den * (2.0 - 1e-12);", ["test_predict"] + CELLS, None),
    ("bound-miss-margin-wrong-way", "include/nbep/predict.h",
     "!(bb - vc < -1e-12 * (bb + vv * (fabs(c) + pp)))", "!(bb - vc < 1e-12 * (bb + vv * (fabs(c) + pp)))",
     ["test_predict"] + CELLS, None),
    # ---- lasting contacts, TC model, cells-mode let-go ----
    ("contact-one-pushes", "src/contact.c", "if (!(an < 0.0))\n            return false;",
     "if (!(an > 0.0))\n            return false;", ["test_contact"] + GRAN, None),
    ("contact-leaves-tol", "src/contact.c", "if (m == 0 ? !(xn >= 0.0) : !(xn >= -tol))",
     "if (m == 0 ? !(xn >= 0.0) : !(xn >= tol))", ["test_contact"] + GRAN, None),
    ("contact-edge-pushes", "src/contact.c",
     "if (!(r1 - g * r2 >= -tol * den) || !(r2 - g * r1 >= -tol * den))",
     "if (!(r1 - g * r2 >= -tol * den))", ["test_contact"] + GRAN, None),
    # three contacts of a left-handed order taken as right-handed: the forces' signs flipped
    ("contact-corner-det-sign", "src/contact.c", "double s = det > 0.0 ? 1.0 : -1.0;", "double s = 1.0;",
     ["test_contact"] + GRAN, None),
    ("contact-no-triples", "src/contact.c", "for (int size = 0; size <= (k < 3 ? k : 3); size++)",
     "for (int size = 0; size <= (k < 2 ? k : 2); size++)", ["test_contact"] + GRAN, None),
    ("contact-tangent-edge-as-plane", "src/contact.c",
     "    if (line)\n        return nbep_vec3_scale(t, nbep_vec3_dot(v, t));",
     "    if (line)\n        return nbep_vec3_axpy(v, -nbep_vec3_dot(v, first), first);",
     ["test_contact"] + GRAN, None),
    # a second active normal parallel to the first (test_contact: two floors and a wall)
    ("contact-tangent-parallel-as-edge", "src/contact.c",
     "            if (!edge(first, n[j], &t))\n                continue;",
     "            (void)edge(first, n[j], &t);", ["test_contact"], None),
    ("contact-tangent-third-test", "src/contact.c",
     "} else if (fabs(nbep_vec3_dot(t, n[j])) > NBEP_CONTACT_TOL) {",
     "} else if (fabs(nbep_vec3_dot(t, n[j])) < NBEP_CONTACT_TOL) {", ["test_contact"] + GRAN, None),
    ("tc-off", "src/pred_react.c", "return recent ? 1.0 : e;", "return e;", SIM + GRAN, None),
    # a restitution a little off in the bulk of a gas (0.9 taken as 0.89): Haff's law
    ("restitution-off-by-a-hundredth", "src/pred_react.c", "return recent ? 1.0 : e;",
     "return recent ? 1.0 : e - 0.01;", TEAM, None),
    ("tc-own-history-only", "src/pred_react.c",
     "bool recent = t_abs - c->t_last[a] < tc || t_abs - c->t_last[b] < tc;",
     "bool recent = t_abs - c->t_last[a] < tc;", SIM + GRAN, None),
    ("tc-partner-unstamped", "src/pred_react.c",
     "    c->t_last[a] = t_abs;\n    c->t_last[b] = t_abs;\n", "    c->t_last[a] = t_abs;\n",
     SIM + GRAN, None),
    ("cells-no-let-go", "src/pred_cells.c",
     "            nbep_evloop_visit_block(x->c->ev, w->fired[k], cells_let_go, x);",
     "            (void)cells_let_go;", ["test_run_contract"] + CELLS + GRAN, None),
    ("cells-let-go-at-step-start", "src/pred_cells.c",
     "let_go(x->c, x->s, j, x->sc->dt, x->t_local, x->w);",
     "let_go(x->c, x->s, j, x->sc->dt, 0.0, x->w);", ["test_run_contract"] + CELLS + GRAN, None),
    # ---- run.order = "step": the paper's step (approximate, opt-in) ----
    ("order-step-ignored", "src/algo_predictive.c",
     "p.order_step = p.rounds && sc->order_step;", "p.order_step = false;", ORDER, None),
    ("order-step-cells-allowed", "src/scene.c",
     "(strcmp(sc->algorithm, \"predictive\") != 0 || sc->neighbors_cells))",
     "(strcmp(sc->algorithm, \"predictive\") != 0))", ORDER, None),
    ("order-step-react-at-round-min", "src/algo_predictive.c",
     "react(c, s, sc, ev->time, ev->time - T0, lo, hi, ev, w, cnt, mx);",
     "react(c, s, sc, t_min, t_min - T0, lo, hi, ev, w, cnt, mx);", ORDER, None),
    ("order-step-key-claim-without-time", "src/algo_predictive.c",
     "        if (c->order_step && !holds_time(c, ev, lo, hi))\n            continue;\n"
     "        claim_min(&c->claim[par][lo], key);",
     "        claim_min(&c->claim[par][lo], key);", ORDER, None),
    ("order-step-react-any-copy", "src/algo_predictive.c",
     "        if (c->order_step && !holds_time(c, ev, lo, hi))\n            continue;\n"
     "        /* Both copies", "        /* Both copies", ORDER, None),
    ("react-both-copies", "src/algo_predictive.c", "        if (seen == stamp ||\n",
     "        if (0 ||\n", SIM + ORDER, None),
    ("order-step-time-claim-lo-only", "src/algo_predictive.c",
     "            claim_min(&c->tclaim[hi], t);\n", "", ORDER, None),
    # ---- resuming ----
    ("resume-dt-unchecked", "src/output_resume.c",
     "    if (memcmp(&dt, &sc->dt, sizeof dt) != 0) {", "    if (0) {", ["tests/test_resume.sh"],
     None),
    ("resume-bodies-radius-mass-only", "src/output_resume.c",
     "    for (size_t k = 0; k < sizeof sets / sizeof *sets && rc == 0; k++) {",
     "    for (size_t k = 0; k < 2 && rc == 0; k++) {", ["tests/test_resume.sh"], None),
    ("resume-box-unchecked", "src/output_resume.c",
     "    if (has_box && !(sc->has_box && memcmp(&lo, &sc->box_min, sizeof lo) == 0 &&",
     "    if (0 && !(sc->has_box && memcmp(&lo, &sc->box_min, sizeof lo) == 0 &&",
     ["tests/test_resume.sh"], None),
    ("box-attrs-not-written", "src/output.c",
     "    if (sc->has_box &&\n        (nbep__output_write_attr(root, p, \"box_min\"",
     "    if (0 &&\n        (nbep__output_write_attr(root, p, \"box_min\"",
     ["test_output", "tests/test_resume.sh"], None),
    ("resume-not-noted", "src/output_resume.c",
     "    if (note_resume(o->file, path, sc, threads, o->xmf_step[frames - 1], d) < 0 ||\n        nbep__output_commit",
     "    if (nbep__output_commit", ["tests/test_resume.sh"], None),
    ("resume-cells-any-frame", "src/scene.c",
     "    return !nbep_scene_cells_engine(sc) || step % (int64_t)sc->output_every == 0;",
     "    return 1 || step % (int64_t)sc->output_every == 0;", ["tests/test_resume.sh"], None),
    ("resume-cells-rule-for-naive", "src/scene.c",
     "    return sc->neighbors_cells && strcmp(sc->algorithm, \"predictive\") == 0;",
     "    return sc->neighbors_cells;", ["tests/test_resume.sh"], None),
    ("resume-nothing-to-do-taken", "src/output_resume.c",
     "sc->steps <= (uint64_t)res.last_step) {", "sc->steps < (uint64_t)res.last_step) {",
     ["tests/test_resume.sh"], None),
    ("resume-begun-on-refusal", "src/output.c",
     "    if (o->resume.pending || o->staged) {\n        nbep__output_release(op);",
     "    if (o->staged) {\n        nbep__output_release(op);", ["test_output"], None),
    ("run-published-before-sim", "src/run.c",
     "                        : nbep_output_create_staged(file, &sc, threads, &out, d);",
     "                        : nbep_output_create(file, &sc, threads, &out, d);",
     ["tests/test_cli.sh"], None),
    ("run-summary-truncated-at-start", "src/run.c", "    *out = fopen(tmp, \"w\");",
     "    *out = fopen(where, \"w\");", ["tests/test_resume.sh"], None),
    ("resume-every-unchecked", "src/output_resume.c",
     "    if (has_every && every != sc->output_every && nbep_scene_cells_engine(sc)) {",
     "    if (0 && every != sc->output_every && nbep_scene_cells_engine(sc)) {", ["tests/test_resume.sh"],
     None),
    ("summary-drift-inf-kept", "src/sim.c",
     "    if (isinf(s->energy_rel_drift))\n        s->energy_rel_drift = copysign(DBL_MAX, s->energy_rel_drift);",
     "", ["tests/test_cli.sh"], None),
    ("summary-alias-unresolved", "src/run.c", "    const bool same = ca && cb && strcmp(ca, cb) == 0;",
     "    const bool same = false;", ["tests/test_cli.sh"], None),
    ("signal-last-wins", "src/main.c",
     "    atomic_compare_exchange_strong_explicit(&stop_signal, &none, sig, memory_order_relaxed,\n                                            memory_order_relaxed);",
     "    (void)none;\n    atomic_store_explicit(&stop_signal, sig, memory_order_relaxed);",
     ["tests/test_signals.sh"], None),
    ("resume-line-changes-unsaid", "src/output_resume.c",
     "    if (strcmp(algo, sc->algorithm) != 0)\n        snprintf(changed, sizeof changed, \", algorithm %s\", sc->algorithm);",
     "", ["tests/test_resume.sh"], None),
    ("run-signal-while-placing-ignored", "src/run.c", "    if (sig != NBEP_OK) {\n        nbep_scene_fini(&sc);",
     "    if (0) {\n        nbep_scene_fini(&sc);", ["tests/test_signals.sh"], None),
    # nbep check of a study: every run's scene loaded as nbep sweep will load it
    ("check-sweep-first-run-only", "src/sweep.c",
     "    for (size_t run = 0; st == NBEP_OK && run < p.n_runs; run++) {\n        if (run > 0 &&",
     "    for (size_t run = 0; st == NBEP_OK && run < 1; run++) {\n        if (run > 0 &&",
     ["test_sweep", "tests/test_sweep_cli.sh"], None),
    ("check-sweep-budget-ignored", "src/sweep.c", "        if (run > 0 && !(nbep_now() - t0 < budget_s)) {",
     "        if (0) {", ["test_sweep"], None),
    ("check-sweep-failures-pass", "src/sweep.c",
     "    return st != NBEP_OK ? st : rep->failed ? NBEP_EDECK : NBEP_OK;", "    return st;",
     ["test_sweep", "tests/test_sweep_cli.sh"], None),
    ("check-sweep-list-unbounded", "src/sweep.c",
     "        } else if (rep->failed++ < NBEP_SWEEP_CHECK_LISTED) {",
     "        } else if (rep->failed++ < 1000) {", ["tests/test_sweep_cli.sh"], None),
    ("check-sweep-output-last-run", "src/sweep.c",
     "            rep->output_bytes += nbep_output_bytes(", "            rep->output_bytes = nbep_output_bytes(",
     ["test_sweep", "tests/test_sweep_cli.sh"], None),
    ("check-sweep-never", "src/main.c",
     "    const bool study = sc.sweep_replicas > 1 || sc.sweep_n_axes > 0;",
     "    const bool study = sc.sweep_n_axes > 0 && sc.sweep_replicas > 100;",
     ["tests/test_sweep_cli.sh"], None),
    ("sweep-axis-group-allowed", "src/scene.c",
     "    if (strcmp(key, \"run\") == 0 || strcmp(key, \"output\") == 0)",
     "    if (0)", ["tests/test_sweep_cli.sh"], None),
    ("sweep-axis-column-allowed", "src/scene.c",
     "    if (strcmp(key, \"spheres\") == 0 || strcmp(key, \"planes\") == 0)",
     "    if (0)", ["tests/test_sweep_cli.sh"], None),
    ("sweep-seed-unbounded", "src/scene.c",
     "    if (sc->sweep_replicas > 1 && sc->seed > (uint64_t)INT64_MAX - (sc->sweep_replicas - 1))",
     "    if (0)", ["tests/test_sweep_cli.sh"], None),
    # an axis's path must name entries the deck has; a run's failure names the axis's line
    ("sweep-axis-index-appends", "src/scene_override.c", "            if (s->idx >= have) {",
     "            if (s->idx > have) {", ["test_sweep"], None),
    ("override-vector-element-unnamed", "src/scene_text.c",
     "        ov = config_setting_get_hook(config_setting_get_elem(s, (unsigned)k));",
     "        (void)0;", ["test_scene"], None),
    ("sweep-axis-line-of-set-value", "src/scene.c",
     "        (void)nbep__scene_origin(values, true, &axis->line);",
     "        (void)nbep__scene_origin(values, false, &axis->line);", ["test_sweep"], None),
    # each sweep axis value checked on its own when the deck is (check_axis_values): refused
    # up front, at the value's own line or by the --set that gave it, said once per problem,
    # and without placing spheres (a value that only placement refuses fails its run)
    ("sweep-values-unchecked", "src/scene.c",
     "    if (mode == LOAD_DECK && sc.sweep_n_axes && !L.c.oom)",
     "    if (0)", ["test_sweep", "tests/test_sweep_cli.sh"], None),
    ("sweep-value-line-of-axis", "src/scene.c",
     "                config_setting_get_elem(L->axes[a].values, (unsigned)v), false, &line);",
     "                L->axes[a].values, false, &line);", ["test_sweep"], None),
    ("sweep-value-set-unnamed", "src/scene.c",
     "            if (by)\n                nbep__strbuf_add(&label, \"%s: \", by);\n            else",
     "            if (0)\n                nbep__strbuf_add(&label, \"%s: \", by);\n            else",
     ["test_sweep", "tests/test_sweep_cli.sh"], None),
    ("sweep-value-deck-problem-repeated", "src/scene.c",
     "                if (!msg || diag_has(L->c.d, errors0, msg))",
     "                if (!msg)", ["test_sweep"], None),
    ("sweep-value-other-unnamed", "src/scene.c",
     "                if (strncmp(msg, label.p, n_label) == 0 && msg[n_label] == ':')",
     "                if (1)", ["test_sweep"], None),
    ("sweep-value-places", "src/scene.c",
     "    if (geometry_ok && check_counts(&L, &sc, entries, n_entries, n_all_planes, &total) &&\n        mode != LOAD_VALUE) {",
     "    if (geometry_ok && check_counts(&L, &sc, entries, n_entries, n_all_planes, &total)) {",
     ["test_sweep"], None),
    ("sweep-run-rechecks-values", "src/sweep.c", "                                     .sweep_run = true};",
     "                                     .sweep_run = false};", ["test_sweep"],
     "a sweep's run would check its axes' values again, which its plan checked from the same "
     "deck and command line: the same answers, only the cost of a parse of the deck per value "
     "per run"),
    # a region outside the box: refused along wall axes only, a lattice cut to wall axes only
    ("region-periodic-refused", "src/scene.c",
     "        if (!sc->periodic[k] && !(h[k] > bl[k] && l[k] < bh[k]))",
     "        if (!(h[k] > bl[k] && l[k] < bh[k]))", ["test_scene"], None),
    ("region-lattice-uncut", "src/scene.c", "                    lo[a] = fmax(lo[a], bl[a]);",
     "                    (void)0;", ["test_scene"], None),
    # --resume with another output file: found by the setting's origin, however typed
    ("resume-other-output-allowed", "src/scene.c",
     "        if (label)\n            sc->output_file_origin = dup_string(L, label);",
     "        (void)label;", ["tests/test_cli.sh"], None),
    ("sweep-axis-line-lost", "src/sweep.c",
     "        if ((oom = !label) == false && p.axes[k].line) /* deck:line:, as every deck error */",
     "        if ((oom = !label) == false && false) /* deck:line:, as every deck error */",
     ["test_sweep"], None),
    ("sweep-summary-in-study", "src/sweep.c",
     "        st = summary_not_in_study(&p, cli->summary, dd);",
     "        st = NBEP_OK;", ["tests/test_sweep_cli.sh"], None),
    ("sweep-wait-deaf", "src/sweep.c",
     "    if (w->st != NBEP_OK || (w->st = nbep_sim_stop_status(w->stop_signal)) == NBEP_OK)",
     "    if (1 || w->st != NBEP_OK || (w->st = nbep_sim_stop_status(w->stop_signal)) == NBEP_OK)",
     ["tests/test_sweep_mpi.sh"], None),
    ("setup-signal-unpolled", "src/algo_predictive.c",
     "if (setup && tid == 0 && nbep_sim_stop_status(setup->opt.stop_signal) != NBEP_OK)",
     "if (0 && setup && tid == 0 && nbep_sim_stop_status(setup->opt.stop_signal) != NBEP_OK)",
     ["tests/test_signals.sh"], None),
    ("setup-stop-runs-steps", "src/algo_predictive.c",
     "        if (!c->imported && atomic_load_explicit(&sim->stop, memory_order_relaxed)) {",
     "        if (0) {", ["tests/test_signals.sh"], None),
    ("run-output-is-deck-taken", "src/run.c",
     "    const char *over = nbep_output_same_file(output, deck)    ? output",
     "    const char *over = 0 ? output", ["tests/test_cli.sh"], None),
    ("resume-steps-before-last-taken", "src/output_resume.c",
     "sc->steps <= (uint64_t)res.last_step) {", "sc->steps <= (uint64_t)res.step) {",
     ["tests/test_resume.sh"], None),
    ("resume-stats-mismatch-taken", "src/output_resume.c",
     "    if (o->resume.stats != sc->out_stats) {", "    if (0) {", ["tests/test_resume.sh"], None),
    ("resume-summary-is-run-taken", "src/run.c", "    if (summary && output &&",
     "    if (0 && summary && output &&", ["tests/test_resume.sh"], None),
    ("resume-apply-velocity", "src/output_resume.c",
     "        memcpy(s->vel, r->vel, r->n * sizeof *s->vel);\n", "", ["tests/test_resume.sh"], None),
    ("resume-apply-image", "src/output_resume.c",
     "        memcpy(s->image, r->image, 3 * r->n * sizeof *s->image);\n", "",
     ["tests/test_resume.sh"], None),
    ("resume-first-frame-again", "src/sim.c", "nbep_status st = sim->resumed ? NBEP_OK : emit_frame(sim, 0);",
     "nbep_status st = emit_frame(sim, 0);", ["tests/test_resume.sh"], None),
    # ---- frame schedule, summary and counters ----
    ("frame-last-step", "src/sim.c", "    return step % sim->scene->output_every == 0 || step == sim->step_end;",
     "    return step % sim->scene->output_every == 0;", SIM + ["test_output"], None),
    ("summary-drift-sign", "src/sim.c", "? (sim->energy_final - sim->energy_initial) /",
     "? (sim->energy_initial - sim->energy_final) /", SIM + ["test_output"], None),
    ("summary-quiet-steps", "src/sim.c", "if (row.collisions == 0)\n        sim->quiet_steps++;",
     "if (row.collisions <= 1)\n        sim->quiet_steps++;", SIM + ["test_output"], None),
    ("counter-collisions", "src/sim.c", "row.collisions = c[NBEP_COUNTER_SPHERE_COLLISIONS] + c[NBEP_COUNTER_PLANE_COLLISIONS];",
     "row.collisions = c[NBEP_COUNTER_SPHERE_COLLISIONS];", SIM + ["test_output"], None),
    ("counter-predict-checks", "src/algo_predictive.c", "cnt->c[NBEP_COUNTER_CHECKS]++; /* the paper's check() */",
     "/* check() not counted */", SIM, None),
    # ---- the command line and the files a user names ----
    ("override-origin-ignored", "src/scene.c", "    if (origins && origins[k])\n        return strdup(origins[k]);",
     "    (void)origins;", ["test_scene", "tests/test_cli.sh"], None),
    ("run-file-format-unchecked", "src/output_hdf5.c", "    const int run = is_run(file, path, d);",
     "    const int run = 1;", ["test_output", "tests/test_cli.sh"], None),
    ("run-file-directory-passes", "src/output_hdf5.c", "    if (!err && !S_ISREG(sb.st_mode))",
     "    if (0)", ["tests/test_cli.sh"], None),
    ("resume-end-line-counts-from-0", "src/run.c", "    const uint64_t ran = from >= 0 && s->steps >= (uint64_t)from ? s->steps - (uint64_t)from",
     "    const uint64_t ran = 0 && s->steps >= (uint64_t)from ? s->steps - (uint64_t)from",
     ["tests/test_resume.sh"], None),
    ("real-text-17-digits", "src/summary.c", "    for (int digits = 1; digits <= 17; digits++) {",
     "    for (int digits = 17; digits <= 17; digits++) {", ["test_output"], None),
    ("real-text-exponent-kept", "src/summary.c", "    if (strpbrk(buf, \"eE\") && fabs(v) >= 1.0 && fabs(v) < 1e15 && v == floor(v))",
     "    if (0)", ["test_output"], None),
    # ---- energies beyond doubles, files being written, sweeps as job scripts use them ----
    ("step-overflow-written", "src/sim.c", "    if (!finite) {\n        if (sim->status == NBEP_OK) {",
     "    if (0) {\n        if (sim->status == NBEP_OK) {", ["test_extremes"], None),
    ("total-energy-unchecked", "src/sim.c", "    if (!isfinite(sim->energy_initial)) {",
     "    if (0) {", ["test_extremes"], None),
    ("info-open-once", "src/output_hdf5.c", "    for (int tries = 0; fapl >= 0 && tries < 20; tries++) {",
     "    for (int tries = 0; fapl >= 0 && tries < 1; tries++) {", ["tests/test_cli.sh"], None),
    ("info-cut-short-is-io", "src/output_hdf5.c",
     "        nbep__output_close_id(&fapl);\n        /* HDF5's signature, but no file it can open (cut short by a copy, or locked by the\n         * run that writes it): not a file this command can take, as a file of another kind */\n        return NBEP_EUSAGE;",
     "        nbep__output_close_id(&fapl);\n        return NBEP_EIO;", ["tests/test_cli.sh"], None),
    ("sweep-replicas-not-neutral", "src/sweep.c", "    if (len > 6 && strncmp(ov, \"sweep.\", 6) == 0)\n        return true;",
     "", ["tests/test_sweep_cli.sh"], None),
    ("sweep-summary-untried", "src/sweep.c", "(st = try_summary(cli->summary, dd)) != NBEP_OK)",
     "(st = NBEP_OK) != NBEP_OK)", ["tests/test_sweep_cli.sh"], None),
    ("sweep-stale-table-kept", "src/sweep.c", "        st = remove_tables(&p, dd);",
     "        st = NBEP_OK;", ["tests/test_sweep_cli.sh"], None),
    ("sweep-srun-unseen", "src/sweep.c", "    if (env_long(\"SLURM_PROCID\") > 0 ||\n        (getenv(\"SLURM_STEP_ID\") && env_long(\"SLURM_STEP_NUM_TASKS\") > 1))",
     "    if (0)", ["tests/test_sweep_cli.sh"], None),
    ("sweep-summary-dir-kept", "src/sweep.c", "        unmake_dir(p.dir, made);", "        (void)made;",
     ["tests/test_sweep_cli.sh"], None),
    ("sweep-farm-refused", "src/sweep.c", "    if (forced == 0) /* one study per process",
     "    if (0) /* one study per process", ["tests/test_sweep_cli.sh"], None),
    ("sweep-peer-stop-unseen", "src/sweep.c", "    return q->received ? q->seen : NBEP_OK;",
     "    return NBEP_OK;", ["tests/test_sweep_mpi.sh"], None),
    ("sweep-wait-spins", "src/sweep.c", "        nanosleep(&nap, NULL);\n",
     "        (void)nap;\n", ["tests/test_sweep_mpi.sh"], None),
    ("peak-rss-lifetime", "src/run.c", "    nbep_peak_rss_reset(); /* peak_rss_bytes",
     "    (void)0; /* peak_rss_bytes", ["tests/test_sweep_cli.sh"], None),
    # ---- the user interface: deck ranges, overrides, suggestions, the command line, the
    # sidecar, nbep info, the summary's reader, the sweep's table (README "Mutation testing") ----
    ("ui-threads-max-refused", "src/scene.c", "        if (v > NBEP_THREADS_MAX)\n            ERR(L, at, \"run.threads",
     "        if (v >= NBEP_THREADS_MAX)\n            ERR(L, at, \"run.threads", ["test_scene", "tests/test_cli.sh"], None),
    ("ui-sweep-seed-bound-off-by-one", "src/scene.c",
     "sc->seed > (uint64_t)INT64_MAX - (sc->sweep_replicas - 1))",
     "sc->seed > (uint64_t)INT64_MAX - sc->sweep_replicas)", ["test_scene", "tests/test_sweep_cli.sh"], None),
    ("ui-sweep-runs-max-off-by-one", "src/scene.c", "    if (runs > NBEP_SWEEP_RUNS_MAX)\n        ERR(",
     "    if (runs >= NBEP_SWEEP_RUNS_MAX)\n        ERR(", ["test_scene", "tests/test_sweep_cli.sh"], None),
    # a run.steps axis value of 0 is taken: since 2026-11-30 checked as run.steps is
    ("ui-sweep-steps-axis-zero-refused", "src/scene.c", "if (((f & F_GE0) && v < 0) ||",
     "if (((f & F_GE0) && v <= 0) ||", ["test_scene", "test_sweep", "tests/test_sweep_cli.sh"], None),
    ("ui-override-entry-plural", "src/scene_override.c", "len == 1 ? \"y\" : \"ies\"",
     "len <= 1 ? \"y\" : \"ies\"", ["test_scene", "tests/test_cli.sh"], None),
    ("ui-override-array-aggregate-unchecked", "src/scene_override.c",
     "    if (config_setting_is_array(node) && config_setting_is_aggregate(v)) {",
     "    if (0 && config_setting_is_aggregate(v)) {", ["test_scene", "tests/test_cli.sh"], None),
    ("ui-override-path-untrimmed", "src/scene_override.c", "char *path = trimmed(ov, (size_t)(eq - ov)),",
     "char *path = strndup(ov, (size_t)(eq - ov)),", ["test_scene", "tests/test_cli.sh"], None),
    ("ui-override-made-groups-unlabelled", "src/scene_override.c",
     "        if (!config_setting_get_hook(child) && config_setting_source_line(child) == 0)\n            config_setting_set_hook(child, (void *)label);\n",
     "", ["test_scene"], None),
    ("ui-suggest-element-path", "src/scene_schema.c",
     "strcmp(leaf_of(schema[id].path), seg) == 0 && !strstr(schema[id].path, \"[]\")",
     "strcmp(leaf_of(schema[id].path), seg) == 0", ["test_scene"], None),
    ("ui-suggest-half-the-letters", "src/scene_schema.c", "size_t limit = seg_len / 3 > 1 ? seg_len / 3 : 1,",
     "size_t limit = seg_len / 2 > 1 ? seg_len / 2 : 1,", ["test_scene"], None),
    ("ui-widen-int64-min-refused", "src/scene_text.c",
     "const uint64_t max64 = neg ? (uint64_t)INT64_MAX + 1 : (uint64_t)INT64_MAX;",
     "const uint64_t max64 = (uint64_t)INT64_MAX;", ["test_scene", "tests/test_cli.sh"], None),
    ("ui-cli-output-unquoted", "src/cli.c", "{\"-o\", \"--output\", \"output.file\", true}",
     "{\"-o\", \"--output\", \"output.file\", false}", ["tests/test_cli.sh"], None),
    ("ui-cli-info-takes-resume", "src/cli.c", "(cli->n_overrides || cli->summary || cli->resume))",
     "(cli->n_overrides || cli->summary))", ["tests/test_cli.sh"], None),
    ("ui-xdmf-time-6-digits", "src/output_xdmf.c", "<Time Value=\\\"%.17g\\\"/>",
     "<Time Value=\\\"%g\\\"/>", ["test_output_xdmf", "test_output"], None),
    ("ui-xdmf-slab-count-frames", "src/output_xdmf.c",
     "Dimensions=\\\"1 %zu 3\\\" Type=\\\"HyperSlab\\\">\\n\",\n        indent, n);",
     "Dimensions=\\\"1 %zu 3\\\" Type=\\\"HyperSlab\\\">\\n\",\n        indent, n_frames);",
     ["test_output_xdmf", "test_output"], None),
    ("ui-xdmf-scalar-dims-off-by-one", "src/output_xdmf.c", "        n, h5, name);", "        n + 1, h5, name);",
     ["test_output_xdmf", "test_output"], None),
    # ---- sizes as printed (nbep_format_bytes) and what nbep check counts of a run's output ----
    ("size-binary-units", "src/util.c", "        bytes /= 1000.0;", "        bytes /= 1024.0;",
     ["test_util"], None),
    ("size-1000-kept", "src/util.c", "while (u < last && fabs(bytes) >= 999.5)",
     "while (u < last && fabs(bytes) >= 1000.0)", ["test_util"], None),
    ("size-two-figures", "src/util.c", "snprintf(buf, NBEP_BYTES_TEXT_MAX, \"%.3g %s\", bytes, unit[u]);",
     "snprintf(buf, NBEP_BYTES_TEXT_MAX, \"%.2g %s\", bytes, unit[u]);",
     ["test_util", "tests/test_cli.sh"], None),
    ("size-xdmf-head-uncounted", "src/output_xdmf.c",
     "    xml_head(&o, h5, n_spheres, (size_t)n_frames);\n", "", ["test_output_xdmf"], None),
    ("size-xdmf-last-step-on-grid", "src/output_xdmf.c",
     "(int64_t)(k + 1 < n_frames ? k * every : steps);", "(int64_t)(k * every);",
     ["test_output_xdmf"], None),
    ("size-xdmf-first-frames-sampled", "src/output_xdmf.c",
     "(uint64_t)((double)i * (double)(n_frames - 1) /", "(uint64_t)((double)i * (double)(sampled - 1) /",
     ["test_output_xdmf"], None),
    ("size-xdmf-velocity-always", "src/output.c",
     "return nbep_xdmf_bytes(path, sc->state.n, sc->steps, sc->output_every, sc->dt,\n                           sc->out_velocity);",
     "return nbep_xdmf_bytes(path, sc->state.n, sc->steps, sc->output_every, sc->dt,\n                           true);",
     ["tests/test_cli.sh"], None),
    ("size-xdmf-without-positions", "src/output.c", "    if (!sc->out_position)\n        return 0.0;\n    return nbep_xdmf_bytes(",
     "    return nbep_xdmf_bytes(", ["tests/test_cli.sh"], None),
    ("size-check-sidecar-left-out", "src/check.c",
     "f->output_bytes = nbep_output_bytes(sc, nbep_sim_keeps_events(sc)) + f->sidecar_bytes;",
     "f->output_bytes = nbep_output_bytes(sc, nbep_sim_keeps_events(sc));",
     ["tests/test_cli.sh"], None),
    ("size-sweep-sidecar-deck-name", "src/sweep.c",
     "nbep_output_sidecar_bytes(&rs, path ? path : rs.output_file);",
     "nbep_output_sidecar_bytes(&rs, rs.output_file);", ["test_sweep"], None),
    ("size-sweep-tables-left-out", "src/sweep.c",
     "nbep_format_bytes(r->output_bytes + r->tables_bytes, size),",
     "nbep_format_bytes(r->output_bytes, size),", ["test_sweep", "tests/test_sweep_cli.sh"], None),
    ("size-sweep-csv-left-out", "src/sweep.c", "    return csv + runs * csv_row + h5;",
     "    return h5;", ["test_sweep"], None),
    ("size-sweep-h5-records-left-out", "src/sweep.c",
     "runs * (8.0 * numbers + 16.0 * texts) + fmax(heap, TABLE_H5_HEAP_COLLECTION);",
     "fmax(heap, TABLE_H5_HEAP_COLLECTION);", ["test_sweep"], None),
    # ---- a sweep's pace: the runs that ran to their end, per minute ----
    ("pace-every-run", "src/sweep.c",
     "s.ended += (x->outcome == NBEP_SWEEP_OK && !x->reused) || x->outcome == NBEP_SWEEP_FAILED;",
     "s.ended += 1;", ["tests/test_sweep_cli.sh"], None),
    ("pace-reused-counted", "src/sweep.c",
     "s.ended += (x->outcome == NBEP_SWEEP_OK && !x->reused) || x->outcome == NBEP_SWEEP_FAILED;",
     "s.ended += x->outcome == NBEP_SWEEP_OK || x->outcome == NBEP_SWEEP_FAILED;",
     ["tests/test_sweep_cli.sh"], None),
    ("pace-interrupted-counted", "src/sweep.c",
     "s.ended += (x->outcome == NBEP_SWEEP_OK && !x->reused) || x->outcome == NBEP_SWEEP_FAILED;",
     "s.ended += (x->outcome == NBEP_SWEEP_OK && !x->reused) || x->outcome == NBEP_SWEEP_FAILED ||\n"
     "                   x->outcome == NBEP_SWEEP_INTERRUPTED;",
     ["tests/test_sweep_cli.sh"], None),
    ("pace-failed-uncounted", "src/sweep.c",
     "s.ended += (x->outcome == NBEP_SWEEP_OK && !x->reused) || x->outcome == NBEP_SWEEP_FAILED;",
     "s.ended += x->outcome == NBEP_SWEEP_OK && !x->reused;", ["tests/test_sweep_cli.sh"], None),
    ("pace-json-every-run", "src/sweep.c", "        runs_per_minute(s, wall), \"sim_seconds\"",
     "        wall > 0.0 ? 60.0 * n / wall : 0.0, \"sim_seconds\"",
     ["tests/test_sweep_cli.sh"], None),
    ("ui-info-periodic-y-from-x", "src/output_info.c", "r.periodic[1] ? \"y\" : \"\"",
     "r.periodic[0] ? \"y\" : \"\"", ["test_output", "tests/test_resume.sh"], None),
    ("ui-output-periodic-attr-y-from-x", "src/output.c", "sc->has_box && sc->periodic[1],",
     "sc->has_box && sc->periodic[0],", ["test_output", "tests/test_resume.sh", "test_periodic"], None),
    ("ui-run-end-line-drift-overlap-swapped", "src/run.c", "s->energy_rel_drift, s->max_overlap_rel, file);",
     "s->max_overlap_rel, s->energy_rel_drift, file);", ["tests/test_cli.sh", "tests/test_resume.sh"], None),
    ("ui-summary-negative-int-read", "src/summary.c",
     "if (!json_is_integer(v) || json_integer_value(v) < 0 || json_integer_value(v) > INT_MAX)",
     "if (!json_is_integer(v) || json_integer_value(v) > INT_MAX)", ["test_summary", "test_sweep"], None),
    ("ui-summary-duplicate-keys-read", "src/summary.c", "json_loads(json, JSON_REJECT_DUPLICATES, NULL)",
     "json_loads(json, 0, NULL)", ["test_summary", "test_sweep"], None),
    ("ui-sweep-table-missing-real-zero", "src/output_sweep.c", "v->r = missing ? NAN : c->r[row];",
     "v->r = missing ? 0.0 : c->r[row];", ["test_sweep", "tests/test_sweep_cli.sh"], None),
    # ---- the deck's window of magnitudes (scene.h NBEP_DECK_SCALE_MIN, _MAX) ----
    ("ui-scale-min-edge-refused", "src/scene.c", "(magnitude >= NBEP_DECK_SCALE_MIN &&",
     "(magnitude > NBEP_DECK_SCALE_MIN &&", ["tests/test_cli.sh"], None),
    ("ui-scale-no-max", "src/scene.c", "magnitude <= NBEP_DECK_SCALE_MAX);",
     "magnitude <= INFINITY);", ["tests/test_cli.sh"], None),
    ("ui-scale-zero-refused", "src/scene.c", "    return magnitude == 0.0 ||\n",
     "    return 0 ||\n", ["tests/test_cli.sh"], None),
    ("ui-scale-vector-norm-underflows", "src/scene.c",
     "    return m > 0.0 ? m * nbep_vec3_norm(u) : 0.0;",
     "    return m > 0.0 ? nbep_vec3_norm(v) : 0.0;", ["tests/test_cli.sh"], None),
    ("ui-scale-box-sides-unchecked", "src/scene.c", "        if (!in_scale(h[k] - l[k]))",
     "        if (0 && !in_scale(h[k] - l[k]))", ["tests/test_cli.sh"], None),
    ("ui-span-edge-refused", "src/scene.c", "    if (m > NBEP_DECK_SPAN_MAX * rmin)",
     "    if (m >= NBEP_DECK_SPAN_MAX * rmin)", ["test_scene"], None),
    ("ui-span-planes-unchecked", "src/scene.c", "        if (planes[k].point_at) {",
     "        if (0 && planes[k].point_at) {", ["test_scene"], None),
    ("ui-span-regions-unchecked", "src/scene.c", "        } else if (region) {",
     "        } else if (0 && region) {", ["test_scene"], None),
    ("ui-span-largest-radius", "src/scene.c", "            rmin = fmin(rmin, e[k].radius);",
     "            rmin = rmin < INFINITY ? fmax(rmin, e[k].radius) : e[k].radius;", ["test_scene"], None),
    ("ui-by-largest-times-inverse", "src/scene.c",
     "return nbep_vec3_make(v.x / *m, v.y / *m, v.z / *m);", "return nbep_vec3_scale(v, 1.0 / *m);",
     ["test_scene"], None),
    # ---- the order deck errors are listed in: the command line's options in the order given,
    # then the deck's lines from the top, then messages naming neither; stable within a rank ----
    ("order-load-unsorted", "src/scene.c", "    nbep_diag_sort(d, errors0);\n",
     "", ["test_scene", "tests/test_cli.sh"], None),
    ("order-sort-in-place-unstable", "src/status.c",
     "        for (; j > first && d->rank[j - 1] > r; j--) {",
     "        for (; j > first && d->rank[j - 1] >= r; j--) {", ["test_status"], None),
    ("order-unranked-first", "include/nbep/status.h", "#define NBEP_DIAG_UNRANKED UINT64_MAX",
     "#define NBEP_DIAG_UNRANKED 0", ["test_status", "test_scene"], None),
    ("order-options-after-deck", "src/scene_text.c", "            k++;\n        return k;",
     "            k++;\n        return NBEP_DIAG_UNRANKED - 1;", ["test_scene", "tests/test_cli.sh"],
     None),
    ("order-options-as-found", "src/scene_text.c", "            k++;\n        return k;",
     "            k++;\n        return 0;", ["test_scene", "tests/test_cli.sh"], None),
    ("order-override-error-unranked", "src/scene_override.c",
     "nbep_diag_add_ranked(c->d, nbep__scene_rank(c, label, 0), file, line,",
     "nbep_diag_add_ranked(c->d, NBEP_DIAG_UNRANKED, file, line,", ["test_scene"], None),
    ("order-override-widen-unranked", "src/scene_text.c",
     "nbep_diag_add_ranked(c->d, nbep__scene_rank(c, label, 0), __FILE__,\n                                         __LINE__, \"%s: integer",
     "nbep_diag_add_ranked(c->d, NBEP_DIAG_UNRANKED, __FILE__,\n                                         __LINE__, \"%s: integer", ["test_scene"], None),
    ("order-syntax-error-unranked", "src/scene.c",
     "nbep_diag_add_ranked(d, nbep__scene_rank(&L.c, NULL, at > 0 ? (uint64_t)at : 0),",
     "nbep_diag_add_ranked(d, NBEP_DIAG_UNRANKED + 0 * (at > 0 ? (uint64_t)at : 0),",
     ["test_scene"], None),
    ("order-overlaps-first-found", "src/scene_place.c",
     "    else if (at.rank < o->kept[o->last].at.rank) /* found later: before the last only by rank */",
     "    else if (0) /* found later: before the last only by rank */", ["test_scene"], None),
    ("order-overlaps-last-not-latest", "src/scene_place.c",
     "(o->kept[j].at.rank == o->kept[o->last].at.rank &&\n             o->kept[j].seq > o->kept[o->last].seq)",
     "(o->kept[j].at.rank == o->kept[o->last].at.rank &&\n             o->kept[j].seq < o->kept[o->last].seq)",
     ["test_scene"], None),
    ("order-overlaps-count-unranked", "src/scene_place.c",
     "        nbep_diag_add_ranked(c->d, last_rank, __FILE__, __LINE__,",
     "        nbep_diag_add_ranked(c->d, NBEP_DIAG_UNRANKED, __FILE__, __LINE__,", ["test_scene"],
     None),
    ("order-overlaps-count-at-last-found", "src/scene_place.c",
     "        last_rank = o.kept[k].at.rank > last_rank ? o.kept[k].at.rank : last_rank;",
     "        last_rank = o.kept[k].at.rank;", ["test_scene"], None),
    # ---- what a deck error is blamed on: the --set (or sweep axis) that caused it, not a deck
    # line the user did not touch ----
    # an overlap: any member of the entries that places its spheres, the first typed
    ("blame-overlap-position-only", "src/scene_place.c",
     "        blame_first(c, b, m);",
     "        blame_first(c, b, strcmp(placing[k][0], \"position\") == 0 ? m : NULL);",
     ["test_scene", "test_sweep"], None),
    ("blame-overlap-first-member-found", "src/scene_place.c",
     "    if (rank < b->rank)\n        *b = (blame){ov, 0, rank};",
     "    if (ov && !b->label)\n        *b = (blame){ov, 0, rank};", ["test_scene"], None),
    # the override that made a setting: one of an array's elements too
    ("blame-set-by-elements-unasked", "src/scene_text.c",
     "nbep__scene_origin(s, config_setting_is_array(s), &line)", "nbep__scene_origin(s, false, &line)",
     ["test_scene"], None),
    ("blame-overlap-region-corners-unasked", "src/scene_place.c",
     "{\"region\", \"min\"}, {\"region\", \"max\"}};",
     "{\"region\", NULL}, {\"region\", NULL}};", ["test_scene"], None),
    ("blame-overlap-later-sphere-first", "src/scene_place.c",
     "    if (bb.label && bb.rank < at.rank) /* a deck line's rank is past every option's */",
     "    if (bb.label && !at.label) /* a deck line's rank is past every option's */",
     ["test_scene"], None),
    # a region the box was moved off: the --set of the box's corner, where typed first
    ("blame-region-box-unasked", "src/scene.c",
     "        if (r_corner < r_at)\n            at = corner;", "        if (0)\n            at = corner;",
     ["test_scene"], None),
    ("blame-region-box-over-first", "src/scene.c",
     "        if (r_corner < r_at)\n            at = corner;",
     "        if (r_corner < NBEP_DIAG_UNRANKED)\n            at = corner;", ["test_scene"], None),
    # libconfig's @include, refused at its line and never read
    ("include-accepted", "src/scene_text.c", "        } else if (ch == '@' && is_include(text, i)) {",
     "        } else if (0) {", ["test_scene"], None),
    ("include-accepted-in-a-set", "src/scene_text.c", "        } else if (ch == '@' && is_include(text, i)) {",
     "        } else if (ch == '@' && !label && is_include(text, i)) {", ["test_scene"], None),
    ("include-parsed-anyway", "src/scene.c",
     "    if (n_include) /* refused, each at its line: libconfig must not read the file */\n        goto finish;",
     "", ["test_scene"], None),
    # a group that cannot be placed: the --set (or axis) of what places it, typed first
    ("blame-fill-count-line", "src/scene_place.c",
     "    const blame b = fill_blame(c, s, e, plane_at, in_way);\n    if (b.label)",
     "    const blame b = fill_blame(c, s, e, plane_at, in_way);\n    if (0)", ["test_scene", "test_sweep"], None),
    # ... of what placed the spheres in its way: the entries whose spheres its tries met
    ("blame-fill-in-way-ignored", "src/scene_place.c",
     "    blame b = in_way;", "    blame b = {NULL, 0, NBEP_DIAG_UNRANKED};", ["test_scene"], None),
    ("blame-fill-in-way-every-entry", "src/scene_place.c",
     "        if (met[j])\n            members_blame(c, b, g->e[j].setting);",
     "        if (1)\n            members_blame(c, b, g->e[j].setting);", ["test_scene"], None),
    ("blame-fill-in-way-past-planes", "src/scene_place.c",
     "        if (clear_of_planes(g->s, pr->p, pr->r))\n            (void)probe_near(g, pr, reach);",
     "        (void)probe_near(g, pr, reach);", ["test_scene"], None),
    # ... and of what bounds its room: the box (no region), the planes at or inside its region
    ("blame-fill-box-unasked", "src/scene_place.c",
     "    if (!config_setting_get_member(e->setting, \"region\")) {\n        const config_setting_t *box = box_of(e->setting);",
     "    if (0) {\n        const config_setting_t *box = box_of(e->setting);", ["test_scene"], None),
    ("blame-fill-planes-unasked", "src/scene_place.c",
     "    for (size_t p = 0; plane_at && p < s->n_planes; p++) {\n        const config_setting_t *at = plane_at[2 * p];",
     "    for (size_t p = 0; plane_at && p < 0; p++) {\n        const config_setting_t *at = plane_at[2 * p];",
     ["test_scene"], None),
    ("blame-fill-lattice-sees-planes", "src/scene_place.c",
     "        if ((!wall && e->place == NBEP__PLACE_LATTICE) || !plane_reaches(s, p, e->lo, e->hi))",
     "        if (!plane_reaches(s, p, e->lo, e->hi))", ["test_scene"], None),
    ("blame-fill-planes-anywhere", "src/scene_place.c",
     "    return !(least > s->plane_offset[p]);", "    return true;", ["test_scene"], None),
    # an overlap with a wall or plane: the --set that moved it, where typed first
    ("blame-wall-ignored", "src/scene_place.c",
     "                report(&o, i, walls[p], name, by);",
     "                report(&o, i, (blame){NULL, 0, NBEP_DIAG_UNRANKED}, name, by);",
     ["test_scene"], None),
    # an overlap across a periodic face: the --set of the box that moved or made the faces
    ("blame-face-ignored", "src/scene_place.c",
     "                blame_first(o->c, &bb, v ? config_setting_get_elem(v, (unsigned)axis) : NULL);",
     "", ["test_scene"], None),
    ("blame-face-every-axis", "src/scene_place.c",
     "            if (shift[axis] == 0.0)\n                continue;\n", "", ["test_scene"], None),
    ("blame-face-min-unasked", "src/scene_place.c",
     "face_corners[3] = {\"min\", \"max\", \"periodic\"};",
     "face_corners[3] = {\"max\", \"max\", \"periodic\"};", ["test_scene"], None),
    ("blame-face-periodic-unasked", "src/scene_place.c",
     "face_corners[3] = {\"min\", \"max\", \"periodic\"};",
     "face_corners[3] = {\"min\", \"max\", \"max\"};", ["test_scene"], None),
    ("blame-wall-min-max-swapped", "src/scene.c",
     "        at[k++] = lo ? config_setting_get_elem(lo, (unsigned)axis) : NULL;\n"
     "        at[k++] = walled;\n"
     "        at[k++] = hi ? config_setting_get_elem(hi, (unsigned)axis) : NULL;",
     "        at[k++] = hi ? config_setting_get_elem(hi, (unsigned)axis) : NULL;\n"
     "        at[k++] = walled;\n"
     "        at[k++] = lo ? config_setting_get_elem(lo, (unsigned)axis) : NULL;",
     ["test_scene"], None),
    ("blame-wall-periodic-counted", "src/scene.c",
     "    for (int axis = 0; sc->has_box && axis < 3; axis++) {\n        if (sc->periodic[axis])\n            continue;\n",
     "    for (int axis = 0; sc->has_box && axis < 3; axis++) {\n", ["test_scene"], None),
    # a --set of box.periodic that walls an axis made its walls
    ("blame-wall-periodic-unasked", "src/scene_place.c",
     "        blame_first(c, b, at[1]);", "", ["test_scene"], None),
    ("blame-plane-normal-unasked", "src/scene_place.c",
     "        blame_first(c, b, config_setting_get_member(at[0], \"normal\"));", "", ["test_scene"],
     None),
    ("blame-plane-point-unasked", "src/scene_place.c",
     "        blame_first(c, b, config_setting_get_member(at[0], \"point\"));", "", ["test_scene"],
     None),
    ("blame-overlap-entry-line", "src/scene_place.c",
     "    (void)nbep__scene_origin(pos ? pos : g, false, &b.line);",
     "    (void)nbep__scene_origin(g, false, &b.line);", ["test_scene"], None),
    # a check of two corners: the one a --set gave, the first typed; else max's deck line
    ("blame-corners-always-max", "src/scene.c", "    return r_min < r_max ? min : max;",
     "    return max;", ["test_scene", "tests/test_cli.sh"], None),
    ("blame-corners-min-over-first-typed", "src/scene.c", "    return r_min < r_max ? min : max;",
     "    return r_min < NBEP_DIAG_UNRANKED ? min : max;", ["test_scene"], None),
    ("blame-corners-deck-min", "src/scene.c", "    return r_min < r_max ? min : max;",
     "    return r_min < r_max || r_max == NBEP_DIAG_UNRANKED ? min : max;", ["test_scene"], None),
    # ---- how a run ended: the summary's status and steps_requested, the sweep's reuse of them,
    # nbep info's line (README "JSON summary") ----
    ("status-sigterm-as-interrupted", "src/summary.c",
     "    case NBEP_ESIGTERM:\n        return NBEP_SUMMARY_TERMINATED;",
     "    case NBEP_ESIGTERM:\n        return NBEP_SUMMARY_INTERRUPTED;",
     ["test_summary", "tests/test_signals.sh"], None),
    ("status-failure-as-completed", "src/summary.c",
     "    default:\n        return NBEP_SUMMARY_FAILED;", "    default:\n        return NBEP_SUMMARY_COMPLETED;",
     ["test_summary", "tests/test_cli.sh"], None),
    ("status-file-unset", "src/run.c",
     "     * run's status, and the --summary file's, failed (below) */\n    res->summary.status = nbep_summary_status_of(st);\n",
     "     * run's status, and the --summary file's, failed (below) */\n",
     ["tests/test_signals.sh"], None),
    ("status-unknown-written-empty", "src/summary.c", "    return text ? json_string(text) : json_null();",
     "    return json_string(text ? text : \"\");", ["test_summary"], None),
    ("status-missing-refused", "src/summary.c",
     "    if (!v || json_is_null(v)) {\n        *out = NBEP_SUMMARY_UNKNOWN;",
     "    if (json_is_null(v)) {\n        *out = NBEP_SUMMARY_UNKNOWN;", ["test_summary", "test_sweep"], None),
    ("status-any-text-unknown", "src/summary.c",
     "    return false; /* a number, or a text that is no status",
     "    *out = NBEP_SUMMARY_UNKNOWN;\n    return true; /* a number, or a text that is no status",
     ["test_summary"], None),
    ("steps-requested-missing-refused", "src/summary.c",
     "    if (!v || json_is_null(v)) {\n        *out = (nbep_summary_count){.known = false};",
     "    if (json_is_null(v)) {\n        *out = (nbep_summary_count){.known = false};",
     ["test_summary", "test_sweep"], None),
    ("steps-requested-is-steps-done", "src/sim.c", "(nbep_summary_count){true, sim->step_end}; /* run.steps */",
     "(nbep_summary_count){true, sim->steps_done}; /* run.steps */",
     ["tests/test_signals.sh", "tests/test_cli.sh"], None),
    ("sweep-reuse-any-status", "src/sweep.c",
     "    return s->steps == steps &&\n           (s->status == NBEP_SUMMARY_COMPLETED || s->status == NBEP_SUMMARY_UNKNOWN);",
     "    return s->steps == steps;", ["test_sweep"], None),
    ("sweep-reuse-older-refused", "src/sweep.c",
     "(s->status == NBEP_SUMMARY_COMPLETED || s->status == NBEP_SUMMARY_UNKNOWN);",
     "(s->status == NBEP_SUMMARY_COMPLETED);", ["test_sweep"], None),
    ("sweep-table-unknown-requested-zero", "src/sweep.c",
     "            null_col[r] = !results[r].has_summary || !results[r].summary.field.known;        \\\n        INT_COL(",
     "            null_col[r] = !results[r].has_summary;                                       \\\n        INT_COL(",
     ["test_sweep"], None),
    ("info-status-signal-unnamed", "src/output_info.c", "s.status == NBEP_SUMMARY_TERMINATED ? \" (SIGTERM)\"",
     "s.status == NBEP_SUMMARY_TERMINATED ? \"\"", ["test_output", "tests/test_signals.sh"], None),
    ("info-status-requested-from-root", "src/output_info.c",
     "s.steps_requested.known ? s.steps_requested.value : r->steps);", "r->steps);",
     ["test_output"], None),
    # ---- the warning of an exact run that ended in overlaps ----
    ("overlap-warn-threshold-inverted", "src/run.c", "if (exact && s->max_overlap_rel > EXACT_OVERLAP_WARN)",
     "if (exact && s->max_overlap_rel < EXACT_OVERLAP_WARN)", ["tests/test_resume.sh"], None),
    ("overlap-warn-naive-too", "src/run.c",
     "const bool exact = strcmp(sc->algorithm, \"predictive\") == 0 && !sc->order_step;",
     "const bool exact = !sc->order_step;", ["tests/test_resume.sh"], None),
    ("overlap-warn-never", "src/run.c", "        warn_overlap(&sc, &res->summary, file);\n", "",
     ["tests/test_resume.sh"], None),
    # ---- nbep check: where the run's file goes ----
    ("check-output-dir-unchecked", "src/main.c",
     "    if (st == NBEP_OK && !study)\n        st = nbep_run_check_output_dir(sc.output_file, d);\n", "",
     ["tests/test_cli.sh"], None),
    ("check-output-dir-directory-passes", "src/run.c",
     "    if (stat(output, &sb) == 0 && S_ISDIR(sb.st_mode))\n        err = EISDIR;",
     "    if (0)\n        err = EISDIR;", ["tests/test_cli.sh"], None),
    ("check-output-dir-file-on-way-passes", "src/run.c",
     "    else if (!S_ISDIR(sb.st_mode))\n        err = ENOTDIR;", "", ["tests/test_cli.sh"], None),
    ("check-sweep-dir-unchecked", "src/main.c",
     "    if (st == NBEP_OK && study) /* where its runs go: nbep sweep makes the folder */\n        st = nbep_sweep_check_dir(rep.dir, d);\n",
     "", ["tests/test_sweep_cli.sh"], None),
    ("check-sweep-dir-made", "src/sweep.c", "const int r = look ? mkdir_looked(p, *made > 0) : mkdir(p, 0777);",
     "const int r = mkdir(p, 0777);", ["tests/test_sweep_cli.sh"], None),
    ("check-sweep-dir-below-looked", "src/sweep.c", "    if (below)\n        return 0;\n    struct stat sb;",
     "    struct stat sb;", ["tests/test_sweep_cli.sh"], None),
    ("signal-handler-nests", "src/main.c",
     "    sigaddset(&sa.sa_mask, SIGINT);\n    sigaddset(&sa.sa_mask, SIGTERM);\n", "",
     ["tests/test_signals.sh"], None),
    # ---- nbep check --summary: the JSON report ----
    ("check-json-beside-human", "src/main.c",
     "FILE *human = cli->summary && cli->quiet ? NULL : json_out ? stderr : stdout;",
     "FILE *human = cli->summary && cli->quiet ? NULL : stdout;", ["tests/test_cli.sh"], None),
    ("check-json-quiet-ignored", "src/main.c",
     "FILE *human = cli->summary && cli->quiet ? NULL : json_out ? stderr : stdout;",
     "FILE *human = json_out ? stderr : stdout;", ["tests/test_cli.sh"], None),
    ("check-json-study-max-is-output", "src/check.c", "\"memory_bytes_max\", bytes(r->memory_max)",
     "\"memory_bytes_max\", bytes(r->output_bytes)", ["tests/test_sweep_cli.sh"], None),
    ("check-json-bytes-megabytes", "src/check.c", "json_integer((json_int_t)llround(v))",
     "json_integer((json_int_t)llround(v / 1e6))", ["tests/test_cli.sh"], None),
    ("check-json-paths-unchecked", "src/main.c",
     "st = nbep_run_check_paths(cli->path, sc.output_file, cli->summary, d);",
     "st = nbep_run_check_paths(cli->path, sc.output_file, NULL, d);", ["tests/test_cli.sh"], None),
    # a --summary naming a directory: refused before any step (it ran every step, then exit 1)
    ("summary-dir-accepted", "src/run.c",
     "    if (stat(where, &sb) == 0 && S_ISDIR(sb.st_mode))\n        NBEP_FAIL(d, nbep_status_of_open(EISDIR)",
     "    if (0)\n        NBEP_FAIL(d, nbep_status_of_open(EISDIR)", ["tests/test_cli.sh"], None),
    # a signal to nbep check: no report, exit 130/143; a study's loading stops at the next run
    ("check-signal-ignored", "src/main.c",
     "    const nbep_status sig = nbep_sim_stop_status(&stop_signal);\n    if (sig != NBEP_OK) {\n        nbep_scene_fini(&sc);",
     "    const nbep_status sig = NBEP_OK;\n    if (sig != NBEP_OK) {\n        nbep_scene_fini(&sc);",
     ["tests/test_signals.sh"], None),
    ("check-study-signal-unlooked", "src/sweep.c",
     "        if (nbep_sim_stop_status(stop) != NBEP_OK)\n            break; /* Ctrl-C",
     "        if (0)\n            break; /* Ctrl-C", ["tests/test_signals.sh"], None),
    # no pace yet: "ETA -", not "ETA 0 s" with every step to go
    ("progress-eta-zero-without-rate", "src/sim.c",
     "\"%s\", at >= (double)sim->step_end ? \"0 s\" : \"-\");", "\"%s\", \"0 s\");",
     ["tests/test_signals.sh"], None),
]


def run(cmd, cwd, timeout=None, log=None):
    try:
        r = subprocess.run(cmd, cwd=cwd, timeout=timeout, stdout=log or subprocess.DEVNULL,
                           stderr=subprocess.STDOUT)
        return r.returncode
    except subprocess.TimeoutExpired:
        return "timeout"


def test_path(name):
    return name if name.endswith(".sh") else "build/tests/" + name


def copy_tree(dst):
    """The tree as git sees it into dst: tracked files and untracked ones git does not ignore,
    as they are in the working tree (not build outputs, nor scratch folders a developer keeps
    in ignored paths); without git, everything but .git, build and bin."""
    listed = subprocess.run(["git", "ls-files", "-z", "-c", "-o", "--exclude-standard"],
                            cwd=ROOT, capture_output=True)
    if listed.returncode != 0:
        shutil.copytree(ROOT, dst, dirs_exist_ok=True,
                        ignore=shutil.ignore_patterns(".git", "build", "bin"))
        return
    for rel in sorted(set(listed.stdout.decode().split("\0")) - {""}):
        src = os.path.join(ROOT, rel)
        if not os.path.lexists(src):  # tracked, deleted in the working tree
            continue
        os.makedirs(os.path.dirname(os.path.join(dst, rel)), exist_ok=True)
        shutil.copy2(src, os.path.join(dst, rel), follow_symlinks=False)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--jobs", type=int, default=2, help="make -j per build (default 2)")
    ap.add_argument("--timeout", type=int, default=120, help="seconds per test program")
    ap.add_argument("--only", default="", help="comma-separated mutant ids")
    ap.add_argument("--list", action="store_true", help="list the mutants and exit")
    ap.add_argument("--stale", action="store_true",
                    help="only check that every mutant's snippet occurs once (make check)")
    ap.add_argument("--keep", action="store_true", help="keep the scratch copy")
    ap.add_argument("--allow-missing", action="store_true",
                    help="skip tests the tree does not have (to measure an older tree)")
    ap.add_argument("--skip-baseline", action="store_true",
                    help="do not first run the named tests on the unmutated copy")
    a = ap.parse_args()
    mutants = MUTANTS
    if a.only:
        want = set(a.only.split(","))
        mutants = [m for m in MUTANTS if m[0] in want]
        unknown = want - {m[0] for m in mutants}
        if unknown:
            sys.exit("mutate: no mutant named " + ", ".join(sorted(unknown)))
    if a.list:
        for m in mutants:
            print(f"{m[0]:28} {m[1]:24} {' '.join(m[4])}")
        return 0

    # staleness first, against the working tree, so it is reported before any build
    stale = []
    for mid, path, orig, _repl, _tests, _eq in mutants:
        with open(os.path.join(ROOT, path)) as f:
            count = f.read().count(orig)
        if count != 1:
            stale.append((mid, path, count))
    for mid, path, count in stale:
        print(f"STALE mutant {mid}: its snippet occurs {count} times in {path} (must be once); "
              f"update scripts/mutate.py", file=sys.stderr)
    if a.stale:
        print(f"mutate: {len(mutants) - len(stale)} of {len(mutants)} mutants apply")
        return 1 if stale else 0

    scratch = tempfile.mkdtemp(prefix="nbep-mutate-")
    try:
        copy_tree(scratch)
        print(f"mutate: building the unmutated copy in {scratch}", flush=True)
        if run(["make", f"-j{a.jobs}", "MPI=0", "bin/nbep", "check-programs"], scratch) != 0:
            sys.exit("mutate: the unmutated tree does not build")
        # the tests' scratch folder (nbep_test_tmp), as scripts/run-tests.sh makes it: without
        # it a test that writes a file fails whatever the mutant, until some shell test that
        # makes it has run (a --only of test_granular's mutants was "killed" so)
        os.makedirs(os.path.join(scratch, "build", "tests", "tmp"), exist_ok=True)
        # every test the run names, once on the unmutated copy: a test that fails there fails
        # whatever the mutant, and each of its "kills" would be counted for nothing
        # (test_sweep_cli.sh expected an MPI build's message and "killed" every sweep mutant)
        stale_ids = {s[0] for s in stale}
        named = sorted({t for m in mutants if not m[5] and m[0] not in stale_ids for t in m[4]
                        if os.path.exists(os.path.join(scratch, test_path(t)))})
        for t in [] if a.skip_baseline else named:
            if "sweep_mpi" in t:
                continue  # its mutants are built with MPI, this copy without
            log_path = os.path.join(scratch, "build", f"baseline-{os.path.basename(t)}.log")
            with open(log_path, "w") as log:
                cmd = (["bash"] if t.endswith(".sh") else []) + [test_path(t)]
                r = run(["timeout", "-k", "5", str(a.timeout)] + cmd, scratch, log=log)
            if r != 0:
                with open(log_path) as log:
                    tail = log.read()[-2000:]
                sys.exit(f"mutate: {t} fails on the unmutated tree (exit {r}), so it would "
                         f"'kill' every mutant; fix it first. Its output ends:\n{tail}")
        print(f"mutate: {len(named)} test(s) pass on the unmutated copy", flush=True)
        rows = []
        counts = {"killed": 0, "survived": 0, "equivalent": 0}
        for mid, path, orig, repl, tests, eq in mutants:
            if any(s[0] == mid for s in stale):
                rows.append((mid, "STALE", "snippet not found exactly once"))
                continue
            if eq:
                counts["equivalent"] += 1
                rows.append((mid, "equivalent", eq))
                print(f"{mid:28} equivalent", flush=True)
                continue
            target = os.path.join(scratch, path)
            with open(target) as f:
                text = f.read()
            with open(target, "w") as f:
                f.write(text.replace(orig, repl, 1))
            t0 = time.monotonic()
            # MPI=0 keeps Open MPI out of the tests' processes; a mutant only an MPI test can
            # see is built with it (only sweep.c takes MPI's flags, and the mutant or its undoing
            # touches it, so it and every link are made again either way)
            mpi = [] if any("sweep_mpi" in t for t in tests) else ["MPI=0"]  # []: the default
            rc = run(["make", f"-j{a.jobs}"] + mpi + ["bin/nbep", "check-programs"], scratch)
            if rc != 0:
                verdict, why = "killed", "does not build"
            else:
                verdict, why = "survived", "every test passed: " + " ".join(tests)
                for t in tests:
                    if not os.path.exists(os.path.join(scratch, test_path(t))):
                        if a.allow_missing:
                            continue
                        sys.exit(f"mutate: mutant {mid} names a test that does not exist: {t}")
                    env_log = open(os.path.join(scratch, "build", f"mutant-{mid}-{os.path.basename(t)}.log"), "w")
                    cmd = (["bash"] if t.endswith(".sh") else []) + [test_path(t)]
                    r = run(["timeout", "-k", "5", str(a.timeout)] + cmd, scratch, log=env_log)
                    env_log.close()
                    if r != 0:
                        how = "hung (timeout)" if r in (124, 137, "timeout") else f"exit {r}"
                        verdict, why = "killed", f"{t} {how}"
                        break
            with open(target, "w") as f:
                f.write(text)
            counts[verdict] += 1
            rows.append((mid, verdict, why))
            print(f"{mid:28} {verdict:10} {why} ({time.monotonic() - t0:.0f} s)", flush=True)
    finally:
        if not a.keep:
            shutil.rmtree(scratch, ignore_errors=True)

    print()
    print("| mutant | result | detail |")
    print("| --- | --- | --- |")
    for mid, verdict, why in rows:
        print(f"| {mid} | {verdict} | {why.replace('|', chr(92) + '|')} |")
    print()
    if stale:
        print(f"mutate: {len(stale)} stale mutant(s): " + ", ".join(s[0] for s in stale),
              file=sys.stderr)
    print(f"mutants: {counts['killed']} killed, {counts['survived']} survived, "
          f"{counts['equivalent']} equivalent")
    return 0 if counts["survived"] == 0 and not stale else 1


if __name__ == "__main__":
    sys.exit(main())
