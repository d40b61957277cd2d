/* platform_mps2.c -- example_print() on the Arm MPS2 board under qemu: the
 * semihosting output of the board support in tests/mcu/startup.c (which
 * also holds the vector table and calls main, then exits qemu with main's
 * verdict).  A real target prints to its UART or telemetry instead. */
#include "mcu_platform.h"

void example_print(const char *s);
void example_print(const char *s) { ct_plat_puts(s); }
