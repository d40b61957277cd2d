/*
 * bad_stack.c -- deliberately breaks the stack rules: recursion, a
 * dynamically sized frame (alloca) and a call through a function pointer.
 * tests/mcu/stack_report.py must report all three (test
 * mcu_stack_selftest_*).  Compiles cleanly with the flight flags.
 */
#include <stddef.h>
#include <stdint.h>

uint32_t ct_bad_fib(uint32_t n);
uint32_t ct_bad_dynamic(uint32_t n);
uint32_t ct_bad_indirect(uint32_t (*fn)(uint32_t), uint32_t v);
uint32_t ct_bad_fine(uint32_t v);

uint32_t ct_bad_fib(uint32_t n)
{
    return n < 2u ? n : ct_bad_fib(n - 1u) + ct_bad_fib(n - 2u);
}

uint32_t ct_bad_dynamic(uint32_t n)
{
    volatile uint8_t *buf = (volatile uint8_t *)__builtin_alloca(n + 1u);
    buf[n] = (uint8_t)n;
    return buf[n];
}

uint32_t ct_bad_indirect(uint32_t (*fn)(uint32_t), uint32_t v)
{
    return fn(v) + 1u;
}

uint32_t ct_bad_fine(uint32_t v)
{
    return v * 3u + 1u;
}
