#!/usr/bin/env python3
"""The shape of the code, checked: no file of a crate's `src/` over the line budget (code
before its first `#[cfg(test)]`) unless it is listed below with the reason it is one idea,
and no import circle between the files of a crate, nor between the dashboard's modules
(`web/src`, relative `import … from "./x"`, type-only imports included: a circle of types
is still a circle to read through).

Why a script of our own: `cargo-modules` and similar tools need a nightly or a download; what
is checked here is small and textual. A `use`, or a path written out in the code
(`crate::a::b::c`, `super::x`), makes an edge from the file that writes it to the file that
defines the module it names. A module's own `mod`/`pub use` lines do not count: re-exporting a
child is how a module shows its parts, not a dependency of the parent's logic. Nor do a
child's uses of its ancestors (see `without_ancestors`).

Run from the repository root: `python3 tests/structure.py`; exits 1 and says what is wrong.
"""

import re
import sys
from pathlib import Path

BUDGET = 600
# Files allowed past the budget: path -> why it is one idea.
ONE_IDEA: dict[str, str] = {}

USE_PATH = re.compile(r"\b(crate|super|self)((?:::\w+)+)")


def code_lines(text: str) -> list[str]:
    out = []
    for line in text.splitlines():
        if line.strip().startswith("#[cfg(test)]"):
            break
        out.append(line)
    return out


def module_files(src: Path) -> dict[tuple[str, ...], Path]:
    """Module path (relative to the crate root) -> the file that defines it."""
    mods = {}
    for f in src.rglob("*.rs"):
        rel = f.relative_to(src).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] in ("lib", "main") and len(parts) == 1:
            parts = []
        elif parts[-1] == "mod":
            parts = parts[:-1]
        mods[tuple(parts)] = f
    return mods


def strip_comments(text: str) -> str:
    text = re.sub(r"//[^\n]*", "", text)
    return re.sub(r"/\*.*?\*/", "", text, flags=re.S)


def edges_of(mod: tuple[str, ...], f: Path, mods: dict) -> set[Path]:
    text = strip_comments("\n".join(code_lines(f.read_text())))
    # Lines that only declare or re-export children are the module's table of contents.
    text = "\n".join(
        l for l in text.splitlines()
        if not re.match(r"\s*(pub(\(crate\))?\s+)?mod\s+\w+\s*;", l)
        and not re.match(r"\s*pub(\(crate\))?\s+use\s+(self::)?\w+::", l)
    )
    is_dir_mod = f.name in ("mod.rs", "lib.rs", "main.rs")
    out = set()
    # Expand `use a::{b, c::{d}}` groups into paths.
    for m in USE_PATH.finditer(text):
        root, rest = m.group(1), m.group(2).split("::")[1:]
        if root == "crate":
            base = []
        elif root == "self":
            base = list(mod) if is_dir_mod else list(mod)
        else:  # super
            base = list(mod)[:-1]
            while rest and rest[0] == "super":
                base = base[:-1]
                rest = rest[1:]
        path = base + rest
        # The longest prefix that is a module file.
        for n in range(len(path), -1, -1):
            target = mods.get(tuple(path[:n]))
            if target is not None:
                if target != f:
                    out.add(target)
                break
    # `use child::x` (a path relative to this module, edition 2018+): an edge to the child,
    # unless the line only re-exports it (filtered above).
    own = list(mod)
    for m in re.finditer(r"\buse\s+(\w+)((?:::\w+)*)", text):
        first = m.group(1)
        if first in ("crate", "super", "self", "std", "core", "alloc"):
            continue
        path = own + [first] + m.group(2).split("::")[1:]
        for n in range(len(path), len(own), -1):
            target = mods.get(tuple(path[:n]))
            if target is not None:
                if target != f:
                    out.add(target)
                break
    # Paths written inline through a child (`spiral::Spiral::new()`).
    for child in {k[len(own)] for k in mods if len(k) == len(own) + 1 and k[: len(own)] == tuple(own)}:
        if re.search(rf"(?<![\w:]){child}::\w", text):
            target = mods[tuple(own) + (child,)]
            if target != f:
                out.add(target)
    # `use crate::x::{a, b::c}`: the braces name modules too.
    for m in re.finditer(r"\buse\s+crate((?:::\w+)*)::\{([^;]*)\};", text, flags=re.S):
        base = m.group(1).split("::")[1:]
        for item in re.split(r"[,{}]", m.group(2)):
            item = item.strip().split(" as ")[0]
            if not item:
                continue
            path = base + item.split("::")
            for n in range(len(path), -1, -1):
                target = mods.get(tuple(path[:n]))
                if target is not None:
                    if target != f:
                        out.add(target)
                    break
    return out


def without_ancestors(mod: tuple[str, ...], edges: set[Path], mods: dict) -> set[Path]:
    """A child sees its ancestors' items by Rust's design (`super::`, a type whose `impl` is
    split over its module's files); only uses of siblings, descendants and unrelated modules
    can close a circle."""
    ancestors = {mods.get(mod[:n]) for n in range(len(mod))}
    return {e for e in edges if e not in ancestors}


def cycles(graph: dict[Path, set[Path]]) -> list[list[Path]]:
    """Strongly connected components with more than one file (Tarjan)."""
    index, low, stack, on, comps = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
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
            if len(comp) > 1:
                comps.append(sorted(comp))

    sys.setrecursionlimit(10_000)
    for v in graph:
        if v not in index:
            visit(v)
    return comps


# `import … from "./x"`, `export … from "../y"`, `import "./z"` and `import("./w")`: every
# relative specifier, whatever is imported (a type-only import ties two files as much).
TS_IMPORT = re.compile(
    r"""(?:\bfrom\s*|\bimport\s*\(?\s*)["'](\.{1,2}/[^"']+)["']"""
)
TS_EXTENSIONS = (".ts", ".tsx", ".mts")


def ts_target(f: Path, spec: str) -> Path | None:
    """The file a relative specifier of `f` names (`./x` → `x.ts`, `x/index.ts`)."""
    base = (f.parent / spec).resolve()
    candidates = [base] if base.suffix in TS_EXTENSIONS else []
    candidates += [base.with_name(base.name + e) for e in TS_EXTENSIONS]
    candidates += [base / f"index{e}" for e in TS_EXTENSIONS]
    return next((c for c in candidates if c.is_file()), None)


def ts_graph(src: Path) -> dict[Path, set[Path]]:
    """The relative imports between the TypeScript files under `src`."""
    graph = {}
    for f in sorted(p for e in TS_EXTENSIONS for p in src.rglob(f"*{e}")):
        f = f.resolve()
        text = re.sub(r"/\*.*?\*/", "", f.read_text(), flags=re.S)
        text = re.sub(r"^\s*//[^\n]*", "", text, flags=re.M)
        graph[f] = {t for s in TS_IMPORT.findall(text) if (t := ts_target(f, s)) and t != f}
    return graph


def main() -> int:
    root = Path(__file__).resolve().parent.parent
    problems = []
    for src in sorted(root.glob("crates/*/src")):
        mods = module_files(src)
        graph = {f: without_ancestors(m, edges_of(m, f, mods), mods) for m, f in mods.items()}
        for comp in cycles(graph):
            names = " ↔ ".join(str(p.relative_to(root)) for p in comp)
            problems.append(f"import circle: {names}")
        for f in mods.values():
            rel = str(f.relative_to(root))
            if f.name == "tests.rs":
                continue
            n = len(code_lines(f.read_text()))
            if n > BUDGET and rel not in ONE_IDEA:
                problems.append(f"{rel}: {n} lines of code (budget {BUDGET}): split it by idea")
    web = root / "web" / "src"
    for comp in cycles(ts_graph(web)) if web.is_dir() else []:
        names = " ↔ ".join(str(p.relative_to(root)) for p in comp)
        problems.append(f"import circle: {names}")
    for p in problems:
        print(p)
    if problems:
        print(f"structure: {len(problems)} problem(s)")
        return 1
    print("structure: every crate file within budget, no import circles (crates, web/src)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
