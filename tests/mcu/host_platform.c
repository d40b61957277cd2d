/* host_platform.c -- the platform layer of mcu_main.c for the host replay
 * (same vectors, host compiler, portable 128-bit library build). */
#include <stdio.h>
#include <stdlib.h>

#include "mcu_platform.h"

void ct_plat_puts(const char *s) { fputs(s, stdout); }

void ct_plat_exit(int pass)
{
    fflush(stdout);
    exit(pass ? 0 : 1);
}

void ct_plat_stack_paint(void) {}

unsigned ct_plat_stack_used(void) { return 0u; }
