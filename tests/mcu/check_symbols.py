#!/usr/bin/python3
"""check_symbols.py -- forbidden-symbol check of a cross-built flight library.

For every archive / object given: the external symbols it needs (undefined
and not defined by another member) must all be known-harmless integer or
memory helpers.  Fails (exit 1) on

  heap      malloc, free, calloc, realloc, memalign, sbrk, strdup, ...
  stdio     the printf / scanf families, puts, putchar, fopen, fwrite, ...,
            the newlib reentrancy hooks behind them (_write, _impure_ptr, ...)
  float     soft-float helpers: __aeabi_f* / __aeabi_d* / __aeabi_*2f /
            __aeabi_*2d / __aeabi_[fd]cmp*, the generic libgcc names
            (__addsf3, __muldf3, __floatsisf, __fixdfsi, __extendsfdf2,
            __unordsf2, ...) and libm functions (sqrt, sin, floor, ...)
  hosted    abort, exit, assert, signal, time, errno, getenv, ...
  unknown   anything else not on the allow list (add a genuinely harmless
            integer helper to ALLOW below when a new compiler needs one)
  fpu       (with --objdump) any VFP/FPU instruction in the code
  testhook  a test hook *defined* in the archive (lib/src/bend.h: compiled
            with CT_TEST_HOOKS only, never in a flight build)

For linked images (--image), every *defined* symbol is checked against the
same forbidden patterns (helpers pulled in from libgcc show up there).

  check_symbols.py [--nm arm-none-eabi-nm] [--objdump arm-none-eabi-objdump]
                   [--image file.elf]... [--expect heap,float,stdio] lib.a...

With --expect the run is a self-test: exit 0 only if each listed category
was reported (proves the check can fail).
"""
import argparse
import re
import subprocess
import sys

FORBIDDEN = [
    ('heap', re.compile(r'^_*(malloc|free|calloc|realloc|reallocf|reallocarray|cfree|aligned_alloc|memalign|'
                        r'posix_memalign|valloc|pvalloc|malloc_usable_size|mallinfo|sbrk|brk|strdup|strndup|'
                        r'alloca)(_r)?$')),
    ('heap', re.compile(r'^_*(malloc|free|calloc|realloc)_\w+$|^_*libc_(malloc|free|calloc|realloc)$|'
                        r'^_*(wrap|real)_(malloc|free|calloc|realloc)$|^_Znw|^_Zna|^_Zdl|^_Zda')),
    ('stdio', re.compile(r'^_*v?(f|s|sn|as|d)?i?printf(_r)?$|^_*v?(f|s)?i?scanf(_r)?$|'
                         r'^_*(f?puts|f?putc|putchar|putw|f?getc|getchar|f?gets|getw|ungetc|'
                         r'fopen|fdopen|freopen|fclose|fread|fwrite|fflush|fseek|fseeko|ftell|ftello|rewind|'
                         r'fgetpos|fsetpos|feof|ferror|clearerr|fileno|perror|setvbuf|setbuf|setlinebuf|'
                         r'tmpfile|tmpnam|remove|rename|popen|pclose|'
                         r'write|read|open|close|lseek|fstat|stat|isatty|'
                         r'sfp|srget|swbuf|sflush|smakebuf|swsetup|sinit|impure_ptr|global_impure_ptr|'
                         r'stdin|stdout|stderr)(_r)?$|^_*(putchar|getchar|puts)_unlocked$')),
    ('float', re.compile(r'^__aeabi_[fd]\w*$')),                       # fadd, dmul, fcmpeq, d2iz, f2d, ...
    ('float', re.compile(r'^__aeabi_\w*2[fdh]$')),                     # i2f, ul2d, l2f, ...
    ('float', re.compile(r'^__aeabi_h2f\w*$|^__gnu_[fh]2[fh]\w*$')),
    ('float', re.compile(r'^__(add|sub|mul|div|neg|abs|cmp|eq|ne|lt|le|gt|ge|unord|pow[i]?)'
                         r'[hsdtx]f\d$')),                               # __addsf3, __unorddf2, __powisf2
    ('float', re.compile(r'^__(float|floatun)[sdt]i[hsdtx]f$|^__fix(uns)?[hsdtx]f[sdt]i$|'
                         r'^__(extend|trunc)[hsdtx]f[hsdtx]f\d$|^__(mul|div)[sdtx]c3$')),
    ('float', re.compile(r'^(sqrt|cbrt|sin|cos|tan|asin|acos|atan|atan2|sinh|cosh|tanh|exp|exp2|expm1|log|log2|'
                         r'log10|log1p|pow|floor|ceil|round|lround|llround|trunc|rint|lrint|nearbyint|fabs|'
                         r'fmod|remainder|hypot|ldexp|frexp|modf|scalbn|copysign|fmin|fmax|fma)[fl]?$')),
    ('hosted', re.compile(r'^_*(abort|exit|_Exit|atexit|assert|assert_func|signal|raise|time|clock|getenv|'
                          r'system|errno|errno_location|setjmp|longjmp|qsort|bsearch|rand|srand|'
                          r'stack_chk_fail|stack_chk_guard)$')),
]

ALLOW = re.compile(
    r'^__aeabi_(u?idiv|u?idivmod|u?ldivmod|lmul|llsl|llsr|lasr|lcmp|ulcmp|'
    r'mem(cpy|move|set|clr)[48]?|uread[48]|uwrite[48]|idiv0|ldiv0)$|'
    r'^__gnu_thumb1_case_\w+$|^__gnu_ldivmod_helper$|^__gnu_uldivmod_helper$|'
    r'^__(u?div|u?mod|u?divmod)[sd]i[34]$|^__(clz|ctz|ffs|popcount|parity|bswap)[sd]i2$|'
    r'^__(ashl|ashr|lshr)di3$|^__muldi3$|^__(u?cmp)di2$|^__negdi2$|'
    r'^(memcpy|memmove|memset|memcmp)$')


TESTHOOK = re.compile(r'^ct_earth_(pieces|path_image24|image24)$')


def classify(sym):
    for kind, rx in FORBIDDEN:
        if rx.search(sym):
            return kind
    if ALLOW.search(sym):
        return None
    return 'unknown'


def nm_symbols(nm, path):
    """(defined, undefined) symbol sets over all members."""
    out = subprocess.run([nm, '-g', path], check=True, capture_output=True, text=True).stdout
    defined, undefined = set(), set()
    for line in out.splitlines():
        parts = line.split()
        if len(parts) == 2 and parts[0] in ('U', 'w', 'v'):
            if parts[0] == 'U':
                undefined.add(parts[1])
        elif len(parts) == 3:
            defined.add(parts[2])
    return defined, undefined


def image_symbols(nm, path):
    out = subprocess.run([nm, path], check=True, capture_output=True, text=True).stdout
    syms = set()
    for line in out.splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[1] in 'TtWwDdBbRr':
            syms.add(parts[2])
        elif len(parts) == 2 and parts[0] == 'U':
            syms.add(parts[1])
    return syms


FPU_RE = re.compile(r'^\s*[0-9a-f]+:\s+(v[a-z0-9]+(\.[a-z0-9.]+)?|vmrs|vmsr|fmrx|fmxr|ldc|stc|mcr|mrc)\s', re.M)


def fpu_instructions(objdump, path):
    out = subprocess.run([objdump, '-d', '--no-show-raw-insn', path], check=True, capture_output=True,
                         text=True).stdout
    return sorted({m.group(1) for m in FPU_RE.finditer(out)})


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--nm', default='arm-none-eabi-nm')
    ap.add_argument('--objdump', help='also reject FPU instructions in the code')
    ap.add_argument('--image', action='append', default=[], help='linked image: check its defined symbols')
    ap.add_argument('--expect', help='self-test: comma-separated categories that must be reported')
    ap.add_argument('archives', nargs='*')
    args = ap.parse_args()

    found = []  # (category, file, symbol)
    for path in args.archives:
        defined, undefined = nm_symbols(args.nm, path)
        needs = sorted(undefined - defined)
        print('%s needs: %s' % (path, ' '.join(needs) if needs else '(nothing)'))
        for s in needs:
            kind = classify(s)
            if kind:
                found.append((kind, path, s))
        for s in sorted(defined):
            if TESTHOOK.search(s):
                found.append(('testhook', path, s))
        if args.objdump:
            fpu = fpu_instructions(args.objdump, path)
            for insn in fpu:
                found.append(('fpu', path, insn))
    for path in args.image:
        syms = image_symbols(args.nm, path)
        for s in sorted(syms):
            kind = classify(s)
            if kind and kind != 'unknown':  # an image also holds startup code and our own symbols
                found.append((kind, path, s))

    for kind, path, sym in found:
        print('FORBIDDEN [%s] %s: %s' % (kind, path, sym))
    kinds = sorted({k for k, _, _ in found})
    if args.expect:
        want = [k for k in args.expect.split(',') if k]
        missing = [k for k in want if k not in kinds]
        if missing:
            print('check_symbols self-test: FAIL, not reported: %s' % ', '.join(missing))
            return 1
        print('check_symbols self-test: ok, the bad code was flagged for %s' % ', '.join(want))
        return 0
    if found:
        print('check_symbols: FAIL (%d forbidden symbols: %s)' % (len(found), ', '.join(kinds)))
        return 1
    print('check_symbols: ok (no heap, stdio, floating point, hosted-runtime or test-hook symbols)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
