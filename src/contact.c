/* Lasting contacts: the motion left to a sphere held by several frictionless contacts
 * (contact.h). The nearest point of a polyhedral cone is found by trying active sets in
 * order of size (at most 15 of them for NBEP_CONTACT_MAX = 4): the first whose forces all
 * push and whose motion leaves every other contact is the answer (the KKT conditions of the
 * projection; the answer is unique, so the order only decides which of several equal
 * degenerate descriptions is reported). */
#include "nbep/contact.h"

#include <assert.h>
#include <math.h>

static nbep_vec3 cross(nbep_vec3 a, nbep_vec3 b)
{
    return nbep_vec3_make(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

/* Unit direction of the edge common to planes with normals n1 and n2; false if they are
 * parallel (within NBEP_CONTACT_TOL), when there is no single edge. */
static bool edge(nbep_vec3 n1, nbep_vec3 n2, nbep_vec3 *t)
{
    nbep_vec3 c = cross(n1, n2);
    double len = nbep_vec3_norm(c);
    if (!(len > NBEP_CONTACT_TOL))
        return false;
    *t = nbep_vec3_make(c.x / len, c.y / len, c.z / len);
    return true;
}

static int bits(unsigned m)
{
    int c = 0;
    for (; m; m &= m - 1)
        c++;
    return c;
}

/* The motion under the contacts of mask, all held at x.n = 0, and their pushes (mu, in the
 * order of the mask's bits: x = a + sum mu n); false if their forces would have to pull (or
 * the set is degenerate). */
static bool try_set(nbep_vec3 a, const nbep_vec3 *n, int k, unsigned mask, double tol,
                    nbep_vec3 *x, double mu[3])
{
    int idx[3], m = 0;
    for (int j = 0; j < k; j++)
        if (mask >> j & 1u)
            idx[m++] = j;
    if (m == 0) {
        *x = a;
    } else if (m == 1) {
        double an = nbep_vec3_dot(a, n[idx[0]]);
        if (!(an < 0.0))
            return false;
        *x = nbep_vec3_axpy(a, -an, n[idx[0]]);
        mu[0] = -an; /* > 0 by the test above */
    } else if (m == 2) {
        nbep_vec3 n1 = n[idx[0]], n2 = n[idx[1]], t;
        if (!edge(n1, n2, &t))
            return false;
        *x = nbep_vec3_scale(t, nbep_vec3_dot(a, t));
        nbep_vec3 r = nbep_vec3_sub(*x, a); /* = mu1 n1 + mu2 n2 */
        double g = nbep_vec3_dot(n1, n2), r1 = nbep_vec3_dot(r, n1), r2 = nbep_vec3_dot(r, n2);
        double den = 1.0 - g * g;
        if (!(r1 - g * r2 >= -tol * den) || !(r2 - g * r1 >= -tol * den))
            return false;
        /* (>= -tol: a push that is zero to round-off counts as none) */
        mu[0] = fmax(0.0, (r1 - g * r2) / den);
        mu[1] = fmax(0.0, (r2 - g * r1) / den);
    } else {
        nbep_vec3 n1 = n[idx[0]], n2 = n[idx[1]], n3 = n[idx[2]];
        nbep_vec3 c23 = cross(n2, n3), c31 = cross(n3, n1), c12 = cross(n1, n2);
        double det = nbep_vec3_dot(n1, c23);
        if (!(fabs(det) > NBEP_CONTACT_TOL))
            return false;
        /* -a = mu1 n1 + mu2 n2 + mu3 n3 (Cramer); every mu must push */
        double s = det > 0.0 ? 1.0 : -1.0;
        if (!(-nbep_vec3_dot(a, c23) * s >= -tol * fabs(det)) ||
            !(-nbep_vec3_dot(a, c31) * s >= -tol * fabs(det)) ||
            !(-nbep_vec3_dot(a, c12) * s >= -tol * fabs(det)))
            return false;
        mu[0] = fmax(0.0, -nbep_vec3_dot(a, c23) / det);
        mu[1] = fmax(0.0, -nbep_vec3_dot(a, c31) / det);
        mu[2] = fmax(0.0, -nbep_vec3_dot(a, c12) / det);
        *x = nbep_vec3_make(0.0, 0.0, 0.0);
    }
    for (int j = 0; j < k; j++) {
        if (mask >> j & 1u)
            continue;
        double xn = nbep_vec3_dot(*x, n[j]);
        if (m == 0 ? !(xn >= 0.0) : !(xn >= -tol))
            return false;
    }
    return true;
}

nbep_vec3 nbep_contact_project(nbep_vec3 a, const nbep_vec3 *n, int k, unsigned *active)
{
    double mu[NBEP_CONTACT_MAX];
    return nbep_contact_project_push(a, n, k, active, mu);
}

nbep_vec3 nbep_contact_project_push(nbep_vec3 a, const nbep_vec3 *n, int k, unsigned *active,
                                    double mu[NBEP_CONTACT_MAX])
{
    assert(k >= 0 && k <= NBEP_CONTACT_MAX);
    for (int j = 0; j < NBEP_CONTACT_MAX; j++)
        mu[j] = 0.0;
    const double tol = NBEP_CONTACT_TOL * nbep_vec3_norm(a);
    const unsigned all = (1u << k) - 1u;
    for (int size = 0; size <= (k < 3 ? k : 3); size++)
        for (unsigned mask = 0; mask <= all; mask++) {
            if (bits(mask) != size)
                continue;
            nbep_vec3 x;
            double m[3] = {0.0, 0.0, 0.0};
            if (try_set(a, n, k, mask, tol, &x, m)) {
                *active = mask;
                for (int j = 0, q = 0; j < k; j++)
                    if (mask >> j & 1u)
                        mu[j] = m[q++];
                return x;
            }
        }
    /* only degenerate sets left (normals within round-off of dependent): held still */
    *active = all;
    return nbep_vec3_make(0.0, 0.0, 0.0);
}

nbep_vec3 nbep_contact_tangent(nbep_vec3 v, const nbep_vec3 *n, int k, unsigned mask)
{
    nbep_vec3 first = {0.0, 0.0, 0.0}, t = {0.0, 0.0, 0.0};
    bool have = false, line = false;
    for (int j = 0; j < k; j++) {
        if (!(mask >> j & 1u))
            continue;
        if (!have) {
            first = n[j];
            have = true;
        } else if (!line) {
            if (!edge(first, n[j], &t))
                continue;                 /* parallel to the first: nothing new */
            line = true;
        } else if (fabs(nbep_vec3_dot(t, n[j])) > NBEP_CONTACT_TOL) {
            return nbep_vec3_make(0.0, 0.0, 0.0); /* three independent: no motion left */
        }
    }
    if (line)
        return nbep_vec3_scale(t, nbep_vec3_dot(v, t));
    if (have)
        return nbep_vec3_axpy(v, -nbep_vec3_dot(v, first), first);
    return v;
}
