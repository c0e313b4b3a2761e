#!/usr/bin/env python3
"""Layout check of a Rust crate's `src`: import circles and long functions.

Usage:
    python3 tools/layout-check.py [--max-fn-lines N] [--report-fn-lines N]
                                  [--include-tests] SRC_DIR...

For each SRC_DIR (e.g. `crates/cota-core/src`) it prints the module import
graph's circles and every function longer than the report threshold
(default 40 lines), longest first. Exit status: 1 when a circle exists, or
when `--max-fn-lines N` is given and a function is longer than N lines;
2 on bad usage; 0 otherwise. Python 3 standard library only.

# Modules
A module is a file (`a.rs`, or `a/mod.rs` for a folder module `a`, whose
children are the other files of `a/`, or the files of `a/` beside `a.rs`).
The crate root (`lib.rs` or `main.rs`) is the module `crate`. Each module is
one node of the graph: the code of its own file. Test code is left out:
items after `#[cfg(test)]` and modules declared with `#[cfg(test)] mod x;`.

# Edges
Module `A` depends on module `B` when `A`'s code names a path into `B`: a
`use` of `crate::`, `super::` or `self::` paths, or such a path written
inline (`crate::bitree::hierarchy_for(…)`). A path is followed through child
modules as far as they go, then through re-exports (`pub use`, also
`pub(crate) use`) and, for a `pub use …::*`, into the module re-exported,
so `crate::HeightGrid` counts as a use of the module that defines
`HeightGrid`, not of the crate root. Re-exports and `mod` declarations
themselves are declarations, not uses: they make no edge. Comments, doc
links and string literals are ignored.

# Circles
Every edge `A -> B` is looked at from the deepest module `P` that contains
both (a module contains itself and its descendants): it becomes an edge
between `a` and `b`, the children of `P` on the way to `A` and to `B`, where
`P`'s own code (its `mod.rs`, or the crate root) stands for itself. So at each
level the nodes are one module's own code and its children, each child
standing for its whole subtree. A circle is a cycle in any of these graphs:
two siblings (or subtrees) that use each other, directly or around a loop,
or a family's `mod.rs` that uses one of its children while that child (or
anything inside it) uses the `mod.rs`'s own items. A child using its
parent's items is fine as long as the parent's code does not use the child;
a parent using its children is fine as long as they do not use it.

# Functions
A function is `fn name(…) { … }` (free, method or nested), counted from the
line holding `fn` to the line of its closing brace. Test code is left out
unless `--include-tests` is given.
"""

import argparse
import os
import re
import sys

IDENT = r"[A-Za-z_][A-Za-z0-9_]*"


def sanitize(text):
    """Blanks comments, strings and char literals (keeps newlines and length)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if text.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif text.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == "r" and re.match(r'r#*"', text[i:]) and not re.match(r"[A-Za-z0-9_]", text[i - 1 : i] or " "):
            m = re.match(r'r(#*)"', text[i:])
            close = '"' + m.group(1)
            j = text.find(close, i + len(m.group(0)))
            j = n if j < 0 else j + len(close)
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == "'":
            m = re.match(r"'(\\u\{[0-9a-fA-F]+\}|\\.|[^\\'\n])'", text[i:])
            if m:
                out.append(" " * len(m.group(0)))
                i += len(m.group(0))
            else:
                out.append(c)
                i += 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def matching_brace(text, i):
    """Index just after the brace block opening at text[i] == '{'."""
    depth = 0
    for j in range(i, len(text)):
        if text[j] == "{":
            depth += 1
        elif text[j] == "}":
            depth -= 1
            if depth == 0:
                return j + 1
    return len(text)


def strip_tests(code):
    """Removes the item after each `#[cfg(test)]`; returns (code, test modules)."""
    test_mods = set()
    out, pos = [], 0
    for m in re.finditer(r"#\[cfg\(test\)\]", code):
        if m.start() < pos:
            continue
        rest = code[m.end() :]
        decl = re.match(r"\s*(?:#\[[^\]]*\]\s*)*(?:pub(?:\([^)]*\))?\s+)?mod\s+(" + IDENT + r")\s*;", rest)
        if decl:
            test_mods.add(decl.group(1))
            end = m.end() + decl.end()
        else:
            brace = code.find("{", m.end())
            semi = code.find(";", m.end())
            if brace < 0 or (0 <= semi < brace):
                end = semi + 1 if semi >= 0 else len(code)
            else:
                end = matching_brace(code, brace)
        out.append(code[pos : m.start()])
        out.append(re.sub(r"[^\n]", " ", code[m.start() : end]))
        pos = end
    out.append(code[pos:])
    return "".join(out), test_mods


def expand_use(tree):
    """`a::{b, c::{d, e as f}, g::*}` -> [(['a','b'], 'b'), …] (path, name)."""
    tree = re.sub(r"\s+", "", tree)
    results = []

    def split_top(s):
        parts, depth, cur = [], 0, ""
        for ch in s:
            if ch == "," and depth == 0:
                parts.append(cur)
                cur = ""
                continue
            depth += ch == "{"
            depth -= ch == "}"
            cur += ch
        if cur:
            parts.append(cur)
        return parts

    def walk(prefix, s):
        if not s:
            return
        brace = s.find("{")
        if brace >= 0 and (s.find("::") < 0 or brace <= s.rfind("::") + 2):
            head = s[:brace].rstrip(":")
            inner = s[brace + 1 : s.rfind("}")]
            segs = [x for x in head.split("::") if x]
            for part in split_top(inner):
                walk(prefix + segs, part)
            return
        segs = [x for x in s.split("::") if x]
        results.append((prefix + segs, segs[-1] if segs else None))

    walk([], tree)
    return results


def parse_uses(code):
    """Yields (is_pub, [(segments, name)], start offset, end offset)."""
    pat = re.compile(r"(?<![A-Za-z0-9_])(pub(?:\s*\([^)]*\))?\s+)?use\s+([^;]+);")
    for m in pat.finditer(code):
        tree = m.group(2)
        # Aliases: `x as y` -> keep the path, note the new name.
        aliased = []
        for path, name in expand_use(re.sub(r"\s+as\s+(" + IDENT + r")", r"@\1", tree)):
            last = path[-1] if path else ""
            if "@" in last:
                real, alias = last.split("@", 1)
                path = path[:-1] + [real]
                name = alias
            aliased.append((path, name))
        yield (m.group(1) is not None, aliased, m.start(), m.end())


class Module:
    def __init__(self, path, file):
        self.path = path  # tuple of segments, () for the crate root
        self.file = file
        self.children = {}
        self.code = ""
        self.full_code = ""
        self.reexports = {}  # name -> absolute path (list)
        self.globs = []  # absolute paths re-exported with *
        self.items = set()
        self.test = False


def discover(src):
    root_file = None
    for name in ("lib.rs", "main.rs"):
        if os.path.exists(os.path.join(src, name)):
            root_file = os.path.join(src, name)
            break
    if root_file is None:
        sys.exit(f"layout-check: {src}: expected lib.rs or main.rs, found neither")
    mods = {}

    def add(path, file, folder):
        mod = Module(path, file)
        mods[path] = mod
        text = open(file, encoding="utf-8").read()
        code = sanitize(text)
        mod.full_code = code
        code, test_mods = strip_tests(code)
        mod.code = code
        if folder and os.path.isdir(folder):
            for entry in sorted(os.listdir(folder)):
                full = os.path.join(folder, entry)
                if entry.endswith(".rs") and entry != "mod.rs":
                    name = entry[:-3]
                    sub = os.path.join(folder, name)
                    child = add(path + (name,), full, sub)
                    child.test = name in test_mods or mod.test
                    mod.children[name] = child
                elif os.path.isdir(full) and os.path.exists(os.path.join(full, "mod.rs")):
                    child = add(path + (entry,), os.path.join(full, "mod.rs"), full)
                    child.test = entry in test_mods or mod.test
                    mod.children[entry] = child
        return mod

    root = add((), root_file, src)
    return root, mods


def absolute(mod, segs):
    """A use/inline path in `mod` made absolute (None for external crates)."""
    if not segs:
        return None
    head = segs[0]
    if head == "crate":
        return list(segs[1:])
    if head in ("super", "self"):
        base = list(mod.path)
        rest = list(segs)
        while rest and rest[0] in ("super", "self"):
            if rest[0] == "super":
                if not base:
                    return None
                base = base[:-1]
            rest = rest[1:]
        return base + rest
    if head in mod.children:
        return list(mod.path) + list(segs)
    return None


def collect(mods):
    for mod in mods.values():
        for m in re.finditer(
            r"(?m)^\s*(?:pub(?:\([^)]*\))?\s+)?(?:const\s+|async\s+|unsafe\s+)*"
            r"(?:fn|struct|enum|trait|type|const|static|union|macro_rules!)\s+(" + IDENT + ")",
            mod.code,
        ):
            mod.items.add(m.group(1))
        for is_pub, paths, _, _ in parse_uses(mod.code):
            if not is_pub:
                continue
            for segs, name in paths:
                target = absolute(mod, segs)
                if target is None:
                    continue
                if name == "*":
                    mod.globs.append(target[:-1])
                elif name == "self":
                    mod.reexports[target[-2] if len(target) > 1 else ""] = target[:-1]
                else:
                    mod.reexports[name] = target


def resolve(mods, segs, depth=0):
    """The module an absolute path lands in."""
    cur = mods[()]
    i = 0
    while i < len(segs):
        seg = segs[i]
        if seg in cur.children:
            cur = cur.children[seg]
            i += 1
            continue
        if depth < 16 and seg not in cur.items:
            if seg in cur.reexports:
                return resolve(mods, cur.reexports[seg] + segs[i + 1 :], depth + 1)
            for g in cur.globs:
                target = resolve(mods, g, depth + 1)
                if seg in target.items or seg in target.reexports or seg in target.children:
                    return resolve(mods, list(target.path) + segs[i:], depth + 1)
        break
    return cur


def line_of(code, offset):
    return code.count("\n", 0, offset) + 1


def edges_of(mods):
    edges = []  # (from path, to path, line)
    for mod in mods.values():
        if mod.test:
            continue
        code = mod.code
        masked = list(code)
        for is_pub, paths, start, end in parse_uses(code):
            masked[start:end] = re.sub(r"[^\n]", " ", code[start:end])
            if is_pub:
                continue
            for segs, _ in paths:
                target = absolute(mod, segs)
                if target is None:
                    continue
                edges.append((mod.path, resolve(mods, target).path, line_of(code, start)))
        rest = "".join(masked)
        # Inline paths; `mod` declarations are not uses.
        rest = re.sub(r"(?m)^\s*(?:pub(?:\([^)]*\))?\s+)?mod\s+" + IDENT + r"\s*;", "", rest)
        for m in re.finditer(r"(?<![A-Za-z0-9_:])((?:crate|super|self)(?:::" + IDENT + r")+)", rest):
            segs = m.group(1).split("::")
            target = absolute(mod, segs)
            if target is None:
                continue
            edges.append((mod.path, resolve(mods, target).path, line_of(rest, m.start())))
    return edges


def lift(a, b):
    """(level, node_a, node_b): the deepest common module and the two nodes."""
    k = 0
    while k < len(a) and k < len(b) and a[k] == b[k]:
        k += 1
    level = a[:k]
    na = a[: k + 1] if len(a) > k else level
    nb = b[: k + 1] if len(b) > k else level
    return level, na, nb


def sccs(nodes, adj):
    index, low, onstack, stack, out = {}, {}, set(), [], []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        onstack.add(v)
        for w in sorted(adj.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in onstack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                onstack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(nodes):
        if v not in index:
            visit(v)
    return out


def name(path):
    return "crate" if not path else "::".join(path)


def own(path, level):
    return name(path) + ("/mod (own code)" if path == level and path else "")


def circles(mods, edges):
    levels = {}
    where = {}
    for a, b, line in edges:
        if a == b:
            continue
        level, na, nb = lift(a, b)
        if na == nb:
            continue
        levels.setdefault(level, {}).setdefault(na, set()).add(nb)
        where.setdefault((level, na, nb), []).append((a, b, line))
    found = []
    for level, adj in sorted(levels.items()):
        nodes = set(adj) | {x for v in adj.values() for x in v}
        for comp in sccs(nodes, adj):
            inner = []
            for u in comp:
                for v in sorted(adj.get(u, ())):
                    if v in comp:
                        for a, b, line in sorted(set(where[(level, u, v)]))[:3]:
                            inner.append(f"{own(u, level)} -> {own(v, level)}: {mods[a].file}:{line} uses {name(b)}")
            found.append((level, comp, inner))
    return found


def functions(mods, include_tests):
    out = []
    for mod in mods.values():
        if mod.test and not include_tests:
            continue
        code = mod.full_code if include_tests else mod.code
        for m in re.finditer(r"(?<![A-Za-z0-9_])fn\s+(" + IDENT + r")\s*(<[^{;]*?>)?\s*\(", code):
            # The body starts at the first `{` after the signature, unless a
            # `;` comes first (a declaration without a body).
            j, depth = m.end(), 1
            while j < len(code) and depth:
                depth += code[j] == "("
                depth -= code[j] == ")"
                j += 1
            brace, semi = code.find("{", j), code.find(";", j)
            if brace < 0 or (0 <= semi < brace):
                continue
            end = matching_brace(code, brace)
            first, last = line_of(code, m.start()), line_of(code, end - 1)
            out.append((last - first + 1, mod.file, first, m.group(1)))
    return sorted(out, key=lambda x: (-x[0], x[1], x[2]))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("src", nargs="+", help="a crate's src folder")
    ap.add_argument("--report-fn-lines", type=int, default=40, help="list functions longer than this (default 40)")
    ap.add_argument("--max-fn-lines", type=int, help="fail when a function is longer than this")
    ap.add_argument("--include-tests", action="store_true", help="also measure test functions")
    args = ap.parse_args()
    status = 0
    for src in args.src:
        if not os.path.isdir(src):
            print(f"layout-check: {src}: expected a folder, found none", file=sys.stderr)
            return 2
        root, mods = discover(src)
        collect(mods)
        edges = edges_of(mods)
        distinct = {(a, b) for a, b, _ in edges if a != b}
        print(f"{src}: {sum(1 for m in mods.values() if not m.test)} modules, {len(distinct)} import edges")
        found = circles(mods, edges)
        if found:
            status = 1
            print(f"  import circles: {len(found)}")
            for level, comp, inner in found:
                print(f"  - in {name(level)}: {' <-> '.join(own(c, level) for c in comp)}")
                for line in inner:
                    print(f"      {line}")
        else:
            print("  import circles: none")
        threshold = args.report_fn_lines
        if args.max_fn_lines is not None:
            threshold = min(threshold, args.max_fn_lines)
        fns = [f for f in functions(mods, args.include_tests) if f[0] > threshold]
        print(f"  functions over {threshold} lines: {len(fns)}")
        for lines, file, line, fname in fns:
            flag = ""
            if args.max_fn_lines is not None and lines > args.max_fn_lines:
                flag = f"  (over --max-fn-lines {args.max_fn_lines})"
                status = 1
            print(f"    {lines:4d}  {file}:{line} {fname}{flag}")
    return status


if __name__ == "__main__":
    try:
        sys.exit(main())
    except BrokenPipeError:
        sys.exit(0)
