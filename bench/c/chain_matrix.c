/* (b) The calibrated 3x4 matrix chain, inner products written out: per joint the angle as
 * a binary angle (count scaled, zero offset added as an integer), its cosine and sine by
 * quarter turn and polynomial (turn.h), the harmonic error from them (coefficients rotated
 * to the offset at boot) added to second order, then R <- R F_i Rz(angle) and
 * o <- o + R (link + rate dt); gravity to first order at the end. */
#include "bench.h"
#include "cal.h"
#include "turn.h"

const char chain_name[] = "matrix";

static struct {
    struct count_scale scale;
    uint32_t offset;
    float h[4];
    int has_h;
    float f[3][3], link[3], rate[3], g;
} J[CAL_JOINTS];
static float dir[3];

void chain_init(void) {
    for (int i = 0; i < CAL_JOINTS; i++) {
        const struct cal_joint *c = &cal_joints[i];
        J[i].scale = count_scale_of(c->counts);
        J[i].offset = binary_of(c->zero_offset);
        harmonics_at(c, c->zero_offset, J[i].h);
        J[i].has_h = c->s1 != 0 || c->c1 != 0 || c->s2 != 0 || c->c2 != 0;
        for (int r = 0; r < 3; r++) {
            for (int k = 0; k < 3; k++) J[i].f[r][k] = (float)c->f[r][k];
            J[i].link[r] = (float)c->link[r];
            J[i].rate[r] = (float)c->rate[r];
        }
        J[i].g = (float)c->gravity;
    }
    for (int r = 0; r < 3; r++) dir[r] = (float)cal_probe_dir[r];
}

int chain_eval(const uint32_t *counts, int32_t temp_mc, float out[6]) {
    float dt = delta_t(temp_mc);
    float r00 = 1, r01 = 0, r02 = 0, r10 = 0, r11 = 1, r12 = 0, r20 = 0, r21 = 0, r22 = 1;
    float o0 = 0, o1 = 0, o2 = 0;
    struct gravity gv;
    gv.n = 0;
    for (int i = 0; i < CAL_JOINTS; i++) {
        if (counts[i] >= J[i].scale.counts) return i + 1;
        float c, s;
        turn_cs(count_turn(J[i].scale, counts[i]) + J[i].offset, &c, &s);
        if (J[i].has_h) turn_by(&c, &s, harmonic(J[i].h, c, s));
        const float(*f)[3] = J[i].f;
        /* R F, column by column. */
        float a0 = r00 * f[0][0] + r01 * f[1][0] + r02 * f[2][0];
        float a1 = r10 * f[0][0] + r11 * f[1][0] + r12 * f[2][0];
        float a2 = r20 * f[0][0] + r21 * f[1][0] + r22 * f[2][0];
        float b0 = r00 * f[0][1] + r01 * f[1][1] + r02 * f[2][1];
        float b1 = r10 * f[0][1] + r11 * f[1][1] + r12 * f[2][1];
        float b2 = r20 * f[0][1] + r21 * f[1][1] + r22 * f[2][1];
        float d0 = r00 * f[0][2] + r01 * f[1][2] + r02 * f[2][2];
        float d1 = r10 * f[0][2] + r11 * f[1][2] + r12 * f[2][2];
        float d2 = r20 * f[0][2] + r21 * f[1][2] + r22 * f[2][2];
        /* ... times Rz. */
        r00 = a0 * c + b0 * s, r01 = b0 * c - a0 * s, r02 = d0;
        r10 = a1 * c + b1 * s, r11 = b1 * c - a1 * s, r12 = d1;
        r20 = a2 * c + b2 * s, r21 = b2 * c - a2 * s, r22 = d2;
        if (J[i].g != 0.0f) {
            float ax[3] = {d0, d1, d2}, o[3] = {o0, o1, o2};
            gravity_push(&gv, J[i].g, ax, o);
        }
        float l0 = J[i].link[0] + J[i].rate[0] * dt;
        float l1 = J[i].link[1] + J[i].rate[1] * dt;
        float l2 = J[i].link[2] + J[i].rate[2] * dt;
        o0 += r00 * l0 + r01 * l1 + r02 * l2;
        o1 += r10 * l0 + r11 * l1 + r12 * l2;
        o2 += r20 * l0 + r21 * l1 + r22 * l2;
    }
    float p[3] = {o0, o1, o2};
    float n[3] = {r00 * dir[0] + r01 * dir[1] + r02 * dir[2], r10 * dir[0] + r11 * dir[1] + r12 * dir[2],
                  r20 * dir[0] + r21 * dir[1] + r22 * dir[2]};
    gravity_apply(&gv, p, n);
    for (int r = 0; r < 3; r++) out[r] = p[r], out[3 + r] = n[r];
    return 0;
}
