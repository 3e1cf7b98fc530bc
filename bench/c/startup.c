/* The smallest start a Cortex-M4F image needs under QEMU mps2-an386: the vector table, the
 * FPU switched on before any float instruction, .data copied and .bss zeroed, then main;
 * semihosting for output and for the exit code (QEMU's own exit status), as the Rust
 * boards do (boards/common/src/qemu.rs). */
#include <stdint.h>
#include "bench.h"

extern uint32_t _stack_top, _data_load, _data_start, _data_end, _bss_start, _bss_end;
extern int main(void);
void reset_handler(void);

static void fault_handler(void) { semihost_exit(1); }

__attribute__((section(".vectors"), used)) static void (*const vectors[16])(void) = {
    (void (*)(void))&_stack_top,
    reset_handler,
    fault_handler, /* NMI */
    fault_handler, /* HardFault */
    fault_handler, /* MemManage */
    fault_handler, /* BusFault */
    fault_handler, /* UsageFault */
};

void reset_handler(void) {
    /* CPACR: full access to CP10 and CP11 (the FPU). */
    *(volatile uint32_t *)0xE000ED88 |= 0xFu << 20;
    __asm volatile("dsb\n isb" ::: "memory");
    uint32_t *src = &_data_load, *dst = &_data_start;
    while (dst < &_data_end) *dst++ = *src++;
    for (dst = &_bss_start; dst < &_bss_end;) *dst++ = 0;
    semihost_exit(main());
}

static int semihost(int op, const void *arg) {
    register int r0 __asm("r0") = op;
    register const void *r1 __asm("r1") = arg;
    __asm volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

void semihost_write(const char *s) { semihost(0x04 /* SYS_WRITE0 */, s); }

void semihost_exit(int code) {
    /* SYS_EXIT: ADP_Stopped_ApplicationExit is QEMU's exit status 0, RunTimeErrorUnknown 1. */
    semihost(0x18, (const void *)(uintptr_t)(code == 0 ? 0x20026 : 0x20023));
    for (;;) {
    }
}
