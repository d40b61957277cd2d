#!/bin/sh
# profile_m4.sh -- Cortex-M4 instructions per function of ct_geolocate
# (bench/m4/profile_m4.c under qemu mps2-an386, single-stepped with the exec
# log, -Os as the flight builds, or CT_M4_OPT; toolchain and flags from
# scripts/m4_common.sh, as bench_m4.sh): the baked scene of bench_m4.sh, the
# effects FX (0 straight, 1 sphere, 2 the true Earth exact, 3 fitted per
# call, 4 a kept map; 5 straight through the 8 px unprojection grid over
# bench_m4's rows of 8 px), N pixels one by one or in one batch (B = 1).  Prints
# the functions with the most executed instructions between the two calls
# of profile_begin, and their total.  Needs the build's ct_gen_m4_data (the
# data bench_m4.sh bakes).
#
#   scripts/profile_m4.sh <build-dir> [FX] [N] [B] [top]
set -u
ROOT=$(cd "$(dirname "$0")/.." && pwd)
. "$ROOT/scripts/m4_common.sh"
BUILD=${1:-$ROOT/build}
FX=${2:-2}
N=${3:-4}
B=${4:-0}
TOP=${5:-30}
if ! m4_tools; then
    echo "profile_m4: ${PREFIX}gcc or $QEMU not found (scripts/deps.sh installs them)" >&2
    exit 1
fi
GEN="$BUILD/bench/ct_gen_m4_data"
[ -x "$GEN" ] || { echo "profile_m4: $GEN missing (build the project first)" >&2; exit 1; }
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
"$GEN" "$OUT/data.c" 100 >/dev/null || { echo "profile_m4: ct_gen_m4_data failed" >&2; exit 1; }
m4_link "$OUT/p.elf" "$ROOT/bench/m4/profile_m4.c" "$OUT/data.c" -DPROFILE_FX="$FX" -DPROFILE_PIXELS="$N" \
    -DPROFILE_BATCH="$B" || { echo "profile_m4: build failed" >&2; exit 1; }
m4_run 1200 "$OUT/p.elf" -singlestep -d exec,nochain -D "$OUT/log" >/dev/null 2>&1
# count each function's executed instructions between the first and the
# second entry into profile_begin (each exec-log line: one instruction)
awk -v top="$TOP" '
    { f = $NF }
    f == "profile_begin" && prev != "profile_begin" { marks++ }
    marks == 1 && f != "profile_begin" { c[f]++; total++ }
    { prev = f }
    END {
        if (total == 0) { print "profile_m4: no profile (the run failed?)"; exit 1 }
        printf "profile_m4: effects %s, %s pixel(s)%s: %d instructions\n", fx, npix, batch == "1" ? " in one batch" : "", total
        n = 0
        for (k in c) { names[++n] = k }
        for (i = 1; i <= n; i++) for (j = i + 1; j <= n; j++) if (c[names[j]] > c[names[i]]) { t = names[i]; names[i] = names[j]; names[j] = t }
        for (i = 1; i <= n && i <= top; i++) printf "%10d %5.1f %%  %s\n", c[names[i]], 100 * c[names[i]] / total, names[i]
    }' fx="$FX" npix="$N" batch="$B" "$OUT/log"
