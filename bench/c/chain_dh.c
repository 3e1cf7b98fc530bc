/* (a) Where many firmware teams start: each joint a 3x4 transform built from newlib's sinf
 * and cosf of its angle, multiplied into the running transform in full (the Denavit-
 * Hartenberg style: T = T_1 T_2 ... T_n). The whole model all the same: the angle
 * theta = 2 pi count / counts in float, the zero offset and the two harmonics (sinf and cosf
 * of theta, the second order by the double angle), each joint's fixed rotation, the links'
 * expansion and gravity to first order. Built with -DGEOMETRY_ONLY: the geometry alone (zero
 * offsets, the fixed rotations, the links; one sinf and one cosf a joint), as a team's first
 * version would be, and not the calibrated model: its accuracy shows what the rest is worth. */
#include "bench.h"
#include "cal.h"
#include "turn.h"

#ifdef GEOMETRY_ONLY
const char chain_name[] = "dh-sinf-geometry";
#else
const char chain_name[] = "dh-sinf";
#endif

static struct {
    float f[3][3], link[3], rate[3];
    float k, zero, s1, c1, s2, c2, g;
    uint32_t counts;
} J[CAL_JOINTS];
static float dir[3];

void chain_init(void) {
    for (int i = 0; i < CAL_JOINTS; i++) {
        const struct cal_joint *c = &cal_joints[i];
        for (int r = 0; r < 3; r++) {
            for (int k = 0; k < 3; k++) J[i].f[r][k] = (float)c->f[r][k];
            J[i].link[r] = (float)c->link[r];
            J[i].rate[r] = (float)c->rate[r];
        }
        J[i].k = (float)(6.283185307179586476925 / c->counts);
        J[i].zero = (float)c->zero_offset;
        J[i].s1 = (float)c->s1, J[i].c1 = (float)c->c1;
        J[i].s2 = (float)c->s2, J[i].c2 = (float)c->c2;
        J[i].g = (float)c->gravity;
        J[i].counts = c->counts;
    }
    for (int r = 0; r < 3; r++) dir[r] = (float)cal_probe_dir[r];
}

/* t = t * a, both 3x4 (rotation | translation). */
static void mul34(float t[3][4], const float a[3][4]) {
    float out[3][4];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++) {
            float x = c == 3 ? t[r][3] : 0.0f;
            for (int k = 0; k < 3; k++) x += t[r][k] * a[k][c];
            out[r][c] = x;
        }
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++) t[r][c] = out[r][c];
}

int chain_eval(const uint32_t *counts, int32_t temp_mc, float out[6]) {
    float dt = delta_t(temp_mc);
    float t[3][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}};
    struct gravity gv;
    gv.n = 0;
    for (int i = 0; i < CAL_JOINTS; i++) {
        if (counts[i] >= J[i].counts) return i + 1;
        float th = (float)counts[i] * J[i].k;
#ifdef GEOMETRY_ONLY
        float phi = th + J[i].zero;
#else
        float st = sinf(th), ct = cosf(th);
        float phi = th + J[i].zero + J[i].s1 * st + J[i].c1 * ct + J[i].s2 * (2.0f * st * ct) +
                    J[i].c2 * (ct * ct - st * st);
#endif
        float c = cosf(phi), s = sinf(phi);
        float a[3][4];
        for (int r = 0; r < 3; r++) {
            a[r][0] = J[i].f[r][0] * c + J[i].f[r][1] * s;
            a[r][1] = J[i].f[r][1] * c - J[i].f[r][0] * s;
            a[r][2] = J[i].f[r][2];
        }
        float l[3];
#ifdef GEOMETRY_ONLY
        (void)dt;
        for (int k = 0; k < 3; k++) l[k] = J[i].link[k];
#else
        for (int k = 0; k < 3; k++) l[k] = J[i].link[k] + J[i].rate[k] * dt;
#endif
        for (int r = 0; r < 3; r++) a[r][3] = a[r][0] * l[0] + a[r][1] * l[1] + a[r][2] * l[2];
        float o[3] = {t[0][3], t[1][3], t[2][3]};
        mul34(t, a);
#ifndef GEOMETRY_ONLY
        if (J[i].g != 0.0f) {
            float ax[3] = {t[0][2], t[1][2], t[2][2]};
            gravity_push(&gv, J[i].g, ax, o);
        }
#else
        (void)o;
#endif
    }
    float p[3], n[3];
    for (int r = 0; r < 3; r++) {
        p[r] = t[r][3];
        n[r] = t[r][0] * dir[0] + t[r][1] * dir[1] + t[r][2] * dir[2];
    }
    gravity_apply(&gv, p, n);
    for (int r = 0; r < 3; r++) out[r] = p[r], out[3 + r] = n[r];
    return 0;
}
