#!/usr/bin/env python3
"""Fails when the firmware's modules include each other in a cycle.

A module is a .c file and its .h (drivers/uart.c + drivers/uart.h = drivers/uart); a module depends on every
module whose header it includes, from its .c or its .h. Dependencies must run one way (hal and core at the
bottom, then protocol, drivers, modules, app): a cycle means two modules cannot be understood, tested or
replaced without each other (as comm and locomotion once were). Includes resolve like the compilers' -I. and
-Iprotocol; system headers (<...>) are ignored.

    python3 tools/include_cycles.py <firmware dir>      exit 1 and print each cycle found
"""
import re
import sys
from pathlib import Path

INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)
SEARCH = [".", "protocol"]  # the build's -I paths, after the including file's own folder


def module_of(path, root):
    return str(path.relative_to(root).with_suffix(""))


def graph(root):
    files = [p for p in root.rglob("*") if p.suffix in (".c", ".h") and "build" not in p.relative_to(root).parts]
    edges = {}
    for f in files:
        src = module_of(f, root)
        edges.setdefault(src, set())
        for name in INCLUDE.findall(f.read_text(errors="replace")):
            for base in [f.parent] + [root / s for s in SEARCH]:
                target = (base / name).resolve()
                if target.exists():
                    dst = module_of(target, root.resolve())
                    if dst != src:
                        edges[src].add(dst)
                    break
    return edges


def cycles(edges):
    """Strongly connected components of more than one module (Tarjan), each as a sorted list."""
    index, low, on_stack, stack, out = {}, {}, set(), [], []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in sorted(edges.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    sys.setrecursionlimit(10000)
    for v in sorted(edges):
        if v not in index:
            visit(v)
    return out


def main():
    root = Path(sys.argv[1] if len(sys.argv) > 1 else ".").resolve()
    edges = graph(root)
    found = cycles(edges)
    if found:
        print("include cycles among firmware modules (dependencies must run one way):")
        for comp in found:
            members = set(comp)
            detail = "; ".join(f"{m} -> {', '.join(sorted(edges[m] & members))}" for m in comp)
            print(f"  {' <-> '.join(comp)}: {detail}")
        sys.exit(1)
    print(f"include graph: {len(edges)} modules, no cycle")


if __name__ == "__main__":
    main()
