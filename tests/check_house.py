"""The house rules of the source tree, checked by `make test`:

- a room is a folder holding sources (solver/pde, solver/recon, io, kernels, ...);
  the includes between rooms form no cycle (a room may use the rooms below it only);
- every project include names its file from the repository root ("solver/base/lsm_grid.h"),
  so that the dependency is visible where it is made (the OpenCL-compiled kernels/
  headers, which the OpenCL compiler reads beside each other, excepted);
- no source file in solver/, kernels/ or io/ is over 800 lines;
- nothing refers to the shared folder beside the repository (a parent-relative path to
  it: the repository must stand alone).

    /usr/bin/python3 tests/check_house.py [ROOT]

Prints what breaks a rule and exits 1, or prints a one-line summary and exits 0.
"""
import os
import re
import subprocess
import sys

MAX_LINES = 800
# The folder beside the repository that nothing may use (spelled in parts so that this
# file does not name it itself).
OUTSIDE = "/".join(["..", "shared"])
SOURCE_ROOTS = ("solver/", "kernels/", "io/")
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def tracked(root):
    out = subprocess.run(["git", "-C", root, "ls-files", "-co", "--exclude-standard"],
                         capture_output=True, text=True, check=True).stdout
    return sorted(f for f in out.split() if os.path.isfile(os.path.join(root, f)))


def cycles(graph):
    """Every cycle's rooms, found by depth-first search (one per back edge)."""
    found, state, stack = [], {}, []

    def visit(node):
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == 1:
                found.append(stack[stack.index(nxt):] + [nxt])
            elif nxt not in state:
                visit(nxt)
        stack.pop()
        state[node] = 2

    for node in sorted(graph):
        if node not in state:
            visit(node)
    return found


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else "."
    files = tracked(root)
    problems = []
    graph = {}
    sources = [f for f in files if f.endswith((".c", ".h", ".cl")) and f.startswith(SOURCE_ROOTS)]
    for f in sources:
        text = open(os.path.join(root, f), encoding="utf-8", errors="replace").read()
        lines = text.count("\n")
        if lines > MAX_LINES:
            problems.append("%s: %d lines (at most %d)" % (f, lines, MAX_LINES))
        room = os.path.dirname(f)
        for inc in INCLUDE.findall(text):
            if inc.startswith(SOURCE_ROOTS) and os.path.isfile(os.path.join(root, inc)):
                other = os.path.dirname(inc)
                if other != room:
                    graph.setdefault(room, set()).add(other)
            elif room == "kernels" and os.path.isfile(os.path.join(root, room, inc)):
                continue  # OpenCL-compiled headers include their neighbours by name
            elif os.path.isfile(os.path.join(root, room, inc)) or "/" in inc and not inc.startswith("build"):
                problems.append('%s: include "%s" does not name the file from the repository root'
                                % (f, inc))
    for cycle in cycles(graph):
        problems.append("include cycle between rooms: " + " -> ".join(cycle))
    for f in files:
        if f.endswith((".png", ".tif", ".tiff", ".nrrd", ".gz")):
            continue
        try:
            text = open(os.path.join(root, f), encoding="utf-8").read()
        except (UnicodeDecodeError, OSError):
            continue
        if OUTSIDE in text:
            problems.append("%s: refers to %s, a folder outside the repository" % (f, OUTSIDE))
    for p in problems:
        print("house: " + p)
    if problems:
        return 1
    print("house: %d sources in %d rooms, no cycle between rooms, none over %d lines"
          % (len(sources), len({os.path.dirname(f) for f in sources}), MAX_LINES))
    return 0


if __name__ == "__main__":
    sys.exit(main())
