/*
 * bad_flight.c -- deliberately breaks the flight rules (heap, stdio,
 * floating point, a test hook's symbol) while compiling cleanly with the
 * flight flags and the warning set.  tests/mcu/check_symbols.py must reject the archive built
 * from it (test mcu_symbols_selftest_*).  Not part of any product.
 */
#include <stddef.h>
#include <stdint.h>

void *malloc(size_t n);
void free(void *p);
int printf(const char *fmt, ...);

double ct_bad_mean(const int32_t *v, int32_t n);
int32_t ct_bad_scale(int32_t v, float f);
int32_t ct_earth_pieces(int32_t v);

double ct_bad_mean(const int32_t *v, int32_t n)
{
    double *acc = (double *)malloc(sizeof *acc);
    double r;
    int32_t i;
    if (acc == NULL) {
        return 0.0;
    }
    *acc = 0.0;
    for (i = 0; i < n; ++i) {
        *acc += (double)v[i];
    }
    r = *acc / (double)n;
    (void)printf("mean %d\n", (int)r);
    free(acc);
    return r;
}

int32_t ct_bad_scale(int32_t v, float f)
{
    return (int32_t)((float)v * f);
}

/* named as earth.c's test hook, which a flight build must not define */
int32_t ct_earth_pieces(int32_t v)
{
    return v + 1;
}
