#!/usr/bin/python3
"""Checks that every relative link in README.md and docs/*.md resolves.

A link [text](target) or image ![alt](target) whose target is not a URL must name a file or
folder that exists (relative to the page that holds it), and a `#anchor` must name a heading
of the target page (GitHub's rule: lower case, punctuation dropped, spaces to '-', repeats
numbered -1, -2, ...). Links inside fenced code blocks are ignored.

Usage: scripts/check_links.py [REPO]   (default: the repository holding this script)
Exit status: 0 when every link resolves, 1 otherwise (each broken link printed as
FILE:LINE: target: reason), 2 on a usage error.
"""
import os
import re
import sys

LINK = re.compile(r"!?\[(?:[^\]\[]|\[[^\]]*\])*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
FENCE = re.compile(r"^\s*(```|~~~)")


def strip_code_spans(line):
    """Returns the line with inline code spans blanked (links inside them are not links)."""
    return re.sub(r"`[^`]*`", lambda m: " " * len(m.group(0)), line)


def anchors_of(path, cache):
    """Returns the set of GitHub heading anchors of the markdown file at path."""
    if path in cache:
        return cache[path]
    seen = {}
    result = set()
    in_fence = False
    with open(path, encoding="utf-8") as f:
        for line in f:
            if FENCE.match(line):
                in_fence = not in_fence
                continue
            if in_fence:
                continue
            m = re.match(r"^(#{1,6})\s+(.*?)\s*#*\s*$", line)
            if not m:
                continue
            text = m.group(2).lower()
            text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", text)  # a link's text only
            slug = re.sub(r"[^\w\- ]", "", text, flags=re.UNICODE).replace(" ", "-")
            n = seen.get(slug, 0)
            seen[slug] = n + 1
            result.add(slug if n == 0 else "%s-%d" % (slug, n))
    cache[path] = result
    return result


def check_file(path, cache):
    """Returns the broken links of one markdown file as printable lines."""
    errors = []
    in_fence = False
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            if FENCE.match(line):
                in_fence = not in_fence
                continue
            if in_fence:
                continue
            for m in LINK.finditer(strip_code_spans(line)):
                target = m.group(1)
                if re.match(r"^[a-z][a-z0-9+.-]*:", target):  # http:, https:, mailto:
                    continue
                file_part, _, anchor = target.partition("#")
                where = path
                if file_part:
                    where = os.path.normpath(os.path.join(os.path.dirname(path), file_part))
                    if not os.path.exists(where):
                        errors.append("%s:%d: %s: no such file" % (path, number, target))
                        continue
                if anchor:
                    if not where.endswith(".md") or os.path.isdir(where):
                        errors.append("%s:%d: %s: anchor on a non-markdown target" %
                                      (path, number, target))
                    elif anchor not in anchors_of(where, cache):
                        errors.append("%s:%d: %s: no heading with that anchor" %
                                      (path, number, target))
    return errors


def main():
    """Checks README.md and docs/*.md of the repository; prints the broken links."""
    if len(sys.argv) > 2:
        print(__doc__.strip(), file=sys.stderr)
        return 2
    repo = sys.argv[1] if len(sys.argv) == 2 else os.path.dirname(
        os.path.dirname(os.path.abspath(__file__)))
    pages = [os.path.join(repo, "README.md")]
    docs = os.path.join(repo, "docs")
    pages += sorted(os.path.join(docs, n) for n in os.listdir(docs) if n.endswith(".md"))
    cache = {}
    errors = []
    for page in pages:
        errors += check_file(os.path.relpath(page), cache) if os.path.exists(page) else [
            "%s: missing" % page
        ]
    for e in errors:
        print(e)
    print("check_links: %d page(s), %d broken link(s)" % (len(pages), len(errors)))
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
