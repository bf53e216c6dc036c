/* predict.c internals shared with its tests: the GSL-free contact search that the quartic
 * falls back on, exported so that tests/test_predict.c can check it against the GSL path. */
#ifndef NBEP_PREDICT_IMPL_H
#define NBEP_PREDICT_IMPL_H

#include "nbep/vec3.h"

/* The same answer as nbep_predict_pair, found without GSL: the critical points of
 * f(t) = |dp + dv t + da t^2/2|^2 - sigma^2 are isolated through the real roots of f'' (closed
 * form) and bisection on f', then the first stretch on which f decreases to or below zero is
 * searched by bisection. Slower than the companion-matrix path, but it cannot miss a root;
 * it is used when GSL reports a failure and for pairs that overlap without closing at t = 0. */
double nbep__predict_pair_bracket(nbep_vec3 dp, nbep_vec3 dv, nbep_vec3 da, double sigma);

#endif
