/* (c) The lean forward chain. At boot (double) each joint's fixed rotation is split into
 * z-x-z Euler angles F_i = Rz(a_i) Rx(alpha_i) Rz(b_i); b_i and the next joint's a_(i+1)
 * join joint i's count as one binary-angle offset (with the zero offset), the harmonic
 * coefficients rotated to match and link i turned back by a_(i+1). Per joint and point
 * remain a turn about z by the reading and a turn about x by a constant:
 *
 *   p = Rz(a_1) [Rx(alpha_1) Rz(t'_1) (v'_1 + Rx(alpha_2) Rz(t'_2) (v'_2 + ...))],
 *
 * evaluated tip to base (Horner), the probe direction alongside. Gravity: a first pass,
 * base to tip, keeps the angles and turns the base's vertical into each compliant joint's
 * frame; the second adds each deflection g_k (w x z).z_k to its joint's angle. The same
 * form as the Rust hub's src/lean.rs, written plainly (no quarter-turn split of the
 * rotations). */
#include "bench.h"
#include "cal.h"
#include "turn.h"

const char chain_name[] = "lean";

static struct {
    struct count_scale scale;
    uint32_t offset;
    float h[4];
    int has_h;
    float link[3], rate[3], g;
    float ca, sa; /* cos, sin alpha */
} J[CAL_JOINTS];
static float dir[3], base_c, base_s;
static int vertical_joints;

static double turn_rad(uint32_t t) { return (double)(int32_t)t * (6.283185307179586476925 / 4294967296.0); }

void chain_init(void) {
    uint32_t a[CAL_JOINTS + 1] = {0}, b[CAL_JOINTS];
    double alpha[CAL_JOINTS];
    for (int i = 0; i < CAL_JOINTS; i++) {
        const double(*f)[3] = cal_joints[i].f;
        /* Column 2 of Rz(a) Rx(alpha) Rz(b) is (sin a sin alpha, -cos a sin alpha, cos alpha). */
        double ai = atan2(f[0][2], -f[1][2]);
        a[i] = binary_of(ai);
        double c = cos(turn_rad(a[i])), s = sin(turn_rad(a[i])), n[3][3], p[3][3];
        for (int k = 0; k < 3; k++) { /* N = Rz(-a) F = Rx(alpha) Rz(b) */
            n[0][k] = c * f[0][k] + s * f[1][k];
            n[1][k] = -s * f[0][k] + c * f[1][k];
            n[2][k] = f[2][k];
        }
        alpha[i] = atan2(-n[1][2], n[2][2]);
        double ca = cos(alpha[i]), sa = sin(alpha[i]);
        for (int k = 0; k < 3; k++) { /* P = Rx(-alpha) N = Rz(b) */
            p[0][k] = n[0][k];
            p[1][k] = ca * n[1][k] + sa * n[2][k];
            p[2][k] = -sa * n[1][k] + ca * n[2][k];
        }
        b[i] = binary_of(atan2(p[1][0], p[0][0]));
    }
    vertical_joints = 0;
    for (int i = 0; i < CAL_JOINTS; i++) {
        const struct cal_joint *cj = &cal_joints[i];
        J[i].scale = count_scale_of(cj->counts);
        J[i].offset = binary_of(cj->zero_offset) + b[i] + a[i + 1];
        harmonics_at(cj, turn_rad(J[i].offset), J[i].h);
        J[i].has_h = cj->s1 != 0 || cj->c1 != 0 || cj->s2 != 0 || cj->c2 != 0;
        /* v' = Rz(-a_(i+1)) v. */
        double c = cos(turn_rad(a[i + 1])), s = sin(turn_rad(a[i + 1]));
        const double *l = cj->link, *r = cj->rate;
        J[i].link[0] = (float)(c * l[0] + s * l[1]);
        J[i].link[1] = (float)(-s * l[0] + c * l[1]);
        J[i].link[2] = (float)l[2];
        J[i].rate[0] = (float)(c * r[0] + s * r[1]);
        J[i].rate[1] = (float)(-s * r[0] + c * r[1]);
        J[i].rate[2] = (float)r[2];
        J[i].g = (float)cj->gravity;
        J[i].ca = (float)cos(alpha[i]);
        J[i].sa = (float)sin(alpha[i]);
        if (cj->gravity != 0) vertical_joints = i + 1;
    }
    base_c = (float)cos(turn_rad(a[0]));
    base_s = (float)sin(turn_rad(a[0]));
    for (int r = 0; r < 3; r++) dir[r] = (float)cal_probe_dir[r];
}

int chain_eval(const uint32_t *counts, int32_t temp_mc, float out[6]) {
    float dt = delta_t(temp_mc);
    float c0[CAL_JOINTS], s0[CAL_JOINTS], eh[CAL_JOINTS], cc[CAL_JOINTS], ss[CAL_JOINTS];
    /* Written for the joints below vertical_joints, read only for those (gcc cannot tell). */
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
    float vx[CAL_JOINTS], vy[CAL_JOINTS];
    float zx = 0, zy = 0, zz = 1;
    /* Base to tip: the angles, and the vertical up to the last compliant joint. */
#pragma GCC unroll 8
    for (int i = 0; i < CAL_JOINTS; i++) {
        if (counts[i] >= J[i].scale.counts) return i + 1;
        float c, s, e = 0;
        turn_cs(count_turn(J[i].scale, counts[i]) + J[i].offset, &c, &s);
        c0[i] = c, s0[i] = s;
        if (J[i].has_h) {
            e = harmonic(J[i].h, c, s);
            turn_by(&c, &s, e);
        }
        eh[i] = e, cc[i] = c, ss[i] = s;
        if (i < vertical_joints) {
            /* Rx(-alpha), then Rz(-angle). */
            float y = J[i].ca * zy + J[i].sa * zz, z = J[i].ca * zz - J[i].sa * zy;
            float x = c * zx + s * y;
            zy = c * y - s * zx, zx = x, zz = z;
            vx[i] = zx, vy[i] = zy;
        }
    }
    /* Tip to base. */
    float w0 = 0, w1 = 0, w2 = 0, d0 = dir[0], d1 = dir[1], d2 = dir[2];
#pragma GCC unroll 8
    for (int i = CAL_JOINTS - 1; i >= 0; i--) {
        w0 += J[i].link[0] + J[i].rate[0] * dt;
        w1 += J[i].link[1] + J[i].rate[1] * dt;
        w2 += J[i].link[2] + J[i].rate[2] * dt;
        float c = cc[i], s = ss[i];
        /* Every compliant joint is below vertical_joints (chain_init). */
        if (i < vertical_joints && J[i].g != 0.0f) {
            c = c0[i], s = s0[i];
            turn_by(&c, &s, eh[i] + J[i].g * (w0 * vy[i] - w1 * vx[i]));
        }
        float x = c * w0 - s * w1;
        w1 = s * w0 + c * w1, w0 = x;
        x = c * d0 - s * d1;
        d1 = s * d0 + c * d1, d0 = x;
        float ca = J[i].ca, sa = J[i].sa;
        float y = ca * w1 - sa * w2;
        w2 = sa * w1 + ca * w2, w1 = y;
        y = ca * d1 - sa * d2;
        d2 = sa * d1 + ca * d2, d1 = y;
    }
#pragma GCC diagnostic pop
    out[0] = base_c * w0 - base_s * w1, out[1] = base_s * w0 + base_c * w1, out[2] = w2;
    out[3] = base_c * d0 - base_s * d1, out[4] = base_s * d0 + base_c * d1, out[5] = d2;
    return 0;
}
