/*
 * mcu_platform.h -- the two services the vector checker needs from its
 * platform: print a string, and stop with a pass/fail verdict.
 *   Cortex-M (qemu):  startup.c, semihosting SYS_WRITE0 / SYS_EXIT.
 *   host replay:      host_platform.c, stdio / exit code.
 */
#ifndef CT_MCU_PLATFORM_H
#define CT_MCU_PLATFORM_H

void ct_plat_puts(const char *s);
void ct_plat_exit(int pass)
#if defined(__GNUC__)
    __attribute__((noreturn))
#endif
    ;

/* Stack measurement (Cortex-M only; the host replay reports 0): paint the
 * free stack below the caller's frame, then report the deepest byte used
 * since painting, measured from the caller's stack pointer at paint time. */
void ct_plat_stack_paint(void);
unsigned ct_plat_stack_used(void);

#endif /* CT_MCU_PLATFORM_H */
