"""The documentation's house rules, checked by `make test` (tests/test_house.sh):

- README.md has at most 350 lines (details live in the rooms' READMEs);
- every relative link of the repository's Markdown files, [text](path) or
  [text](path#anchor), names a file or folder of the repository, and an anchor
  names a heading of the file it points into (GitHub's heading slugs). The
  dated records of validation/measurements/ and the fuzz corpora are left out.

    /usr/bin/python3 tests/check_docs.py [ROOT]

Prints what breaks a rule and exits 1, or prints a one-line summary and exits 0.
"""
import os
import re
import subprocess
import sys

README_MAX_LINES = 350
SKIP = ("validation/measurements/", "tests/fuzz/corpus/")
LINK = re.compile(r"\]\(([^)\s]+)\)")
HEADING = re.compile(r"^#{1,6}\s+(.*?)\s*#*\s*$", re.M)
FENCE = re.compile(r"^```.*?^```", re.M | re.S)


def tracked_markdown(root):
    out = subprocess.run(["git", "-C", root, "ls-files", "-co", "--exclude-standard", "*.md"],
                         capture_output=True, text=True, check=True).stdout
    return sorted(f for f in out.split() if not f.startswith(SKIP)
                  and os.path.isfile(os.path.join(root, f)))


def slug(heading):
    """GitHub's anchor of a heading: lower case, markup and punctuation dropped,
    spaces to hyphens."""
    text = re.sub(r"[`*_]", "", heading.strip().lower())
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(path, cache):
    if path not in cache:
        with open(path, encoding="utf-8") as f:
            text = FENCE.sub("", f.read())
        cache[path] = {slug(h) for h in HEADING.findall(text)}
    return cache[path]


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else "."
    problems = []
    with open(os.path.join(root, "README.md"), encoding="utf-8") as f:
        lines = f.read().count("\n")
    if lines > README_MAX_LINES:
        problems.append("README.md: %d lines (at most %d)" % (lines, README_MAX_LINES))
    files = tracked_markdown(root)
    cache, links = {}, 0
    for name in files:
        with open(os.path.join(root, name), encoding="utf-8") as f:
            text = FENCE.sub("", f.read())
        for target in LINK.findall(text):
            if re.match(r"^[a-z]+:", target):
                continue  # http:, https:, mailto:
            links += 1
            path, _, anchor = target.partition("#")
            full = os.path.normpath(os.path.join(root, os.path.dirname(name), path)) if path \
                else os.path.join(root, name)
            inside = os.path.abspath(full)
            if inside != os.path.abspath(root) and \
                    not inside.startswith(os.path.join(os.path.abspath(root), "")):
                problems.append("%s: link %s leaves the repository" % (name, target))
            elif not os.path.exists(full):
                problems.append("%s: link %s names nothing" % (name, target))
            elif anchor and (not full.endswith(".md") or anchor not in anchors(full, cache)):
                problems.append("%s: link %s names no heading" % (name, target))
    for p in problems:
        print("docs: " + p)
    if problems:
        return 1
    print("docs: README.md %d lines (at most %d); %d links in %d Markdown files, all resolve"
          % (lines, README_MAX_LINES, links, len(files)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
