#!/usr/bin/python3
"""check_rules.py -- source-level flight rules for lib/ (*.c, *.h).

Comments are ignored and string / character literals blanked before
checking.  Rules:

  float    the types float, double, long double, _Complex, _Imaginary,
           floating literals (1.0, .5, 1e9, 0x1p3), <float.h>/<math.h> names
  heap     malloc, calloc, realloc, free, aligned_alloc, alloca
  stdio    printf/scanf families, puts, putchar, FILE, stdin/stdout/stderr,
           fopen, fwrite, ...
  vla      an array declarator whose size uses a non-constant identifier
           (constants are UPPER_CASE macros or enumerators, sizeof, digits)
  include  any header other than <stdint.h>, <stddef.h>, <limits.h> and the
           library's own headers (files present under the checked tree)

  check_rules.py [--selftest FIXTURE_DIR] DIR...

--selftest first proves the checker can fail: every fixture named bad_*.c
must be rejected for each rule listed in its "expect:" line, and every
good_*.c (forbidden words only inside comments and strings) must pass.
"""
import argparse
import os
import re
import sys

ALLOWED_SYSTEM = {'stdint.h', 'stddef.h', 'limits.h'}

RULES = [
    ('float', re.compile(r'\b(float|double|_Complex|_Imaginary|float_t|double_t)\b')),
    ('float', re.compile(r'(?<![\w.])(\d+\.\d*([eE][+-]?\d+)?|\.\d+([eE][+-]?\d+)?|\d+[eE][+-]?\d+)[fFlL]?(?![\w.])')),
    ('float', re.compile(r'(?<![\w.])0[xX][0-9a-fA-F]*\.?[0-9a-fA-F]*[pP][+-]?\d+')),
    ('float', re.compile(r'\b(FLT|DBL|LDBL)_\w+|\b(HUGE_VAL\w*|INFINITY|NAN)\b|'
                         r'\b(sqrt|sin|cos|tan|atan2?|exp|log|log10|pow|floor|ceil|fabs|fmod|round|trunc)[fl]?\s*\(')),
    ('heap', re.compile(r'\b(malloc|calloc|realloc|free|aligned_alloc|alloca|__builtin_alloca\w*|strdup)\s*\(')),
    ('stdio', re.compile(r'\b(v?[fs]?n?printf|v?[fs]?scanf|f?puts|f?putc|putchar|f?getc|getchar|f?gets|'
                         r'fopen|fclose|fread|fwrite|fflush|fseek|ftell|perror|setvbuf)\s*\(|'
                         r'\b(FILE|stdin|stdout|stderr)\b')),
]

DECL_TYPES = (r'(?:(?:const|volatile|static|register|unsigned|signed|struct\s+\w+|union\s+\w+|enum\s+\w+)\s+)*'
              r'(?:u?int(?:8|16|32|64|ptr|max)_t|u?int_(?:least|fast)\d+_t|size_t|ptrdiff_t|char|short|int|long|'
              r'unsigned|signed|ct_\w+|[A-Za-z_]\w*_t)\b')
ARRAY_DECL = re.compile(DECL_TYPES + r'[\s\*]*(?:const\s+)?\w+\s*((?:\[[^\[\]]*\]\s*)+)')
IDENT = re.compile(r'[A-Za-z_]\w*')
INCLUDE = re.compile(r'^[ \t]*#[ \t]*include[ \t]*(.*)$', re.M)


def strip_code(text):
    """Blank comments (keeping newlines) and the contents of string and
    character literals, so only code remains."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith('/*', i):
            j = text.find('*/', i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r'[^\n]', ' ', text[i:j]))
            i = j
        elif text.startswith('//', i):
            j = text.find('\n', i)
            j = n if j < 0 else j
            out.append(' ' * (j - i))
            i = j
        elif c in '"\'':
            j = i + 1
            while j < n and text[j] != c and text[j] != '\n':
                j += 2 if text[j] == '\\' else 1
            out.append(c + ' ' * (min(j, n) - i - 1) + (c if j < n else ''))
            i = j + 1
        else:
            out.append(c)
            i += 1
    return ''.join(out)


def strip_comments_only(text):
    """Comments blanked, literals kept (for #include names)."""
    out, i, n = [], 0, len(text)
    while i < n:
        if text.startswith('/*', i):
            j = text.find('*/', i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r'[^\n]', ' ', text[i:j]))
            i = j
        elif text.startswith('//', i):
            j = text.find('\n', i)
            j = n if j < 0 else j
            out.append(' ' * (j - i))
            i = j
        elif text[i] in '"\'':
            q, j = text[i], i + 1
            while j < n and text[j] != q and text[j] != '\n':
                j += 2 if text[j] == '\\' else 1
            out.append(text[i:j + 1])
            i = j + 1
        else:
            out.append(text[i])
            i += 1
    return ''.join(out)


def line_of(text, pos):
    return text.count('\n', 0, pos) + 1


def check_file(path, own_headers):
    raw = open(path, encoding='utf-8', errors='replace').read()
    code = strip_code(raw)
    found = []
    for kind, rx in RULES:
        for m in rx.finditer(code):
            found.append((kind, line_of(code, m.start()), m.group(0).strip()))
    # VLAs: array declarators whose size is not a constant expression
    for m in ARRAY_DECL.finditer(code):
        for dims in re.findall(r'\[([^\[\]]*)\]', m.group(1)):
            # sizeof operands and casts to type names are constant
            dims = re.sub(r'\bsizeof\s*(\([^()]*\)|\w+)', '1', dims)
            dims = re.sub(r'\b(u?int\w*_t|size_t|ptrdiff_t|char|short|int|long|unsigned|signed)\b', '1', dims)
            for ident in IDENT.findall(dims):
                if ident == 'sizeof' or ident.isupper() or re.match(r'^[A-Z][A-Z0-9_]*$', ident) or \
                        re.match(r'^(U?INT\d+_C|U?INT\d+_MAX|INT\d+_MIN|SIZE_MAX)$', ident):
                    continue
                if re.match(r'^\d', ident):
                    continue
                found.append(('vla', line_of(code, m.start()), m.group(0).strip()))
                break
    # includes
    for m in INCLUDE.finditer(strip_comments_only(raw)):
        spec = m.group(1).strip()
        mm = re.match(r'^[<"]([^>"]+)[>"]', spec)
        if not mm:
            found.append(('include', line_of(raw, m.start()), '#include ' + spec + ' (computed include)'))
            continue
        name = mm.group(1)
        if spec.startswith('<') and name in ALLOWED_SYSTEM:
            continue
        if os.path.basename(name) in own_headers and '..' not in name:
            continue
        found.append(('include', line_of(raw, m.start()), '#include ' + spec))
    return sorted(set(found), key=lambda f: (f[1], f[0]))


def sources(root):
    if os.path.isfile(root):
        return [root]
    out = []
    for dp, dns, fns in os.walk(root):
        dns.sort()
        for fn in sorted(fns):
            if fn.endswith(('.c', '.h')):
                out.append(os.path.join(dp, fn))
    return out


def check_tree(root, own_headers=None, quiet=False):
    files = sources(root)
    if own_headers is None:
        own_headers = {os.path.basename(f) for f in files if f.endswith('.h')}
    report = {}
    for f in files:
        v = check_file(f, own_headers)
        if v:
            report[f] = v
        if not quiet:
            for kind, line, what in v:
                print('%s:%d: [%s] %s' % (f, line, kind, what))
    return files, report


def selftest(fixture_dir):
    ok = True
    files = sources(fixture_dir)
    own = {os.path.basename(f) for f in files if f.endswith('.h')}
    bad = [f for f in files if os.path.basename(f).startswith('bad_')]
    good = [f for f in files if os.path.basename(f).startswith('good_')]
    if not bad or not good:
        print('selftest: FAIL, need bad_*.c and good_*.c fixtures in %s' % fixture_dir)
        return False
    for f in bad:
        text = open(f, encoding='utf-8').read()
        m = re.search(r'expect:\s*([a-z, ]+)', text)
        want = sorted({w.strip() for w in (m.group(1) if m else '').split(',') if w.strip()})
        got = sorted({k for k, _, _ in check_file(f, own)})
        missing = [w for w in want if w not in got]
        if not want or missing:
            print('selftest: FAIL, %s not rejected for: %s (got %s)' % (f, ', '.join(missing or ['?']), got))
            ok = False
        else:
            print('selftest: %s rejected as expected for %s' % (os.path.basename(f), ', '.join(got)))
    for f in good:
        v = check_file(f, own)
        if v:
            for kind, line, what in v:
                print('selftest: FAIL, false positive %s:%d: [%s] %s' % (f, line, kind, what))
            ok = False
        else:
            print('selftest: %s passes as expected' % os.path.basename(f))
    return ok


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--selftest', metavar='FIXTURE_DIR')
    ap.add_argument('dirs', nargs='+')
    args = ap.parse_args()
    status = 0
    if args.selftest and not selftest(args.selftest):
        status = 1
    for d in args.dirs:
        files, report = check_tree(d)
        if not files:
            print('check_rules: FAIL, no sources under %s' % d)
            status = 1
        elif report:
            n = sum(len(v) for v in report.values())
            print('check_rules: FAIL, %d violations in %d of %d files under %s' % (n, len(report), len(files), d))
            status = 1
        else:
            print('check_rules: ok, %d files under %s (no float, heap, stdio, VLAs or foreign includes)' %
                  (len(files), d))
    return status


if __name__ == '__main__':
    sys.exit(main())
