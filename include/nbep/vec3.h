/* 3-vectors of doubles with inline arithmetic. Header only. */
#ifndef NBEP_VEC3_H
#define NBEP_VEC3_H

#include <math.h>
#include <stdbool.h>

typedef struct nbep_vec3 {
    double x, y, z;
} nbep_vec3;

static inline nbep_vec3 nbep_vec3_make(double x, double y, double z)
{
    return (nbep_vec3){x, y, z};
}
static inline nbep_vec3 nbep_vec3_add(nbep_vec3 a, nbep_vec3 b)
{
    return (nbep_vec3){a.x + b.x, a.y + b.y, a.z + b.z};
}
static inline nbep_vec3 nbep_vec3_sub(nbep_vec3 a, nbep_vec3 b)
{
    return (nbep_vec3){a.x - b.x, a.y - b.y, a.z - b.z};
}
static inline nbep_vec3 nbep_vec3_scale(nbep_vec3 a, double s)
{
    return (nbep_vec3){a.x * s, a.y * s, a.z * s};
}
/* a + s b */
static inline nbep_vec3 nbep_vec3_axpy(nbep_vec3 a, double s, nbep_vec3 b)
{
    return (nbep_vec3){a.x + s * b.x, a.y + s * b.y, a.z + s * b.z};
}
static inline double nbep_vec3_dot(nbep_vec3 a, nbep_vec3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
static inline double nbep_vec3_norm2(nbep_vec3 a)
{
    return nbep_vec3_dot(a, a);
}
static inline double nbep_vec3_norm(nbep_vec3 a)
{
    return sqrt(nbep_vec3_dot(a, a));
}
/* x * 0 is a zero for every finite x and NaN for an infinite or NaN one, so the sum of the
 * three is a zero exactly when all three are finite: one comparison instead of three tests
 * and branches (the response's checks of its inputs ran at 60 instructions a collision of a
 * fluid). Exact under the build's IEEE arithmetic (no -ffast-math: x * 0 is not folded). */
static inline bool nbep_vec3_isfinite(nbep_vec3 a)
{
    return a.x * 0.0 + a.y * 0.0 + a.z * 0.0 == 0.0;
}
static inline bool nbep_vec3_equal(nbep_vec3 a, nbep_vec3 b)
{
    return a.x == b.x && a.y == b.y && a.z == b.z;
}

#endif
