#!/usr/bin/env python3
"""Checks that every relative link in README.md and docs/**/*.md resolves.

Usage: check_doc_links.py ROOT        check ROOT/README.md and every ROOT/docs/**/*.md
       check_doc_links.py --self-test  check that a broken link and a missing anchor are found

A link is `[text](target)` or `![alt](target)` outside code (fenced blocks and `inline code`);
links with a scheme (https:, mailto:) are not followed. A target must name an existing file or
folder relative to the page; `page.md#anchor` (or `#anchor` alone) must name a heading of that
page, spelled as GitHub spells heading anchors. Prints one line per broken link
(`file:line: ...`) and exits 1 when there is one, 2 on bad usage, 0 otherwise.
"""
import os
import re
import sys
import tempfile

LINK = re.compile(r"!?\[(?:[^\]\[]|\[[^\]]*\])*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
INLINE_CODE = re.compile(r"`+[^`]*`+")
SCHEME = re.compile(r"^[a-zA-Z][a-zA-Z0-9+.-]*:")


def prose_lines(text):
    """(line number, line with inline code removed, line) for every line outside fenced code."""
    fence = None
    for number, line in enumerate(text.split("\n"), 1):
        stripped = line.lstrip()
        if fence is None and stripped.startswith(("```", "~~~")):
            fence = stripped[:3]
            continue
        if fence is not None:
            if stripped.startswith(fence):
                fence = None
            continue
        yield number, INLINE_CODE.sub("", line), line


def slug(heading):
    """The anchor GitHub gives a heading: lower case, punctuation dropped, spaces to '-'."""
    text = heading.strip().lower().replace("`", "")
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(path, cache):
    if path not in cache:
        with open(path, encoding="utf-8") as f:
            text = f.read()
        found = set()
        seen = {}
        for _, _, line in prose_lines(text):
            match = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
            if match:
                base = slug(match.group(1))
                count = seen.get(base, 0)
                seen[base] = count + 1
                found.add(base if count == 0 else f"{base}-{count}")
        cache[path] = found
    return cache[path]


def check_file(path, cache):
    """Problems with the links of one markdown file, as 'file:line: message' strings."""
    problems = []
    with open(path, encoding="utf-8") as f:
        text = f.read()
    for number, line, _ in prose_lines(text):
        for match in LINK.finditer(line):
            target = match.group(1)
            if SCHEME.match(target):
                continue
            file_part, _, anchor = target.partition("#")
            where = f"{path}:{number}: link '{target}'"
            resolved = os.path.normpath(os.path.join(os.path.dirname(path), file_part)) \
                if file_part else path
            if not os.path.exists(resolved):
                problems.append(f"{where}: {resolved} does not exist")
                continue
            if anchor and resolved.endswith(".md") and os.path.isfile(resolved):
                if anchor not in anchors(resolved, cache):
                    problems.append(f"{where}: {resolved} has no heading with the anchor "
                                    f"'#{anchor}'")
    return problems


def pages(root):
    found = [os.path.join(root, "README.md")]
    for folder, _, names in os.walk(os.path.join(root, "docs")):
        found += [os.path.join(folder, n) for n in sorted(names) if n.endswith(".md")]
    return found


def check_tree(root):
    cache = {}
    problems = []
    for page in pages(root):
        problems += check_file(page, cache)
    return problems


def self_test():
    with tempfile.TemporaryDirectory() as root:
        os.makedirs(os.path.join(root, "docs", "guide"))
        with open(os.path.join(root, "README.md"), "w", encoding="utf-8") as f:
            f.write("# Top\n\n## A `code` heading, here\n\n[ok](docs/guide/a.md#first-part) "
                    "[self](#a-code-heading-here) [url](https://example.org/x)\n"
                    "```\n[inside code](missing.md)\n```\n`[inline](missing.md)`\n")
        with open(os.path.join(root, "docs", "guide", "a.md"), "w", encoding="utf-8") as f:
            f.write("# First part\n\n[up](../../README.md) [gone](b.md) "
                    "[no anchor](../../README.md#nowhere)\n")
        problems = check_tree(root)
    expected = ["link 'b.md'", "link '../../README.md#nowhere'"]
    ok = len(problems) == len(expected) and all(
        any(e in p for p in problems) for e in expected)
    print("\n".join(problems))
    print("self-test:", "ok" if ok else "FAILED (expected exactly the two broken links above)")
    return 0 if ok else 1


def main(argv):
    if len(argv) == 2 and argv[1] == "--self-test":
        return self_test()
    if len(argv) != 2 or not os.path.isfile(os.path.join(argv[1], "README.md")):
        print("usage: check_doc_links.py ROOT (a folder holding README.md) | --self-test",
              file=sys.stderr)
        return 2
    problems = check_tree(argv[1])
    for p in problems:
        print(p)
    print(f"{len(pages(argv[1]))} pages checked, {len(problems)} broken links")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
