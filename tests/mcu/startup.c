/*
 * startup.c -- minimal bare-metal runtime for the MPS2 images (qemu
 * mps2-an385 / mps2-an386): vector table, reset handler (.data copy, .bss
 * clear, main), fault handlers, semihosting output and exit, and the
 * memcpy/memset the compiler may call.  No newlib, no stdio.
 *
 * Semihosting (Arm): r0 = operation, r1 = argument, then `bkpt 0xab` on
 * M-profile.  SYS_WRITE0 (0x04) prints a NUL-terminated string; SYS_EXIT
 * (0x18) with ADP_Stopped_ApplicationExit makes qemu exit 0, any other
 * reason (we use ADP_Stopped_RunTimeErrorUnknown) makes it exit 1.
 *
 * Built with -fno-builtin -fno-tree-loop-distribute-patterns so the memcpy
 * and memset loops below are not turned back into calls to themselves.
 */
#include <stddef.h>
#include <stdint.h>

#include "mcu_platform.h"

#define SYS_WRITE0 0x04u
#define SYS_EXIT 0x18u
#define ADP_Stopped_ApplicationExit 0x20026u
#define ADP_Stopped_RunTimeErrorUnknown 0x20023u

extern uint32_t __data_load[], __data_start[], __data_end[];
extern uint32_t __bss_start[], __bss_end[];
extern uint32_t __stack_top[], __stack_limit[];

int main(void);
void Reset_Handler(void);
void Fault_Handler(void);
void Default_Handler(void);

static uint32_t semihost(uint32_t op, const void *arg)
{
    register uint32_t r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

void ct_plat_puts(const char *s) { (void)semihost(SYS_WRITE0, s); }

void ct_plat_exit(int pass)
{
    /* AArch32 SYS_EXIT: r1 holds the reason code itself, not a pointer. */
    uintptr_t reason = pass ? ADP_Stopped_ApplicationExit : ADP_Stopped_RunTimeErrorUnknown;
    (void)semihost(SYS_EXIT, (const void *)reason);
    for (;;) {
        /* not reached under qemu; a debugger-less board would stop here */
    }
}

/* ---- stack painting ---------------------------------------------------- */
#define PAINT 0x5AA5C33Cu
static uintptr_t paint_sp; /* caller's SP at paint time */

static uintptr_t current_sp(void)
{
    uintptr_t sp;
    __asm__ volatile("mov %0, sp" : "=r"(sp));
    return sp;
}

__attribute__((noinline)) void ct_plat_stack_paint(void)
{
    /* This function's own frame lies just below the caller's SP; paint from
     * 128 bytes below our SP down to the stack limit.  The caller's SP is
     * at most a few words above ours (this frame is tiny).               */
    uintptr_t sp = current_sp();
    uint32_t *p = (uint32_t *)((sp - 128u) & ~(uintptr_t)3u);
    paint_sp = sp;
    while (p > __stack_limit) {
        *--p = PAINT;
    }
}

unsigned ct_plat_stack_used(void)
{
    const uint32_t *p = __stack_limit;
    while ((uintptr_t)p < paint_sp - 128u && *p == PAINT) {
        ++p;
    }
    return (unsigned)(paint_sp - (uintptr_t)p);
}

void *memcpy(void *dst, const void *src, size_t n)
{
    uint8_t *d = (uint8_t *)dst;
    const uint8_t *s = (const uint8_t *)src;
    while (n-- != 0u) {
        *d++ = *s++;
    }
    return dst;
}

void *memset(void *dst, int c, size_t n)
{
    uint8_t *d = (uint8_t *)dst;
    while (n-- != 0u) {
        *d++ = (uint8_t)c;
    }
    return dst;
}

void Reset_Handler(void)
{
    uint32_t *src = __data_load, *dst = __data_start;
    while (dst < __data_end) {
        *dst++ = *src++;
    }
    for (dst = __bss_start; dst < __bss_end; ++dst) {
        *dst = 0u;
    }
    ct_plat_exit(main() == 0);
}

void Fault_Handler(void)
{
    ct_plat_puts("FAIL: hard fault\n");
    ct_plat_exit(0);
}

void Default_Handler(void)
{
    ct_plat_puts("FAIL: unexpected exception\n");
    ct_plat_exit(0);
}

/* Cortex-M vector table: initial SP, reset, NMI, HardFault, MemManage,
 * BusFault, UsageFault, 4 reserved, SVCall, DebugMon, reserved, PendSV,
 * SysTick.  No peripheral interrupts are enabled. */
typedef void (*ct_vector)(void);
__attribute__((section(".vectors"), used)) const ct_vector ct_vector_table[16] = {
    (ct_vector)(uintptr_t)__stack_top,
    Reset_Handler,
    Default_Handler, /* NMI */
    Fault_Handler,   /* HardFault */
    Fault_Handler,   /* MemManage */
    Fault_Handler,   /* BusFault */
    Fault_Handler,   /* UsageFault */
    0, 0, 0, 0,
    Default_Handler, /* SVCall */
    Default_Handler, /* DebugMon */
    0,
    Default_Handler, /* PendSV */
    Default_Handler, /* SysTick */
};
