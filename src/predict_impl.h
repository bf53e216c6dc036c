/* predict.c internals shared with its tests and benchmarks: the GSL-free contact search, and
 * the compensated evaluations the solvers use, so that tests/test_predict.c and
 * tests/bench/bench_contact.c check and compare against this very code. */
#ifndef NBEP_PREDICT_IMPL_H
#define NBEP_PREDICT_IMPL_H

#include "nbep/vec3.h"

/* The same answer as nbep_predict_pair, found without GSL: the critical points of
 * f(t) = |dp + dv t + da t^2/2|^2 - sigma^2 are isolated through the real roots of f'' (closed
 * form) and bisection on f', then the first stretch on which f decreases to or below zero is
 * searched by bisection. Slower than the companion-matrix path, but it cannot miss a root;
 * it is used when GSL reports a failure and for pairs that overlap without closing at t = 0. */
double nbep__predict_pair_bracket(nbep_vec3 dp, nbep_vec3 dv, nbep_vec3 da, double sigma);

/* |r|^2 - sigma^2 as accurately as if computed in twice the precision and rounded once. */
double nbep__predict_gap2(nbep_vec3 r, double sigma);
/* f(t) = |dp + dv t + da t^2/2|^2 - sigma^2, compensated as the solvers evaluate it. */
double nbep__predict_f(nbep_vec3 dp, nbep_vec3 dv, nbep_vec3 da, double sigma, double t);

#endif
