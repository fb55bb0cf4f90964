#!/usr/bin/env python3
"""The import graph of Rust source folders, from their `crate::` and
`super::` paths (test modules and comments left out): prints the circles
between files and between top-level folders, and exits 1 if there is one.

    python3 tests/import_circles.py core/src capi/src
"""
import os
import re
import sys


def modules(root):
    """Module path (a tuple) -> file, for every .rs file under `root`."""
    found = {}
    for folder, _, names in os.walk(root):
        for name in names:
            if name.endswith(".rs"):
                path = os.path.join(folder, name)
                parts = os.path.relpath(path, root)[:-3].split("/")
                if parts[-1] in ("mod", "lib"):
                    parts = parts[:-1]
                found[tuple(parts)] = path
    return found


def imports(found):
    """Module -> the modules its non-test code names."""
    def resolve(path):
        for n in range(len(path), 0, -1):
            if tuple(path[:n]) in found:
                return tuple(path[:n])
        return None

    edges = {}
    for module, path in found.items():
        source = open(path).read()
        cut = source.find("#[cfg(test)]\nmod tests")
        source = re.sub(r"//.*", "", source if cut < 0 else source[:cut])
        is_dir = path.endswith("mod.rs") or path.endswith("lib.rs")
        deps = set()
        for m in re.finditer(r"\b(crate|super)((?:::\w+)+)(::\{([^;]*?)\})?", source):
            head, tail = m.group(1), m.group(2).split("::")[1:]
            base = [] if head == "crate" else list(module if is_dir else module[:-1])
            if head == "super" and is_dir:
                base = base[:-1]
            targets = [base + tail]
            for item in re.split(r",\s*", m.group(4) or ""):
                item = item.strip().split("::")
                if item and item[0]:
                    targets.append(base + tail + item)
            for t in targets:
                r = resolve(t)
                if r is not None and r != module:
                    deps.add(r)
        edges[module] = deps
    return edges


def circles(nodes, edges):
    """The strongly connected components of more than one node (Tarjan)."""
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]
    sys.setrecursionlimit(10000)

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                out.append(component)

    for v in nodes:
        if v not in index:
            visit(v)
    return out


def main(roots):
    bad = 0
    for root in roots:
        found = modules(root)
        edges = imports(found)
        folders = {}
        for m, deps in edges.items():
            for d in deps:
                if len(m) > 1 and len(d) > 1 and m[0] != d[0]:
                    folders.setdefault(m[0], set()).add(d[0])
        for kind, comps in (("file", circles(list(found), edges)), ("folder", circles(list(folders), folders))):
            print(f"{root}: {len(comps)} {kind}-level import circles")
            for c in comps:
                print("   ", " <-> ".join(sorted("/".join(m) if isinstance(m, tuple) else m for m in c)))
            bad += len(comps)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
