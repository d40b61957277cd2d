#!/usr/bin/python3
"""stack_report.py -- worst-case stack per public function of a cross build.

Walks the call graph GCC writes with -fcallgraph-info=su (one .ci file per
translation unit) from every function declared in the public header and sums
the frame sizes along the deepest path.  Fails (exit 1) on

  * recursion (a cycle in the call graph),
  * a dynamic or unbounded frame ("dynamic" in .su / .ci),
  * an indirect call (__indirect_call) or an unresolved callee -- except
    at the sites in CALLBACK_SITES, where the library calls a function the
    caller gave it (its stack is the caller's to add),
  * a public function without a definition.

Frames:
  * library functions: the -fstack-usage frame, raised to the stack
    adjustment of the function's prologue in the object code when that is
    larger (GCC leaves the "pretend args" area -- the `sub sp, #8` that
    spills a by-value struct argument passed in registers -- out of .su);
  * helper routines the compiler calls (libgcc __aeabi_*, memcpy, ...):
    from the disassembly of an image that links them (--elf), counting every
    push and every `sub sp, #imm` of the routine (an upper bound), following
    its direct calls and tail branches; `blx rN` there is an indirect call.

  stack_report.py --cpu cortex-m0 --header lib/include/conetrace.h \
      --ci <dir or .ci/.su files>... --lib libconetrace.a --elf stack_image.elf \
      [--objdump arm-none-eabi-objdump] [--roots f,g] [--expect recursion,dynamic,indirect]

With --expect the run is a self-test: exit 0 only if every listed kind of
violation was reported.
"""
import argparse
import os
import re
import subprocess
import sys

# The library's only calls through a pointer: the caller's own functions,
# called from these (static) functions.  Their stack adds to the figure of
# every public function above them (docs/library.md says so).
CALLBACK_SITES = {'tile_get': "the caller's ct_tile_loader (tile sets)"}

NODE_RE = re.compile(r'^node: \{ title: "([^"]*)" label: "([^"]*)"(.*)\}\s*$')
EDGE_RE = re.compile(r'^edge: \{ sourcename: "([^"]*)" targetname: "([^"]*)"')
GRAPH_RE = re.compile(r'^graph: \{ title: "([^"]*)"')
FRAME_RE = re.compile(r'(\d+) bytes \(([^)]*)\)')
SU_RE = re.compile(r'^(.*):(\d+):(\d+):(\S+)\t(\d+)\t(\S+)\s*$')


class Violation(Exception):
    pass


def strip_c_comments(text):
    text = re.sub(r'/\*.*?\*/', ' ', text, flags=re.S)
    return re.sub(r'//[^\n]*', ' ', text)


def public_functions(header):
    """Names of the functions declared in the public header."""
    text = strip_c_comments(open(header, encoding='utf-8').read())
    text = re.sub(r'^\s*#.*?(?<!\\)$', ' ', text, flags=re.M | re.S)  # drop preprocessor lines
    names = []
    # a declaration: <type> name ( ... ) ;  at file scope
    for m in re.finditer(r'\b([A-Za-z_]\w*)\s*\(([^;{}()]|\([^()]*\))*\)\s*;', text):
        name = m.group(1)
        before = text[:m.start()].rstrip()
        if name in ('sizeof', 'defined', 'if', 'while', 'for', 'return'):
            continue
        if not re.search(r'[\w\*]$', before):  # needs a return type before it
            continue
        if name not in names:
            names.append(name)
    return names


# ---------------------------------------------------------------- .ci / .su
class Func:
    def __init__(self, title, name, tu, frame, qual):
        self.title, self.name, self.tu, self.frame, self.qual = title, name, tu, frame, qual
        self.su_frame = frame
        self.callees = []
        self.kind = 'lib'
        self.note = ''


def load_ci(paths):
    funcs, edges = {}, []
    for path in paths:
        tu = None
        with open(path, encoding='utf-8', errors='replace') as f:
            for line in f:
                m = GRAPH_RE.match(line)
                if m:
                    tu = m.group(1)
                    continue
                m = NODE_RE.match(line)
                if m:
                    title, label = m.group(1), m.group(2)
                    parts = label.split('\\n')
                    fm = FRAME_RE.search(label)
                    if fm:  # a function with a body in this unit
                        funcs[title] = Func(title, parts[0], tu, int(fm.group(1)), fm.group(2))
                    continue
                m = EDGE_RE.match(line)
                if m:
                    edges.append((m.group(1), m.group(2)))
    for src, dst in edges:
        if src in funcs and dst not in funcs[src].callees:
            funcs[src].callees.append(dst)
    return funcs


def load_su(paths):
    quals = {}
    for path in paths:
        with open(path, encoding='utf-8', errors='replace') as f:
            for line in f:
                m = SU_RE.match(line.rstrip('\n'))
                if m:
                    quals[(os.path.basename(m.group(1)), m.group(4))] = (int(m.group(5)), m.group(6))
    return quals


# ---------------------------------------------------------------- disassembly
INSN_RE = re.compile(r'^\s*([0-9a-f]+):\s+(\S+)\s*(.*)$')
FUNC_RE = re.compile(r'^([0-9a-f]+) <([^>]+)>:\s*$')
MEMBER_RE = re.compile(r'^(\S+):\s+file format')
REG_RANGE_RE = re.compile(r'([a-z]+)(\d+)-[a-z]+(\d+)')


def reg_count(reglist):
    n = 0
    for item in reglist.split(','):
        item = item.strip()
        if not item:
            continue
        m = REG_RANGE_RE.match(item)
        n += int(m.group(3)) - int(m.group(2)) + 1 if m else 1
    return n


def sp_adjust(mnem, ops):
    """Bytes this instruction pushes onto the stack (>= 0), or None."""
    base = mnem.split('.')[0]
    ops = ops.split('@')[0].strip()
    if base == 'push' or (base in ('stmdb', 'stmfd') and ops.startswith('sp!')):
        m = re.search(r'\{([^}]*)\}', ops)
        return 4 * reg_count(m.group(1)) if m else 0
    if base == 'vpush':
        m = re.search(r'\{([^}]*)\}', ops)
        width = 8 if m and m.group(1).strip().startswith('d') else 4
        return width * reg_count(m.group(1)) if m else 0
    if base in ('sub', 'subw', 'subs'):
        m = re.match(r'sp,\s*(?:sp,\s*)?#(\d+)', ops)
        if m:
            return int(m.group(1))
    if base.startswith('str'):
        m = re.search(r'\[sp,\s*#-(\d+)\]!', ops)
        if m:
            return int(m.group(1))
    return None


def is_dynamic_sp(mnem, ops):
    base = mnem.split('.')[0]
    ops = ops.split('@')[0].strip()
    if base in ('sub', 'subs', 'add', 'adds') and re.match(r'sp,\s*(sp,\s*)?(r\d+|ip|fp|sl|lr)\b', ops):
        return True
    if base in ('mov', 'movs') and re.match(r'sp,\s*(r\d+|ip|fp|sl|lr)\b', ops):
        return True
    return False


def is_control(mnem):
    base = mnem.split('.')[0]
    return base in ('b', 'bl', 'blx', 'bx', 'cbz', 'cbnz', 'pop', 'ldm', 'ldmia', 'ldmfd', 'tbb', 'tbh') or \
        re.match(r'^b(eq|ne|cs|hs|cc|lo|mi|pl|vs|vc|hi|ls|ge|lt|gt|le)$', base) is not None


def disassemble(objdump, path):
    out = subprocess.run([objdump, '-d', '--no-show-raw-insn', path], check=True, capture_output=True,
                         text=True).stdout
    funcs = {}  # (member, name) -> list of (mnem, ops)
    member, cur = os.path.basename(path), None
    for line in out.splitlines():
        m = MEMBER_RE.match(line)
        if m:
            member = os.path.basename(m.group(1))
            cur = None
            continue
        m = FUNC_RE.match(line)
        if m:
            cur = []
            funcs[(member, m.group(2))] = cur
            continue
        if cur is None:
            continue
        m = INSN_RE.match(line)
        if m:
            mnem, ops = m.group(2), m.group(3)
            if mnem.startswith('.'):  # literal pool data
                continue
            cur.append((mnem, ops))
    return funcs


def prologue_bytes(insns):
    total = 0
    for mnem, ops in insns:
        if is_control(mnem):
            break
        a = sp_adjust(mnem, ops)
        if a:
            total += a
    return total


class Helper:
    def __init__(self, name, insns):
        self.name = name
        self.frame = 0
        self.callees = []
        self.indirect = False
        self.dynamic = False
        for mnem, ops in insns:
            a = sp_adjust(mnem, ops)
            if a:
                self.frame += a
            if is_dynamic_sp(mnem, ops):
                self.dynamic = True
            base = mnem.split('.')[0]
            if base == 'blx' and re.match(r'(r\d+|ip|lr)\b', ops.strip()):
                self.indirect = True
            m = re.search(r'<([^>+]+)(\+0x[0-9a-f]+)?>', ops)
            if m and (base in ('bl', 'blx', 'b') or re.match(r'^b(eq|ne|cs|hs|cc|lo|mi|pl|vs|vc|hi|ls|ge|lt|gt|le)$',
                                                             base)):
                target = m.group(1)
                if target != name and target not in self.callees:
                    self.callees.append(target)


def load_helpers(objdump, elf):
    """Helper routines of the image, under every name of their address
    (objdump labels one alias, e.g. __udivsi3 for __aeabi_uidiv)."""
    helpers, addr_of = {}, {}
    for (_, name), insns in disassemble(objdump, elf).items():
        helpers.setdefault(name, Helper(name, insns))
    syms = subprocess.run([objdump, '-t', elf], check=True, capture_output=True, text=True).stdout
    by_addr = {}
    # absolute symbols (linker-script constants such as __stack_size =
    # 0x8000) are never call targets: objdump may use one to label an
    # address inside a routine that spans it (a local branch)
    absolute = {line.split()[-1] for line in syms.splitlines() if '*ABS*' in line.split()}
    for h in helpers.values():
        h.callees = [c for c in h.callees if c not in absolute]
    for line in syms.splitlines():
        # 00004a4c g     F .text  0000005c __aeabi_lmul
        parts = line.split()
        if len(parts) >= 4 and re.match(r'^[0-9a-f]{8}$', parts[0]) and \
                any(p.startswith('.text') for p in parts[1:-2]):
            by_addr.setdefault(int(parts[0], 16) & ~1, []).append(parts[-1])
    for names in by_addr.values():
        known = [n for n in names if n in helpers]
        for n in names:
            if n not in helpers and known:
                helpers[n] = helpers[known[0]]
    return helpers


# ---------------------------------------------------------------- the walk
def analyse(funcs, helpers, roots):
    violations = []  # (kind, message)
    by_name = {}
    for f in funcs.values():
        by_name.setdefault(f.name, []).append(f)

    def resolve(title):
        if title in funcs:
            return ('lib', funcs[title])
        if title == '__indirect_call':
            return ('indirect', None)
        if title in helpers:
            return ('helper', helpers[title])
        return ('unresolved', None)

    memo, state = {}, {}

    def worst(key, obj, kind, stack):
        """(bytes, path) of the deepest chain from this node."""
        if key in memo:
            return memo[key]
        if state.get(key) == 'open':
            cyc = stack[stack.index(key):] + [key]
            violations.append(('recursion', 'recursion: ' + ' -> '.join(display(k) for k in cyc)))
            return (0, [])
        state[key] = 'open'
        stack.append(key)
        if kind == 'lib':
            frame, callees = obj.frame, obj.callees
            if obj.qual != 'static':
                violations.append(('dynamic', '%s: %s stack frame (%s)' % (display(key), obj.qual, obj.tu)))
        else:
            frame, callees = obj.frame, obj.callees
            if obj.dynamic:
                violations.append(('dynamic', '%s: stack pointer set from a register' % display(key)))
            if obj.indirect:
                violations.append(('indirect', '%s: indirect call (blx register)' % display(key)))
        best = (0, [])
        for c in callees:
            ck, cobj = c, None
            ckind, cobj = resolve(c)
            if ckind == 'indirect':
                if display(key) not in CALLBACK_SITES:
                    violations.append(('indirect', '%s: indirect call (function pointer)' % display(key)))
                continue
            if ckind == 'unresolved':
                violations.append(('unresolved', '%s: calls %s, which is not in the call graph or the image' %
                                   (display(key), c)))
                continue
            sub = worst(ck, cobj, ckind, stack)
            if sub[0] > best[0]:
                best = sub
        stack.pop()
        state[key] = 'done'
        res = (frame + best[0], [(key, frame)] + best[1])
        memo[key] = res
        return res

    def display(key):
        return key.split(':')[-1]

    table = []
    for r in roots:
        if r in funcs:
            res = worst(r, funcs[r], 'lib', [])
            table.append((r, res[0], res[1]))
        else:
            violations.append(('missing', '%s: declared in the public header but not defined' % r))
            table.append((r, None, []))
    # unique violations, stable order
    seen, uniq = set(), []
    for v in violations:
        if v not in seen:
            seen.add(v)
            uniq.append(v)
    return table, uniq, display


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--cpu', default='?')
    ap.add_argument('--header', help='public header: its functions are the roots')
    ap.add_argument('--roots', help='comma-separated roots instead of --header')
    ap.add_argument('--ci', nargs='+', required=True, help='.ci/.su files or directories holding them')
    ap.add_argument('--lib', help='the archive (prologue check of every frame)')
    ap.add_argument('--elf', help='an image linking the helper routines')
    ap.add_argument('--objdump', default='arm-none-eabi-objdump')
    ap.add_argument('--expect', help='self-test: comma-separated violation kinds that must be reported')
    ap.add_argument('--check-measured', metavar='LOG',
                    help='compare "measured stack NAME: N bytes" lines of a target run with the static bounds; '
                         'exit 1 only if a measurement exceeds its bound')
    args = ap.parse_args()

    ci_files, su_files = [], []
    for p in args.ci:
        if os.path.isdir(p):
            for dp, _, fns in os.walk(p):
                for fn in sorted(fns):
                    if fn.endswith('.ci'):
                        ci_files.append(os.path.join(dp, fn))
                    elif fn.endswith('.su'):
                        su_files.append(os.path.join(dp, fn))
        elif p.endswith('.su'):
            su_files.append(p)
        else:
            ci_files.append(p)
    if not ci_files:
        print('stack_report: no .ci files found in %s (was the build made with -fcallgraph-info=su?)' % args.ci)
        return 1
    if args.lib:  # only units that are members of the archive (ignore stale .ci files)
        members = subprocess.run([args.objdump.replace('objdump', 'ar') if 'objdump' in args.objdump else 'ar',
                                  't', args.lib], capture_output=True, text=True)
        if members.returncode == 0 and members.stdout.strip():
            stems = {re.sub(r'\.(obj|o)$', '', m.strip()) for m in members.stdout.split()}
            ci_files = [f for f in ci_files if re.sub(r'\.ci$', '', os.path.basename(f)) in stems]
            su_files = [f for f in su_files if re.sub(r'\.su$', '', os.path.basename(f)) in stems]
    if not ci_files:
        print('stack_report: no .ci files for the members of %s' % args.lib)
        return 1
    funcs = load_ci(ci_files)
    su = load_su(su_files)
    for f in funcs.values():  # .su and .ci must agree on dynamic frames
        q = su.get((os.path.basename(f.tu or ''), f.name))
        if q and q[1] != 'static' and f.qual == 'static':
            f.qual = q[1]

    # prologue check: raise frames to what the object code actually pushes
    if args.lib:
        dis = disassemble(args.objdump, args.lib)
        by_member = {}
        for (member, name), insns in dis.items():
            stem = re.sub(r'\.(c\.)?(obj|o)$', '', member)
            by_member[(stem, name)] = insns
            by_member.setdefault((stem, re.sub(r'\.\d+$', '', name)), insns)
        for f in funcs.values():
            stem = os.path.splitext(os.path.basename(f.tu or ''))[0]
            insns = by_member.get((stem, f.name))
            if insns is None:
                print('stack_report: note: %s (%s) not found in the object code; using the .su frame' %
                      (f.name, stem))
                continue
            p = prologue_bytes(insns)
            if p > f.frame:
                f.note = '+%d pretend args' % (p - f.frame)
                f.frame = p

    helpers = load_helpers(args.objdump, args.elf) if args.elf else {}
    if args.roots:
        roots = [r for r in args.roots.split(',') if r]
    elif args.header:
        roots = public_functions(args.header)
    else:
        ap.error('--header or --roots is required')
    if not roots:
        print('stack_report: no public functions found')
        return 1

    table, violations, display = analyse(funcs, helpers, roots)

    print('worst-case stack per public function, %s (bytes; -fstack-usage frames along the deepest '
          '-fcallgraph-info path, helper routines from the disassembly)' % args.cpu)
    w = max(len(r) for r, _, _ in table)
    print('  %-*s  %6s  %s' % (w, 'function', 'bytes', 'deepest path (frame bytes)'))
    for r, total, path in table:
        if total is None:
            print('  %-*s  %6s' % (w, r, 'n/a'))
            continue
        chain = ' > '.join('%s(%d)' % (display(k), fr) for k, fr in path)
        print('  %-*s  %6d  %s' % (w, r, total, chain))
    worst_all = max((t for _, t, _ in table if t is not None), default=0)
    print('  %-*s  %6d' % (w, 'max', worst_all))
    notes = sorted({(display(f.title), f.note) for f in funcs.values() if f.note})
    if notes:
        print('  frames raised above .su by the prologue check: ' + ', '.join('%s %s' % n for n in notes))

    kinds = sorted({k for k, _ in violations})
    if args.check_measured:
        bound = {r: t for r, t, _ in table}
        bad, n = 0, 0
        for line in open(args.check_measured, encoding='utf-8', errors='replace'):
            m = re.search(r'measured stack (\w+): (\d+) bytes', line)
            if not m:
                continue
            name, used = m.group(1), int(m.group(2))
            b = bound.get(name)
            n += 1
            if b is None:
                print('measured %s: %d bytes, no static bound' % (name, used))
                bad += 1
            elif used > b:
                print('measured %s: %d bytes EXCEEDS the static bound %d' % (name, used, b))
                bad += 1
            else:
                print('measured %s: %d bytes <= static bound %d' % (name, used, b))
        for kind, msg in violations:
            print('note: VIOLATION [%s] %s' % (kind, msg))
        if n == 0:
            print('stack_report: no measurements in %s' % args.check_measured)
            return 1
        return 1 if bad else 0
    for kind, msg in violations:
        print('VIOLATION [%s] %s' % (kind, msg))
    if args.expect:
        want = [k for k in args.expect.split(',') if k]
        missing = [k for k in want if k not in kinds]
        if missing:
            print('stack_report self-test: FAIL, expected violations not reported: %s' % ', '.join(missing))
            return 1
        print('stack_report self-test: ok, reported %s' % ', '.join(want))
        return 0
    if violations:
        print('stack_report %s: FAIL (%d violations: %s)' % (args.cpu, len(violations), ', '.join(kinds)))
        return 1
    print('stack_report %s: ok (%d public functions, no recursion, no dynamic frames, no indirect calls but '
          'the caller callbacks: %s; their own stack comes on top)' %
          (args.cpu, len(table), ', '.join('%s calls %s' % kv for kv in sorted(CALLBACK_SITES.items()))))
    return 0


if __name__ == '__main__':
    sys.exit(main())
