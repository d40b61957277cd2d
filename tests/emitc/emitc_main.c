/*
 * emitc_main.c -- firmware-style use of a package linked in as C source
 * (`conetrace build --emit-c terrain_pkg`): open it in place, verify it,
 * trace a fixed fan of rays with every method, and print one summary line
 * (size, CRC, counts, a checksum of every result).  Built for the host and
 * for Cortex-M4 (run under qemu); the two lines must be identical.
 * C99, freestanding, no stdio, no float.
 */
#include <stddef.h>
#include <stdint.h>

#include "conetrace.h"
#include "mcu_platform.h"
#include "terrain_pkg.h"

static char g_line[200];
static uint32_t g_len;

static void put_str(const char *s)
{
    while (*s != '\0' && g_len + 1u < sizeof g_line) { /* bound: line size */
        g_line[g_len++] = *s++;
    }
    g_line[g_len] = '\0';
}

static void put_hex(uint64_t v, unsigned digits)
{
    static const char hex[] = "0123456789abcdef";
    unsigned k;
    for (k = digits; k > 0u; --k) { /* bound: digits <= 16 */
        char c[2];
        c[0] = hex[(v >> (4u * (k - 1u))) & 15u];
        c[1] = '\0';
        put_str(c);
    }
}

static uint64_t g_sum = UINT64_C(1469598103934665603);

static void mix(int64_t v)
{
    unsigned k;
    for (k = 0; k < 8u; ++k) { /* bound: 8 bytes */
        g_sum ^= (uint64_t)v >> (8u * k) & 0xffu;
        g_sum *= UINT64_C(1099511628211);
    }
}

int main(void)
{
    ct_package p;
    uint32_t hits = 0u, others = 0u, k, m;
    int ok = 1;
    if (ct_package_open(&p, terrain_pkg, terrain_pkg_SIZE) != CT_OK || ct_package_verify(&p) != CT_OK) {
        ct_plat_puts("emitc: FAIL: the linked package does not open\n");
        ct_plat_exit(0);
    }
    /* a fan of 64 rays from above the tile's corners and edges */
    for (k = 0u; k < 64u; ++k) { /* bound: 64 rays */
        ct_ray r;
        ct_hit h[CT_METHOD_COUNT];
        ct_status s[CT_METHOD_COUNT];
        r.x_q16 = (int64_t)(k % 8u) * (int64_t)p.cells_x * 65536 / 7;
        r.y_q16 = (int64_t)(k / 8u) * (int64_t)p.cells_y * 65536 / 7;
        r.z_q16 = ((int64_t)p.hmax + 200) * 65536;
        r.dx = (int64_t)p.cells_x * 32768 - r.x_q16 + (int64_t)k * 4099;
        r.dy = (int64_t)p.cells_y * 32768 - r.y_q16 - (int64_t)k * 1237;
        r.dz = -((int64_t)(k % 5u) + 1) * ((int64_t)p.hmax - (int64_t)p.hmin + 1) * 32768;
        for (m = 0u; m < (uint32_t)CT_METHOD_COUNT; ++m) { /* bound: 4 methods */
            s[m] = ct_trace(&p, &r, (ct_method)m, &h[m]);
            mix(s[m]);
            mix((int64_t)h[m].steps);
            if (s[m] == CT_HIT || s[m] == CT_HIT_VOID) {
                mix(h[m].x_q16);
                mix(h[m].y_q16);
                mix(h[m].z_q16);
                mix(h[m].e_nm);
                mix(h[m].n_nm);
                mix(h[m].h_nm);
            }
            if (s[m] != s[0] || h[m].x_q16 != h[0].x_q16 || h[m].z_q16 != h[0].z_q16) {
                ok = 0;
            }
        }
        if (s[0] == CT_HIT) {
            hits++;
        } else {
            others++;
        }
    }
    put_str("emitc: size 0x");
    put_hex(p.size, 8u);
    put_str(" crc 0x");
    put_hex((uint64_t)terrain_pkg[12] | (uint64_t)terrain_pkg[13] << 8 | (uint64_t)terrain_pkg[14] << 16 |
                (uint64_t)terrain_pkg[15] << 24,
            8u);
    put_str(" hits 0x");
    put_hex(hits, 2u);
    put_str(" others 0x");
    put_hex(others, 2u);
    put_str(" checksum 0x");
    put_hex(g_sum, 16u);
    put_str(ok ? " PASS\n" : " FAIL (methods disagree)\n");
    ct_plat_puts(g_line);
    ct_plat_exit(ok && hits > 16u);
    return 0;
}
