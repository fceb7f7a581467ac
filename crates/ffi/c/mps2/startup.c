/* The bare-metal side of the replay: QEMU's mps2-an386 (Cortex-M4F), no C library.
 *
 * A vector table, a reset handler that copies .data, clears .bss and enables the FPU, then
 * replay() over the vector QEMU's loader put at 0x21000000 (`-device loader`), output and exit
 * code through semihosting, SysTick as the tick counter (25 MHz; under `-icount shift=3` one tick
 * is 5 instructions), and the stack painted at reset so the run's peak can be read. A HardFault or a panic inside tcomp (tcomp_panic_hook) ends the run with a
 * failure exit code, as the Rust firmware's smoke run does.
 */
#include "../replay.h"

#include <stdint.h>

#include "tcomp.h"

#define VECTOR_ADDR 0x21000000u
#define VECTOR_MAX (16u << 20)

/* Semihosting: SYS_WRITE0 (0x04) and SYS_EXIT (0x18), `bkpt 0xAB` on M-profile. */
static int semihost(int op, const void *arg) {
    register int r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

static void sh_write(const char *text) { semihost(0x04, text); }

static void __attribute__((noreturn)) sh_exit(int ok) {
    /* ADP_Stopped_ApplicationExit: QEMU exits 0; ADP_Stopped_RunTimeErrorUnknown: 1. */
    semihost(0x18, (const void *)(uintptr_t)(ok ? 0x20026u : 0x20023u));
    for (;;) {
    }
}

/* SysTick: free-running 24-bit down counter on the core clock. */
#define SYST_CSR (*(volatile uint32_t *)0xE000E010u)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014u)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018u)

static uint32_t systick_now(void) { return SYST_CVR; }
static uint32_t systick_elapsed(uint32_t t0, uint32_t t1) { return (t0 - t1) & 0x00FFFFFFu; }

/* The library's panic handler calls this (see tcomp.h): report and stop. */
void tcomp_panic_hook(const uint8_t *file, size_t file_len, uint32_t line) {
    static char msg[200] = "PANIC in tcomp at ";
    size_t at = 18;
    for (size_t i = 0; i < file_len && at < sizeof msg - 16; i++) msg[at++] = (char)file[i];
    msg[at++] = ':';
    char digits[10];
    int d = 0;
    do {
        digits[d++] = (char)('0' + line % 10);
        line /= 10;
    } while (line && d < 10);
    while (d) msg[at++] = digits[--d];
    msg[at++] = '\n';
    msg[at] = 0;
    sh_write(msg);
    sh_exit(0);
}

extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _estack;

/* The top 64 KiB of RAM (the stack's) is painted at reset; the lowest word no longer holding the
 * paint is the deepest the stack went. */
#define PAINT 0xA5C3A5C3u
#define PAINTED (64u << 10)

static uint32_t stack_peak(void) {
    const uint32_t *w = (const uint32_t *)((uintptr_t)&_estack - PAINTED);
    while (w < &_estack && *w == PAINT) w++;
    return (uint32_t)((uintptr_t)&_estack - (uintptr_t)w);
}

int main(void) {
    SYST_RVR = 0x00FFFFFFu;
    SYST_CVR = 0;
    SYST_CSR = 5; /* enable, core clock, no interrupt */
    replay_platform_t p = {sh_write, systick_now, systick_elapsed, stack_peak};
    return replay((const uint8_t *)VECTOR_ADDR, VECTOR_MAX, &p);
}

void Reset_Handler(void) {
    /* The FPU first: the library is built for the hard-float ABI. */
    *(volatile uint32_t *)0xE000ED88u |= 0xFu << 20; /* CPACR: CP10, CP11 full access */
    __asm__ volatile("dsb\n isb" ::: "memory");
    for (uint32_t *s = &_sidata, *d = &_sdata; d < &_edata;) *d++ = *s++;
    for (uint32_t *d = &_sbss; d < &_ebss;) *d++ = 0;
    uint32_t sp;
    __asm__ volatile("mov %0, sp" : "=r"(sp));
    for (uint32_t *w = (uint32_t *)((uintptr_t)&_estack - PAINTED); (uintptr_t)w < sp - 64; w++) *w = PAINT;
    sh_exit(main());
}

static void HardFault_Handler(void) {
    sh_write("HardFault\n");
    sh_exit(0);
}

static void Default_Handler(void) {
    sh_write("unexpected exception\n");
    sh_exit(0);
}

__attribute__((section(".isr_vector"), used)) static void (*const vectors[16])(void) = {
    (void (*)(void))(&_estack),
    Reset_Handler,
    Default_Handler,   /* NMI */
    HardFault_Handler, /* HardFault */
    Default_Handler,   /* MemManage */
    Default_Handler,   /* BusFault */
    Default_Handler,   /* UsageFault */
    0, 0, 0, 0,
    Default_Handler, /* SVCall */
    Default_Handler, /* DebugMon */
    0,
    Default_Handler, /* PendSV */
    Default_Handler, /* SysTick */
};
