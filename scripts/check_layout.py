#!/usr/bin/env python3
"""Layout check for the workspace's Rust sources (Python 3 standard library only).

Scans `crates/*/src/**/*.rs` and reports, one line per violation as `path:line: message`:

  (a) files longer than --max-file-lines (default 600) lines, test modules included;
  (b) functions longer than --max-fn-lines (default 100) lines, counted from the line of the
      `fn` keyword to the line of the body's closing brace;
  (c) import cycles between the modules of each crate target (the library, the binary, each
      `src/bin/*` program), at any depth of the module tree.

The module graph of rule (c):

  * Nodes are the file modules, found by following `mod x;` declarations from the target's root
    file (`solver/mod.rs` is the module `solver`, `solver/gather.rs` is `solver::gather`).
    Inline `mod x { .. }` blocks are folded into the file that holds them.
  * Test code is not part of the graph: an item under `#[cfg(test)]` (an inline `mod tests {..}`,
    a `mod tests;` file and everything below it, a `use`) is skipped.
  * A reference is every path of a `use` declaration (groups `{..}` expanded) and every path in
    code that starts with `crate::`, `super::` or `self::`; a leading name that is a submodule of
    the current module counts too (`use gather::Gather;` in `solver/mod.rs`). It resolves to the
    deepest file module its segments name; when the next segment is a name that module itself
    imports (`pub use link_set::Link;` in `solver/mod.rs`, or a private `use`), the reference
    follows that import, so a re-export through a parent does not hide where the item lives.
    Paths into other crates are not followed.
  * A reference from module S to module T, neither an ancestor of the other, is an edge between
    the two *siblings* below their deepest common ancestor P that hold S and T: `solver::gather
    -> irradiance::sh` is the edge `solver -> irradiance` among the crate's top-level modules,
    `solver::gather -> solver::oracle` is `gather -> oracle` among the children of `solver`.
    A parent using its children, or a child using the items its ancestors define, is not an
    edge: a module and the modules inside it are one unit seen from outside.

  Rule: among the children of every module (and of the crate root), the sibling edges have no
  cycle. Each strongly connected component of more than one sibling is reported, with one place
  for each of its edges. So a solver built as stages (kernels <- oracle <- link <- storage <-
  gather <- solver) passes, whether or not its `mod.rs` re-exports the stages' types, while two
  stages that import each other, directly or through a re-export or a ring of others, fail.

Comments, string and character literals are blanked before anything is parsed, so braces, `fn`
and paths inside them do not count. Exits 1 if there is any violation, 0 otherwise.
`--self-test` checks the checker on small inline crates.
"""

import argparse
import re
import sys
import tempfile
from pathlib import Path

IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
KEYWORD_ROOTS = ("crate", "super", "self")


def blank(text):
    """`text` with comments and the contents of string/char literals replaced by spaces
    (newlines kept, so offsets and line numbers stay valid). Quotes stay, as `""`."""
    out = list(text)
    n = len(text)
    i = 0

    def wipe(a, b):
        for k in range(a, b):
            if out[k] != "\n":
                out[k] = " "

    while i < n:
        c = text[i]
        prev = text[i - 1] if i > 0 else ""
        if c == "/" and text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            wipe(i, j)
            i = j
        elif c == "/" and text.startswith("/*", i):
            # Block comments nest in Rust.
            depth, j = 1, i + 2
            while j < n and depth:
                if text.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif text.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            wipe(i, j)
            i = j
        elif c in "rbc" and not (prev.isalnum() or prev == "_"):
            # Raw strings r"..", r#".."#, br"..", cr"..", and prefixed b"..", c"..", b'..'.
            m = re.compile(r'(?:b|c)?r(#*)"').match(text, i)
            if m:
                close = '"' + m.group(1)
                j = text.find(close, m.end())
                j = n if j < 0 else j + len(close)
                wipe(m.end(), j - len(close))
                i = j
            elif c in "bc" and i + 1 < n and text[i + 1] in "\"'":
                i += 1  # the literal itself is handled on the next iteration
            else:
                i += 1
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            wipe(i + 1, min(j, n))
            i = j + 1
        elif c == "'":
            # A char literal ('x', '\n', '\u{..}', '\'') or a lifetime / label ('a, 'static).
            if i + 1 < n and text[i + 1] == "\\":
                # The escaped character may itself be a quote: `'\''`.
                j = i + 3
                while j < n and text[j] != "'":
                    j += 1
                wipe(i + 1, min(j, n))
                i = j + 1
            elif i + 2 < n and text[i + 2] == "'":
                wipe(i + 1, i + 2)
                i += 3
            else:
                i += 1
        else:
            i += 1
    return "".join(out)


def line_starts(text):
    return [0] + [k + 1 for k, ch in enumerate(text) if ch == "\n"]


def line_of(starts, offset):
    """1-based line number of `offset`, given the offsets where lines start."""
    lo, hi = 0, len(starts)
    while lo + 1 < hi:
        mid = (lo + hi) // 2
        if starts[mid] <= offset:
            lo = mid
        else:
            hi = mid
    return lo + 1


def body_end(code, j):
    """From offset `j`, the end of an item: the offset just past the first `;` outside
    brackets, or past the `}` matching the first `{`."""
    depth = 0
    while j < len(code):
        ch = code[j]
        if ch in "([":
            depth += 1
        elif ch in ")]":
            depth -= 1
        elif depth == 0 and ch == ";":
            return j + 1
        elif depth == 0 and ch == "{":
            braces = 0
            while j < len(code):
                if code[j] == "{":
                    braces += 1
                elif code[j] == "}":
                    braces -= 1
                    if braces == 0:
                        return j + 1
                j += 1
            return j
        j += 1
    return j


def functions(code):
    """`(name, start offset, end offset)` of every `fn` item with a body in blanked `code`."""
    found = []
    for m in re.finditer(r"\bfn\s+(?:r#)?([A-Za-z_][A-Za-z0-9_]*)", code):
        # The body starts at the first `{` outside parentheses and brackets (`[u8; 4]` holds a
        # `;`); a `;` there first means a declaration without a body.
        depth, j = 0, m.end()
        while j < len(code):
            ch = code[j]
            if ch in "([":
                depth += 1
            elif ch in ")]":
                depth -= 1
            elif depth == 0 and ch in "{;":
                break
            j += 1
        if j >= len(code) or code[j] == ";":
            continue
        found.append((m.group(1), m.start(), body_end(code, j) - 1))
    return found


# ---------------------------------------------------------------------------------------------
# The module graph.

CFG_TEST = re.compile(r"#\s*\[\s*cfg\s*\(\s*(?:all\s*\(\s*)?test\b[^\]]*\]")
ATTR = re.compile(r"\s*#\s*\[[^\]]*\]")


def strip_tests(code):
    """Blanked `code` with every item under `#[cfg(test)]` blanked too, and the names of the
    file modules (`mod x;`) so removed."""
    out = list(code)
    removed = set()
    for m in CFG_TEST.finditer(code):
        j = m.end()
        while True:  # further attributes on the same item
            a = ATTR.match(code, j)
            if not a:
                break
            j = a.end()
        end = body_end(code, j)
        decl = re.match(r"\s*(?:pub(?:\s*\([^)]*\))?\s+)?mod\s+([A-Za-z_]\w*)\s*;", code[j:end])
        if decl:
            removed.add(decl.group(1))
        for k in range(m.start(), end):
            if out[k] != "\n":
                out[k] = " "
    return "".join(out), removed


def inline_modules(code):
    """`(name, body start, body end)` of each inline `mod x { .. }` block."""
    found = []
    for m in re.finditer(r"(?<![A-Za-z0-9_])mod\s+([A-Za-z_]\w*)\s*\{", code):
        found.append((m.group(1), m.end() - 1, body_end(code, m.end() - 1)))
    return found


def tokenize_use(code, a, b):
    """Tokens `(text, offset)` of a use tree in `code[a:b]`."""
    return [(t.group(0), t.start()) for t in re.finditer(r"::|[A-Za-z_]\w*|[{},*]", code[:b]) if t.start() >= a]


def parse_use_tree(tokens, i, prefix):
    """Expand the use tree at `tokens[i]` below `prefix`: a list of `(segments, alias, offset)`
    and the index after the tree."""
    segs, off = list(prefix), None
    while i < len(tokens):
        t, pos = tokens[i]
        if t == "{":
            out, i = [], i + 1
            while i < len(tokens) and tokens[i][0] != "}":
                sub, i = parse_use_tree(tokens, i, segs)
                out.extend(sub)
                if i < len(tokens) and tokens[i][0] == ",":
                    i += 1
            return out, i + 1
        if t == "*":
            return [(segs + ["*"], None, pos if off is None else off)], i + 1
        if IDENT.fullmatch(t) and t != "as":
            segs.append(t)
            off = pos if off is None else off
            i += 1
            if i < len(tokens) and tokens[i][0] == "::":
                i += 1
                continue
        break
    alias = None
    if i + 1 < len(tokens) and tokens[i][0] == "as":
        alias, i = tokens[i + 1][0], i + 2
    return [(segs, alias, off)], i


def use_declarations(code, spans=None):
    """Each path a `use` declaration in blanked `code` names: `(segments, alias, offset)`; the
    declarations' `(start, end)` are appended to `spans` if given."""
    out = []
    for m in re.finditer(r"(?<![A-Za-z0-9_])use\s+(?!<)", code):
        end = code.find(";", m.end())
        if end < 0:
            continue
        if spans is not None:
            spans.append((m.start(), end))
        if code.startswith("$", m.end()):
            continue  # `use $crate::..` in a macro: the crate that expands it
        tokens = tokenize_use(code, m.end(), end)
        if tokens and tokens[0][0] == "::":
            continue  # `use ::ext::..`: another crate
        trees, _ = parse_use_tree(tokens, 0, [])
        out.extend(t for t in trees if t[0] and t[2] is not None)
    return out


def code_paths(code):
    """Paths in blanked `code` that start with `crate`, `super` or `self`: `(segments, offset)`."""
    out = []
    pat = r"(?<![A-Za-z0-9_:$#])(?:crate|super|self)(?:\s*::\s*[A-Za-z_]\w*)+"
    for m in re.finditer(pat, code):
        out.append((re.findall(r"[A-Za-z_]\w*", m.group(0)), m.start()))
    return out


class Module:
    def __init__(self, path, rel, modpath, code):
        self.path, self.rel, self.modpath, self.code = path, rel, tuple(modpath), code
        self.children = set()
        self.imports = {}  # name -> absolute segments
        self.globs = []  # absolute segments of glob imports
        self.defines = set(re.findall(r"\b(?:fn|struct|enum|trait|type|const|static|union)\s+([A-Za-z_]\w*)", code))
        self.refs = []  # (absolute segments, offset)
        self.starts = None


def build_tree(src, root_file, root):
    """The file modules of the target whose root is `root_file`: modpath -> Module."""
    mods = {}

    def load(path, modpath, child_dir):
        text = path.read_text(encoding="utf-8")
        code, tests = strip_tests(blank(text))
        mod = Module(path, path.relative_to(root), modpath, code)
        mod.starts = line_starts(text)
        mods[tuple(modpath)] = mod
        for m in re.finditer(r"(?<![A-Za-z0-9_])mod\s+([A-Za-z_]\w*)\s*;", code):
            name = m.group(1)
            if name in tests:
                continue
            for cand in (child_dir / f"{name}.rs", child_dir / name / "mod.rs"):
                if cand.exists():
                    sub_dir = cand.parent if cand.name == "mod.rs" else child_dir / name
                    mod.children.add(name)
                    load(cand, modpath + [name], sub_dir)
                    break

    load(root_file, [], root_file.parent if root_file.name in ("lib.rs", "main.rs", "mod.rs") else root_file.parent / root_file.stem)
    return mods


def absolute(mods, mod, inline, segs):
    """`segs`, written in `mod` inside the inline modules `inline`, as an absolute path from the
    crate root, or None for a path into another crate."""
    here = list(mod.modpath) + list(inline)
    first = segs[0]
    if first == "crate":
        return segs[1:]
    if first in ("super", "self"):
        base, k = here, 0
        while k < len(segs) and segs[k] in ("super", "self"):
            if segs[k] == "super":
                if not base:
                    return None
                base = base[:-1]
            k += 1
        return base + segs[k:]
    if not inline and first in mod.children:
        return here + segs
    return None


def collect(mods):
    """Fill each module's imports and references."""
    for mod in mods.values():
        blocks = inline_modules(mod.code)

        def inline_at(off):
            return [name for name, a, b in blocks if a < off < b]

        spans = []
        for segs, alias, off in use_declarations(mod.code, spans):
            inline = inline_at(off)
            abs_segs = absolute(mods, mod, inline, segs)
            if abs_segs is None:
                continue
            if abs_segs and abs_segs[-1] == "self":
                abs_segs = abs_segs[:-1]
            mod.refs.append((abs_segs, off))
            if inline:
                continue
            if abs_segs and abs_segs[-1] == "*":
                mod.globs.append(abs_segs[:-1])
            elif abs_segs:
                mod.imports[alias or abs_segs[-1]] = abs_segs
        rest = list(mod.code)
        for a, b in spans:
            rest[a:b] = [" "] * (b - a)
        for segs, off in code_paths("".join(rest)):
            abs_segs = absolute(mods, mod, inline_at(off), segs)
            if abs_segs is not None:
                mod.refs.append((abs_segs, off))


def resolve(mods, segs, depth=0):
    """The file module an absolute path lives in, following imports of the deepest module it
    names (re-exports), or None."""
    k = 0
    while k < len(segs) and tuple(segs[: k + 1]) in mods:
        k += 1
    node = tuple(segs[:k])
    if node not in mods:
        return None
    mod = mods[node]
    if depth < 16 and k < len(segs):
        name = segs[k]
        if name in mod.imports and name not in mod.defines:
            target = resolve(mods, mod.imports[name] + segs[k + 1 :], depth + 1)
            return target if target is not None else node
        if name not in mod.defines:
            for glob in mod.globs:
                gm = resolve(mods, glob, depth + 1)
                if gm is not None and gm != node:
                    g = mods[gm]
                    if name in g.defines or name in g.imports or tuple(list(gm) + [name]) in mods:
                        return resolve(mods, list(gm) + segs[k:], depth + 1)
    return node


def sibling_graphs(mods):
    """For each parent module: {child: {child: (path, line)}} of the sibling edges below it."""
    graphs = {}
    for mod in mods.values():
        src = mod.modpath
        for segs, off in mod.refs:
            dst = resolve(mods, segs)
            if dst is None or dst == src:
                continue
            n = 0
            while n < min(len(src), len(dst)) and src[n] == dst[n]:
                n += 1
            if n == len(src) or n == len(dst):
                continue  # one holds the other
            parent, a, b = src[:n], src[n], dst[n]
            edges = graphs.setdefault(parent, {}).setdefault(a, {})
            if b not in edges:
                edges[b] = (mod.rel, line_of(mod.starts, off))
    return graphs


def strongly_connected(graph):
    """Tarjan's strongly connected components of `graph` (node -> iterable of nodes)."""
    index, low, on, stack, out = {}, {}, set(), [], []
    counter = [0]
    sys.setrecursionlimit(max(10000, sys.getrecursionlimit()))

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def cycles(crate_name, target, mods):
    """Violations `(path, line, message)` for the import cycles of one target."""
    collect(mods)
    found = []
    for parent, graph in sorted(sibling_graphs(mods).items()):
        where = "::".join(parent) if parent else "the crate root"
        for comp in strongly_connected(graph):
            if len(comp) < 2:
                continue
            members = set(comp)
            edges = sorted((a, b) for a in comp for b in graph.get(a, {}) if b in members)
            first = graph[edges[0][0]][edges[0][1]]
            msg = f"import cycle in {crate_name} ({target}) among the children of {where}: {', '.join(comp)}"
            found.append((first[0], first[1], msg))
            for a, b in edges:
                p, ln = graph[a][b]
                found.append((p, ln, f"  {a} -> {b}"))
    return found


def targets(src):
    """`(label, root file)` of each target with its own module tree."""
    out = [(name, src / name) for name in ("lib.rs", "main.rs") if (src / name).exists()]
    bins = src / "bin"
    if bins.is_dir():
        for p in sorted(bins.iterdir()):
            if p.suffix == ".rs":
                out.append((f"bin/{p.name}", p))
            elif (p / "main.rs").exists():
                out.append((f"bin/{p.name}", p / "main.rs"))
    return out


def check_crate(crate, root, max_file, max_fn):
    """The violations in one crate directory, as `(path, line, message)`."""
    src = crate / "src"
    found = []
    for path in sorted(src.rglob("*.rs")):
        text = path.read_text(encoding="utf-8")
        rel = path.relative_to(root)
        lines = text.count("\n") + (0 if text.endswith("\n") or not text else 1)
        if lines > max_file:
            found.append((rel, 1, f"file has {lines} lines (limit {max_file})"))
        starts = line_starts(text)
        for name, a, b in functions(blank(text)):
            la, lb = line_of(starts, a), line_of(starts, b)
            if lb - la + 1 > max_fn:
                found.append((rel, la, f"fn {name} has {lb - la + 1} lines (limit {max_fn})"))
    for label, root_file in targets(src):
        found.extend(cycles(crate.name, label, build_tree(src, root_file, root)))
    return found


# ---------------------------------------------------------------------------------------------
# Self-test on small inline crates.

SELF_TESTS = [
    # (name, {file: text}, expected substrings of the report, one per violation; [] = clean)
    (
        "sibling cycle through use and a qualified path",
        {
            "lib.rs": "mod a;\nmod b;\n",
            "a.rs": "use crate::b::Y;\npub struct X;\n",
            "b.rs": "pub struct Y;\nfn f() -> super::a::X { super::a::X }\n",
        },
        ["among the children of the crate root: a, b"],
    ),
    (
        "parent uses its children, children use their parent: no cycle",
        {
            "lib.rs": "mod s;\n",
            "s/mod.rs": "mod x;\nmod y;\npub use x::X;\npub struct P;\nfn f() { let _ = self::y::Y; }\n",
            "s/x.rs": "use super::P;\npub struct X;\n",
            "s/y.rs": "use super::X;\npub struct Y;\nfn g() -> crate::s::P { super::P }\n",
        },
        [],
    ),
    (
        "a cycle hidden behind a parent's re-export is found",
        {
            "lib.rs": "mod s;\n",
            "s/mod.rs": "mod x;\nmod y;\npub use self::y::{Y, Z as W};\n",
            "s/x.rs": "use super::W;\npub struct X;\n",
            "s/y.rs": "pub struct Y;\npub struct Z;\nfn g() -> super::x::X { todo!() }\n",
        },
        ["among the children of s: x, y"],
    ),
    (
        "test modules, comments and strings are not edges",
        {
            "lib.rs": "mod a;\nmod b;\n#[cfg(test)]\nmod tests;\n",
            "a.rs": "use crate::b::Y;\npub struct X;\n",
            "b.rs": (
                "pub struct Y; // crate::a::X\nconst S: &str = \"crate::a::X\";\n"
                "#[cfg(test)]\nmod tests {\n    use crate::a::X;\n}\n"
                "#[cfg(test)]\nuse crate::a::X;\n"
            ),
            "tests.rs": "use crate::a::X;\nuse crate::b::Y;\n",
        },
        [],
    ),
    (
        "deep modules lift to their top-level siblings",
        {
            "lib.rs": "pub mod p;\npub mod q;\n",
            "p/mod.rs": "pub mod deep;\n",
            "p/deep.rs": "pub fn f() { crate::q::r::g() }\n",
            "q/mod.rs": "pub mod r;\npub mod s;\n",
            "q/r.rs": "pub fn g() {}\n",
            "q/s.rs": "use crate::p::deep::f;\n",
        },
        ["among the children of the crate root: p, q"],
    ),
    (
        "a ring of three stages and a clean chain beside it",
        {
            "lib.rs": "mod s;\nmod t;\n",
            "s/mod.rs": "mod a;\nmod b;\nmod c;\n",
            "s/a.rs": "use super::b::B;\npub struct A;\n",
            "s/b.rs": "use super::c::C;\npub struct B;\n",
            "s/c.rs": "use super::{a::A, b};\npub struct C;\n",
            "t/mod.rs": "mod a;\nmod b;\nmod c;\n",
            "t/a.rs": "pub struct A;\n",
            "t/b.rs": "use super::a::A;\npub struct B;\n",
            "t/c.rs": "use super::{a::A, b::B};\nuse crate::s::a;\n",
        },
        ["among the children of s: a, b, c"],
    ),
    (
        "inline modules fold into their file",
        {
            "lib.rs": "mod a;\nmod b;\n",
            "a.rs": "pub struct X;\nmod inner {\n    use super::super::b::Y;\n}\n",
            "b.rs": "pub struct Y;\nuse crate::a::X;\n",
        },
        ["among the children of the crate root: a, b"],
    ),
    (
        "file and function limits",
        {
            "lib.rs": "fn ok() {\n" + "    let _ = 1;\n" * 98 + "}\n" + "fn long() {\n" + "    let _ = 1;\n" * 99 + "}\n" + "\n" * 400,
        },
        ["fn long has 101 lines", "file has 601 lines"],
    ),
]


def self_test():
    """Run SELF_TESTS; print each failure and return the exit status."""
    failed = 0
    for name, files, expected in SELF_TESTS:
        with tempfile.TemporaryDirectory() as tmp:
            root = Path(tmp)
            for rel, text in files.items():
                p = root / "crates" / "demo" / "src" / rel
                p.parent.mkdir(parents=True, exist_ok=True)
                p.write_text(text, encoding="utf-8")
            report = check_crate(root / "crates" / "demo", root, 600, 100)
        heads = [msg for _, _, msg in report if not msg.startswith("  ")]
        ok = len(heads) == len(expected) and all(any(e in h for h in heads) for e in expected)
        if not ok:
            failed += 1
            print(f"FAIL {name}: expected {expected}, got:")
            for p, ln, msg in report:
                print(f"    {p}:{ln}: {msg}")
        else:
            print(f"ok   {name}")
    print(f"{len(SELF_TESTS) - failed}/{len(SELF_TESTS)} self-tests pass", file=sys.stderr)
    return 1 if failed else 0


def main():
    ap = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], epilog=__doc__.split("\n\n", 1)[1],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ap.add_argument("--root", type=Path, default=Path(__file__).resolve().parent.parent,
                    help="the workspace root (default: this script's parent's parent)")
    ap.add_argument("--max-file-lines", type=int, default=600)
    ap.add_argument("--max-fn-lines", type=int, default=100)
    ap.add_argument("--self-test", action="store_true", help="check the checker and exit")
    ap.add_argument("crates", nargs="*", help="crate directories under crates/ (default: all)")
    args = ap.parse_args()
    if args.self_test:
        return self_test()
    root = args.root.resolve()
    names = args.crates or sorted(p.name for p in (root / "crates").iterdir() if (p / "src").is_dir())
    total = 0
    for name in names:
        crate = root / "crates" / name
        if not (crate / "src").is_dir():
            print(f"{crate}: no src directory", file=sys.stderr)
            return 2
        for path, line, msg in check_crate(crate, root, args.max_file_lines, args.max_fn_lines):
            print(f"{path}:{line}: {msg}")
            if not msg.startswith("  "):
                total += 1
    print(f"{total} layout violation(s)" if total else "layout ok", file=sys.stderr)
    return 1 if total else 0


if __name__ == "__main__":
    sys.exit(main())
