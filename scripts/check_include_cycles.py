#!/usr/bin/python3
"""Report include cycles between source units of src/ (a unit = foo.h + foo.cpp, named by its path without the
extension). A unit depends on another when its header or source file includes the other's header with a quoted
path under the package name ("relaxed_connectivity/module/name.h", i.e. relative to src/). Exits 1 and prints each cycle when there is one.

Usage: /usr/bin/python3 scripts/check_include_cycles.py [SRC_DIR]
"""
import os
import re
import sys

INCLUDE = re.compile(r'^\s*#\s*include\s+"(?:relaxed_connectivity/)?([^"]+)"', re.M)
SOURCE_EXT = (".h", ".hpp", ".cpp", ".cu", ".cuh")


def units(src):
    found = {}
    for root, _, files in os.walk(src):
        for name in files:
            if name.endswith(SOURCE_EXT):
                path = os.path.relpath(os.path.join(root, name), src)
                found.setdefault(os.path.splitext(path)[0], []).append(os.path.join(root, name))
    return found


def graph(src):
    files = units(src)
    edges = {}
    for unit, paths in files.items():
        deps = set()
        for path in paths:
            with open(path, encoding="utf-8", errors="replace") as f:
                for inc in INCLUDE.findall(f.read()):
                    dep = os.path.splitext(inc)[0]
                    if dep != unit and dep in files:
                        deps.add(dep)
        edges[unit] = sorted(deps)
    return edges


def strongly_connected(edges):
    """Tarjan's algorithm, iterative; returns the components with more than one unit."""
    index, low, on_stack, stack, result, counter = {}, {}, set(), [], [], [0]
    for root in sorted(edges):
        if root in index:
            continue
        work = [(root, iter(edges[root]))]
        index[root] = low[root] = counter[0]
        counter[0] += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, it = work[-1]
            advanced = False
            for nxt in it:
                if nxt not in index:
                    index[nxt] = low[nxt] = counter[0]
                    counter[0] += 1
                    stack.append(nxt)
                    on_stack.add(nxt)
                    work.append((nxt, iter(edges[nxt])))
                    advanced = True
                    break
                if nxt in on_stack:
                    low[node] = min(low[node], index[nxt])
            if advanced:
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    top = stack.pop()
                    on_stack.discard(top)
                    component.append(top)
                    if top == node:
                        break
                if len(component) > 1:
                    result.append(sorted(component))
    return result


def main():
    src = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "src")
    edges = graph(src)
    cycles = strongly_connected(edges)
    for component in cycles:
        links = ["%s -> %s" % (a, b) for a in component for b in edges[a] if b in component]
        print("include cycle: %s (%s)" % (", ".join(component), "; ".join(links)))
    print("%d units, %d include cycles" % (len(edges), len(cycles)))
    return 1 if cycles else 0


if __name__ == "__main__":
    sys.exit(main())
