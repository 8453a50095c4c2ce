#!/usr/bin/env python3
"""Import circles between the modules (files) of one crate: every `crate::a::b` path a file
names (in `use` lines and inline) is an edge to the file that defines the longest module prefix
(`a/b.rs`, `a/b/mod.rs`, `a.rs`, `a/mod.rs`); strongly connected components of more than one
file are circles. Comments are skipped. Usage: scripts/import-cycles.py crates/cbr-render/src
Unit-test modules are left out. Prints each circle (largest first) and exits 1 when one has
more than --max files (default 2)."""
import argparse, os, re, sys

ap = argparse.ArgumentParser()
ap.add_argument("src")
ap.add_argument("--max", type=int, default=2)
a = ap.parse_args()

files = {}
for root, _, names in os.walk(a.src):
    for n in names:
        if n.endswith(".rs"):
            p = os.path.join(root, n)
            files[os.path.relpath(p, a.src)] = p

def module_file(parts):
    for k in range(len(parts), 0, -1):
        base = "/".join(parts[:k])
        for cand in (base + ".rs", base + "/mod.rs"):
            if cand in files:
                return cand
    return None

def self_module(rel):
    m = rel[:-3]
    if m.endswith("/mod"):
        m = m[:-4]
    return m

edges = {f: set() for f in files}
for rel, path in files.items():
    text = open(path, encoding="utf-8").read()
    text = re.sub(r"//[^\n]*", "", text)
    # Unit tests (`#[cfg(test)] mod tests { ... }`, last in a file by convention) are not the
    # architecture: a test may reach any module.
    m = re.search(r"#\[cfg\(test\)\]\s*(pub(\(crate\))?\s+)?mod tests", text)
    if m:
        text = text[: m.start()]
    me = self_module(rel).split("/")
    paths = re.findall(r"crate::((?:\w+::)*\w+)", text)
    # `use crate::{a::b, c}` groups
    for grp in re.findall(r"use crate::\{([^;]*)\};", text, re.S):
        for item in re.split(r",(?![^{]*\})", grp):
            item = item.strip()
            if item:
                paths.append(re.split(r"[:{ ]", item.replace("::{", "::"))[0] if "::" not in item else item.split("::{")[0])
    # `use super::x` relative to this module
    for sp in re.findall(r"super::((?:\w+::)*\w+)", text):
        parent = me[:-1] if not rel.endswith("mod.rs") else me[:-1]
        paths.append("::".join(parent + sp.split("::")) if parent else sp)
    # Paths relative to this module (`use lights::X`, `lights::f()` in deferred/mod.rs): its
    # child modules.
    here = me if rel.endswith("mod.rs") or rel == "lib.rs" else None
    if here is not None:
        prefix = [] if rel == "lib.rs" else here
        for child in re.findall(r"(?<![\w:])(\w+)::", text):
            if module_file(prefix + [child]) not in (None, rel) and child not in ("crate", "super", "self"):
                paths.append("::".join(prefix + [child]))
    for p in paths:
        parts = [x for x in p.split("::") if x and x != "self"]
        t = module_file(parts)
        if t and t != rel:
            edges[rel].add(t)

# Tarjan
index, low, on, stack, out, counter = {}, {}, set(), [], [], [0]
sys.setrecursionlimit(10000)
def strong(v):
    index[v] = low[v] = counter[0]; counter[0] += 1
    stack.append(v); on.add(v)
    for w in edges[v]:
        if w not in index:
            strong(w); low[v] = min(low[v], low[w])
        elif w in on:
            low[v] = min(low[v], index[w])
    if low[v] == index[v]:
        comp = []
        while True:
            w = stack.pop(); on.discard(w); comp.append(w)
            if w == v:
                break
        out.append(sorted(comp))
for v in sorted(edges):
    if v not in index:
        strong(v)
circles = sorted((c for c in out if len(c) > 1), key=len, reverse=True)
print(f"{len(files)} files, {sum(len(e) for e in edges.values())} edges, "
      f"{len(circles)} circles, largest {len(circles[0]) if circles else 0} files")
for c in circles:
    print(f"  {len(c)}: {' '.join(c)}")
sys.exit(1 if circles and len(circles[0]) > a.max else 0)
