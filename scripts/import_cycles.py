#!/usr/bin/env python3
"""Pairs of files in src/ that import each other.

A file imports another when its code (outside comments, strings and `#[cfg(test)]` modules) names an item of the
other's module: `use crate::a::b::X`, `crate::a::b::f()`, `super::b::X`, `self::c::X` or a child module's name.
A path is resolved to the file of the longest module prefix it names; a name the module re-exports (`pub use
child::X`) is followed to the child that defines it, so a path through a parent's facade counts against the file
that holds the item.

A parent and its child naming each other (the parent declares and re-exports its children; a child uses an item
of its parent) is the module facade Rust is built on and is listed apart from the cycles between files neither of
which contains the other. Test-only modules (`#[cfg(test)] mod tests;` in their own file, inline `#[cfg(test)]
mod ... { }`) are left out: they import their parent by definition.

Usage: python3 scripts/import_cycles.py [SRC_DIR]   (default: src). Exit 1 when two files that do not contain
each other import each other, else 0.
"""

import re
import sys
from pathlib import Path

MOD_DECL = re.compile(
    r'((?:#\[[^\]]*\]\s*)*)(?:pub(?:\([^)]*\))?\s+)?mod\s+(\w+)\s*;')
PATH_REF = re.compile(r'\b((?:crate|super|self|flightid)(?:\s*::\s*\w+)+)')


def strip_code(text):
    """The text with comments, string and char literals blanked (newlines kept)."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith('//', i):
            j = text.find('\n', i)
            i = n if j < 0 else j
        elif text.startswith('/*', i):
            depth, i = 1, i + 2
            while i < n and depth:
                if text.startswith('/*', i):
                    depth, i = depth + 1, i + 2
                elif text.startswith('*/', i):
                    depth, i = depth - 1, i + 2
                else:
                    if text[i] == '\n':
                        out.append('\n')
                    i += 1
        elif c == 'r' and re.match(r'r#*"', text[i:i + 10]) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == '_')):
            hashes = re.match(r'r(#*)"', text[i:]).group(1)
            end = text.find('"' + hashes, i + 2 + len(hashes))
            end = n if end < 0 else end + 1 + len(hashes)
            out.append('""' + '\n' * text.count('\n', i, end))
            i = end
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == '\\' else 1
            out.append('""' + '\n' * text.count('\n', i, j))
            i = j + 1
        elif c == "'" and re.match(r"'(\\.|[^\\'])'", text[i:i + 4]) or (c == "'" and text.startswith("'\\u{", i)):
            j = text.find("'", i + 1 + (1 if text[i + 1] == '\\' else 0))
            out.append("' '")
            i = j + 1
        else:
            out.append(c)
            i += 1
    return ''.join(out)


def drop_test_blocks(code):
    """The code without inline `#[cfg(test)] mod name { ... }` blocks."""
    while True:
        m = re.search(r'#\[cfg\(test\)\]\s*(?:pub(?:\([^)]*\))?\s+)?mod\s+\w+\s*\{', code)
        if not m:
            return code
        depth, j = 1, m.end()
        while j < len(code) and depth:
            depth += {'{': 1, '}': -1}.get(code[j], 0)
            j += 1
        code = code[:m.start()] + '\n' * code.count('\n', m.start(), j) + code[j:]


def expand_use(tree):
    """`a::{b, c::{d, e as f}}` -> [['a','b'], ['a','c','d'], ['a','c','e']] (`*` kept as a segment)."""
    tree = re.sub(r'\s+', '', re.sub(r'\s+as\s+\w+', '', tree))
    out = []

    def walk(prefix, s):
        depth, start, parts = 0, 0, []
        for k, ch in enumerate(s):
            depth += {'{': 1, '}': -1}.get(ch, 0)
            if ch == ',' and depth == 0:
                parts.append(s[start:k])
                start = k + 1
        parts.append(s[start:])
        for p in filter(None, parts):
            b = p.find('{')
            if b >= 0:
                head = [x for x in p[:b].split('::') if x]
                walk(prefix + head, p[b + 1:p.rfind('}')])
            else:
                out.append(prefix + [x for x in p.split('::') if x])

    walk([], tree)
    return out


class Tree:
    def __init__(self, src):
        self.src = src
        self.modules = {}     # module path tuple -> file
        self.test_only = set()
        self.code = {}        # file -> code without comments/strings/test blocks
        self.reexports = {}   # module -> {name: absolute path}
        self.walk(src / 'lib.rs', ('crate',), src)
        main = src / 'main.rs'
        if main.exists():
            self.modules[('main',)] = main
            self.load(main)

    def load(self, f):
        self.code[f] = drop_test_blocks(strip_code(f.read_text()))

    def walk(self, f, path, dir_for_children, test=False):
        self.modules[path] = f
        if test:
            self.test_only.add(f)
        self.load(f)
        for m in MOD_DECL.finditer(self.code[f]):
            attrs, name = m.group(1), m.group(2)
            pm = re.search(r'#\[path\s*=\s*""\]', attrs)
            child_test = test or 'cfg(test)' in attrs
            if pm:
                # the path string was blanked; read it from the original text at the same place
                orig = f.read_text()
                pp = re.findall(r'#\[path\s*=\s*"([^"]+)"\]\s*(?:#\[[^\]]*\]\s*)*(?:pub(?:\([^)]*\))?\s+)?mod\s+'
                                + name + r'\s*;', orig)
                cf = f.parent / pp[0]
                self.walk(cf, path + (name,), cf.parent / cf.stem, child_test)
                continue
            for cf, cdir in ((dir_for_children / (name + '.rs'), dir_for_children / name),
                             (dir_for_children / name / 'mod.rs', dir_for_children / name)):
                if cf.exists():
                    self.walk(cf, path + (name,), cdir, child_test)
                    break

    def module_of(self, f):
        return next(p for p, g in self.modules.items() if g == f)

    def absolute(self, mod, segs):
        """A path as written in module `mod` -> absolute segments, or None for another crate."""
        if not segs:
            return None
        if segs[0] == 'flightid':
            return ['crate'] + segs[1:]
        if segs[0] == 'crate':
            return segs
        if segs[0] in ('self', 'super'):
            cur = list(mod)
            while segs and segs[0] in ('self', 'super'):
                if segs[0] == 'super':
                    cur = cur[:-1]
                segs = segs[1:]
            return cur + segs
        if tuple(mod) + (segs[0],) in self.modules:
            return list(mod) + segs
        return None

    def collect_reexports(self):
        for mod, f in self.modules.items():
            names = {}
            for m in re.finditer(r'pub(?:\([^)]*\))?\s+use\s+([^;]+);', self.code[f]):
                for segs in expand_use(m.group(1)):
                    a = self.absolute(mod, segs)
                    if a and segs[-1] != '*':
                        names[segs[-1]] = a
            self.reexports[mod] = names

    def resolve(self, segs, depth=0):
        """Absolute path -> the file holding the item (longest module prefix, re-exports followed)."""
        for k in range(len(segs), 0, -1):
            mod = tuple(segs[:k])
            if mod in self.modules:
                rest = segs[k:]
                if rest and depth < 8 and rest[0] in self.reexports.get(mod, {}):
                    target = self.reexports[mod][rest[0]]
                    if target != segs:
                        return self.resolve(target + rest[1:], depth + 1)
                return self.modules[mod]
        return None

    def imports(self, f):
        mod = self.module_of(f)
        code = self.code[f]
        paths = []
        for m in re.finditer(r'\buse\s+([^;]+);', code):
            paths += expand_use(m.group(1))
        for m in PATH_REF.finditer(code):
            paths.append(re.sub(r'\s+', '', m.group(1)).split('::'))
        # a child module named without a prefix: `child::f()` or `use child::X`
        children = {p[-1] for p in self.modules if p[:-1] == mod and len(p) == len(mod) + 1}
        for name in children:
            for m in re.finditer(r'(?<![\w:])' + name + r'\s*::\s*(\w+)', code):
                paths.append([name, m.group(1)])
        out = set()
        for segs in paths:
            segs = [s for s in segs if s != '*'] or segs
            a = self.absolute(mod, segs)
            if a:
                g = self.resolve(a)
                if g and g != f:
                    out.add(g)
        return out


def main():
    src = Path(sys.argv[1] if len(sys.argv) > 1 else 'src')
    t = Tree(src)
    t.collect_reexports()
    files = [f for f in t.modules.values() if f not in t.test_only]
    edges = {f: t.imports(f) - t.test_only for f in files}
    path_of = {f: t.module_of(f) for f in files}
    pairs, facade = [], []
    for a in files:
        for b in edges[a]:
            if a in edges.get(b, ()) and str(a) < str(b):
                pa, pb = path_of[a], path_of[b]
                nested = pa[:len(pb)] == pb or pb[:len(pa)] == pa
                (facade if nested else pairs).append((a, b))
    rel = lambda f: str(f.relative_to(src.parent)) if src.parent != Path('') else str(f)
    print(f'{len(pairs)} pairs of files that import each other ({len(files)} files, test modules left out)')
    for a, b in sorted(pairs):
        print(f'  {rel(a)} <-> {rel(b)}')
    print(f'{len(facade)} parent/child pairs (a module and a file it contains; the facade, not counted)')
    return 1 if pairs else 0


if __name__ == '__main__':
    sys.exit(main())
