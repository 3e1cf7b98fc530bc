/* Float helpers the calibrated chains (matrix, lean) share: a joint's angle from its count
 * as a binary angle (one turn = 2^32: the zero offset and other fixed turns are one integer
 * add), its cosine and sine by an exact quarter turn and polynomials on |r| <= pi/4, the
 * harmonic error from them, and the first-order gravity correction. */
#ifndef TURN_H
#define TURN_H
#include <math.h>
#include <stdint.h>
#include "model.h"

/* A count as a binary angle: a shift where the counts a turn are a power of two. */
struct count_scale {
    uint32_t counts;
    int shift; /* 32 - log2(counts), or -1 */
};

static inline struct count_scale count_scale_of(uint32_t counts) {
    struct count_scale s = {counts, -1};
    for (int k = 0; k < 32; k++)
        if (counts == (1u << k)) s.shift = 32 - k;
    return s;
}

static inline uint32_t count_turn(struct count_scale s, uint32_t count) {
    if (s.shift >= 0) return count << s.shift;
    return (uint32_t)(((uint64_t)count << 32) / s.counts);
}

/* Radians (boot, double) as a binary angle. */
static inline uint32_t binary_of(double rad) {
    return (uint32_t)(int64_t)llround(rad * (4294967296.0 / 6.283185307179586476925));
}

/* cos and sin of a binary angle: quarter turns exact, Taylor polynomials to x^9 and x^10
 * on the remainder (truncation below 2e-9 for |x| <= pi/4). */
static inline void turn_cs(uint32_t t, float *c, float *s) {
    uint32_t q = (t + (1u << 29)) >> 30;
    int32_t r = (int32_t)(t - (q << 30));
    float x = (float)r * 1.4629180792671596e-9f; /* pi / 2^31 */
    float z = x * x;
    float sn = x + x * z * (-1.0f / 6 + z * (1.0f / 120 + z * (-1.0f / 5040 + z * (1.0f / 362880))));
    float cs = 1.0f + z * (-0.5f + z * (1.0f / 24 + z * (-1.0f / 720 + z * (1.0f / 40320 + z * (-1.0f / 3628800)))));
    switch (q & 3) {
    case 0: *c = cs; *s = sn; break;
    case 1: *c = -sn; *s = cs; break;
    case 2: *c = -cs; *s = -sn; break;
    default: *c = sn; *s = -cs; break;
    }
}

/* The harmonic coefficients for the angle u = t + off (rad) instead of the raw t (exact
 * identities, boot, double): {s1', c1', 2 s2', c2'} so that e = s (h0 + c h2 - s h3) + c (h1 + c h3)
 * with c, s the cosine and sine of u. */
static inline void harmonics_at(const struct cal_joint *j, double off, float h[4]) {
    double c1 = cos(off), s1 = sin(off), c2 = cos(2 * off), s2 = sin(2 * off);
    h[0] = (float)(j->s1 * c1 + j->c1 * s1);
    h[1] = (float)(j->c1 * c1 - j->s1 * s1);
    h[2] = (float)(2 * (j->s2 * c2 + j->c2 * s2));
    h[3] = (float)(j->c2 * c2 - j->s2 * s2);
}

static inline float harmonic(const float h[4], float c, float s) {
    return s * (h[0] + c * h[2] - s * h[3]) + c * (h[1] + c * h[3]);
}

/* (c, s) turned by a small angle e (|e| <= 1e-3), to second order. */
static inline void turn_by(float *c, float *s, float e) {
    float h = 0.5f * (e * e), c0 = *c, s0 = *s;
    *c = c0 - (s0 * e + c0 * h);
    *s = s0 + (c0 * e - s0 * h);
}

/* Gravity to first order, as the spec defines it: deflections e_k = g_k a_k . ((p - o_k) x z)
 * from the undeflected pass, then p += sum e_k a_k x (p - o_k), n += sum e_k a_k x n. */
struct gravity {
    int n;
    float g[8], a[8][3], o[8][3];
};

static inline void gravity_push(struct gravity *gv, float g, const float a[3], const float o[3]) {
    int k = gv->n++;
    gv->g[k] = g;
    for (int r = 0; r < 3; r++) gv->a[k][r] = a[r], gv->o[k][r] = o[r];
}

static inline void gravity_apply(const struct gravity *gv, float p[3], float n[3]) {
    float dp[3] = {0, 0, 0}, dn[3] = {0, 0, 0};
    for (int k = 0; k < gv->n; k++) {
        const float *a = gv->a[k];
        float w[3] = {p[0] - gv->o[k][0], p[1] - gv->o[k][1], p[2] - gv->o[k][2]};
        float e = gv->g[k] * (a[0] * w[1] - a[1] * w[0]);
        dp[0] += e * (a[1] * w[2] - a[2] * w[1]);
        dp[1] += e * (a[2] * w[0] - a[0] * w[2]);
        dp[2] += e * (a[0] * w[1] - a[1] * w[0]);
        dn[0] += e * (a[1] * n[2] - a[2] * n[1]);
        dn[1] += e * (a[2] * n[0] - a[0] * n[2]);
        dn[2] += e * (a[0] * n[1] - a[1] * n[0]);
    }
    for (int r = 0; r < 3; r++) p[r] += dp[r], n[r] += dn[r];
}

static inline float delta_t(int32_t temp_mc) { return (float)(temp_mc - 20000) * 0.001f; }
#endif
