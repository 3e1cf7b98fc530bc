/* What main.c, startup.c and each chain share: semihosting output and exit, and the one
 * function each chain file defines (one chain an image: the build picks the file). */
#ifndef BENCH_H
#define BENCH_H
#include <stdint.h>

void semihost_write(const char *s);
void semihost_exit(int code) __attribute__((noreturn));

/* Forms the chain's constants from the generated calibration (cal.h), once at boot. */
void chain_init(void);

/* The probe-ball centre (mm, out[0..3]) and the probe's direction (out[3..6]) at encoder
 * counts `counts` (one a joint) and temperature `temp_mc` (m°C): 0, or the 1-based joint
 * whose count is out of range (nothing written then). */
int chain_eval(const uint32_t *counts, int32_t temp_mc, float out[6]);

/* The chain's name, printed in the log. */
extern const char chain_name[];
#endif
