#!/bin/sh
# check_doc_links.sh -- every relative link in README.md and docs/*.md must
# point at an existing file, and a #fragment into a Markdown file at one of
# its headings (GitHub's anchor rule: lower case, punctuation dropped, spaces
# to hyphens).  External links (http:, https:, mailto:) are not followed.
# Usage: tests/check_doc_links.sh [REPO_ROOT]; exits 1 and lists the broken
# links when there are any.
set -eu
ROOT=${1:-$(cd "$(dirname "$0")/.." && pwd)}
exec /usr/bin/python3 - "$ROOT" <<'EOF'
import os, re, sys

root = sys.argv[1]
pages = [os.path.join(root, "README.md")]
docs = os.path.join(root, "docs")
pages += sorted(os.path.join(docs, f) for f in os.listdir(docs) if f.endswith(".md"))

def strip_code(text):
    text = re.sub(r"^```.*?^```", "", text, flags=re.S | re.M)   # fenced blocks
    return re.sub(r"`[^`\n]*`", "", text)                         # inline code

def anchors(path):
    out, seen = set(), {}
    text = re.sub(r"^```.*?^```", "", open(path, encoding="utf-8").read(), flags=re.S | re.M)
    for m in re.finditer(r"^#{1,6}\s+(.*?)\s*#*\s*$", text, flags=re.M):
        slug = m.group(1).strip().lower()
        slug = re.sub(r"[^\w\- ]", "", slug)   # keeps letters, digits, _, -, spaces
        slug = slug.replace(" ", "-")
        n = seen.get(slug, 0)
        seen[slug] = n + 1
        out.add(slug if n == 0 else "%s-%d" % (slug, n))
    return out

bad = 0
checked = 0
for page in pages:
    text = strip_code(open(page, encoding="utf-8").read())
    for m in re.finditer(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)", text):
        target = m.group(1)
        if re.match(r"^[a-z]+:", target):
            continue
        checked += 1
        path, _, frag = target.partition("#")
        dest = os.path.normpath(os.path.join(os.path.dirname(page), path)) if path else page
        rel = os.path.relpath(page, root)
        if not os.path.exists(dest):
            print("%s: %s: no such file" % (rel, target))
            bad += 1
            continue
        if frag and dest.endswith(".md") and frag not in anchors(dest):
            print("%s: %s: no heading with that anchor in %s" % (rel, target, os.path.relpath(dest, root)))
            bad += 1

print("check_doc_links: %d links in %d pages, %d broken" % (checked, len(pages), bad))
sys.exit(1 if bad else 0)
EOF
