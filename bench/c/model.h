/* The calibrated model as the generated header cal.h gives it (xtask/src/cbase/header.rs
 * writes it from the same calibration file the Rust bench builds its table from): every
 * joint in its z-axis frame, i.e. its axis permuted onto z, so that each chain turns about z
 * only. Doubles: each chain rounds to float once, at boot. */
#ifndef MODEL_H
#define MODEL_H
#include <stdint.h>

struct cal_joint {
    /* Encoder counts a turn. */
    uint32_t counts;
    /* The fixed rotation before the joint in the z-axis frames, F_i = P_(i-1)^T M_i P_i. */
    double f[3][3];
    /* Zero offset (rad). */
    double zero_offset;
    /* Harmonic error of the raw angle t: s1 sin t + c1 cos t + s2 sin 2t + c2 cos 2t. */
    double s1, c1, s2, c2;
    /* The link after the joint (the last one with the probe on it), mm, and its thermal
     * rate (mm/°C): link + rate * (T - 20 °C). */
    double link[3], rate[3];
    /* Gravity compliance (rad/mm), 0 for none. */
    double gravity;
};
#endif
