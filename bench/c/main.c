/* The C baselines' benchmark, timed as the Rust hub's boards/common/src/bench.rs times its
 * chains: under QEMU -icount shift=0 SysTick counts the virtual core clock; a loop of known
 * length gives instructions a tick, the cost of reading the clock is measured the same way
 * and subtracted, each evaluation is timed on its own. The readings are the same recorded
 * ones (readings.h, generated). Each point's result goes out as the bits of its six floats
 * (untimed), for the host to compare with the f64 reference. */
#include "bench.h"
#include "cal.h"
#include "readings.h"

#define SYST_CSR (*(volatile uint32_t *)0xE000E010)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018)
#define LOOP_ITERATIONS 200000u

static inline uint32_t ticks(void) { return SYST_CVR; }
/* Ticks from a to b of the 24-bit down counter. */
static inline uint32_t since(uint32_t a, uint32_t b) { return (a - b) & 0xFFFFFF; }

__attribute__((noinline)) static void counted_loop(uint32_t n) {
    /* subs + bne: two instructions an iteration. */
    __asm volatile("1: subs %0, #1\n bne 1b" : "+r"(n) : : "cc");
}

static char *put_str(char *p, const char *s) {
    while (*s) *p++ = *s++;
    return p;
}
static char *put_u64(char *p, uint64_t v) {
    char tmp[24];
    int n = 0;
    do tmp[n++] = (char)('0' + v % 10), v /= 10;
    while (v);
    while (n) *p++ = tmp[--n];
    return p;
}
static char *put_hex(char *p, uint32_t v) {
    for (int k = 28; k >= 0; k -= 4) *p++ = "0123456789abcdef"[(v >> k) & 15];
    return p;
}

static void log_sum(const char *what, uint64_t points, uint64_t ticks_sum) {
    char line[96], *p = line;
    p = put_str(p, what);
    p = put_u64(p, points);
    p = put_str(p, " points ");
    p = put_u64(p, ticks_sum);
    p = put_str(p, " ticks\n");
    *p = 0;
    semihost_write(line);
}

int main(void) {
    chain_init();
    SYST_RVR = 0xFFFFFF;
    SYST_CVR = 0;
    SYST_CSR = 5; /* core clock, no interrupt, on */

    uint32_t a = ticks();
    counted_loop(LOOP_ITERATIONS);
    uint32_t b = ticks();
    char line[128], *p = line;
    p = put_str(p, "name ");
    p = put_str(p, chain_name);
    p = put_str(p, "\ncalibration loop ");
    p = put_u64(p, 2 * LOOP_ITERATIONS);
    p = put_str(p, " instructions ");
    p = put_u64(p, since(a, b));
    p = put_str(p, " ticks\n");
    *p = 0;
    semihost_write(line);

    uint64_t empty = 0, sum = 0;
    int failures = 0;
    for (int r = 0; r < READINGS; r++) {
        float out[6];
        const uint32_t *counts = reading_counts[r];
        int32_t temp = reading_temp_mc[r];
        __asm volatile("" : : "r"(counts), "r"(temp) : "memory");
        a = ticks();
        b = ticks();
        empty += since(a, b);
        a = ticks();
        int rc = chain_eval(counts, temp, out);
        b = ticks();
        sum += since(a, b);
        failures += rc != 0;
        p = put_str(line, "point ");
        p = put_u64(p, (uint64_t)r);
        *p++ = ' ';
        p = put_u64(p, (uint64_t)rc);
        for (int k = 0; k < 6; k++) {
            union { float f; uint32_t u; } bits = {out[k]};
            *p++ = ' ';
            p = put_hex(p, rc == 0 ? bits.u : 0);
        }
        *p++ = '\n';
        *p = 0;
        semihost_write(line);
    }
    log_sum("clock overhead ", READINGS, empty);
    log_sum("chain ", READINGS, sum);
    return failures ? 1 : 0;
}
