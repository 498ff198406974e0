#!/usr/bin/env python3
"""Holds daemon/ to its layer chart: a file may include only headers of its own library and of the
libraries that library links, directly or through others (the link graph in the CMakeLists.txt
files under daemon/ is the one statement of the layers; this reads it, it does not repeat it).

A header belongs to the library that lists it among its sources (how an interface library names
its headers), else to the one that compiles the source of the same name, else to the first
library defined in its folder. Run by ctest (Layers.IncludesFollowTheLinks);
prints each include that goes up or sideways, and exits 1 if there is one.
"""
import pathlib
import re
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
DAEMON = ROOT / "daemon"

CALL = re.compile(r"\b(add_library|target_link_libraries)\s*\(([^)]*)\)", re.S)
INCLUDE = re.compile(r'^\s*#\s*include\s+"([a-z_]+/[A-Za-z0-9_./]+)"', re.M)
KEYWORDS = {"STATIC", "SHARED", "MODULE", "OBJECT"}


def read_graph():
    """{library: {dependency: visibility}}, {source path relative to daemon/: library}."""
    links, sources = {}, {}
    for cmake in sorted(DAEMON.rglob("CMakeLists.txt")):
        folder = cmake.parent.relative_to(DAEMON)
        text = re.sub(r"#[^\n]*", "", cmake.read_text())
        for kind, args in CALL.findall(text):
            words = [w for w in args.split() if w not in KEYWORDS]
            name, rest = words[0], words[1:]
            deps = links.setdefault(name, {})
            if kind == "add_library":
                for src in rest:
                    if src.endswith((".cpp", ".h", ".proto")) and "$" not in src:
                        sources[str((folder / src).as_posix()).lstrip("./")] = name
                continue
            visibility = "PUBLIC"
            for w in rest:
                if w in ("PUBLIC", "PRIVATE", "INTERFACE"):
                    visibility = w
                elif w.startswith(("dg_", "drivegate_api")):
                    deps[w] = visibility
    return links, sources


def usable(links, lib):
    """What `lib`'s files may include: what it links itself, and what those pass on (PUBLIC or
    INTERFACE), as CMake passes on include directories."""
    seen = set(links.get(lib, {}))
    todo = list(seen)
    while todo:
        for dep, visibility in links.get(todo.pop(), {}).items():
            if visibility != "PRIVATE" and dep not in seen:
                seen.add(dep)
                todo.append(dep)
    return seen


def owner(path, sources):
    """The library a file under daemon/ (relative path) belongs to, or None (daemon's main)."""
    if path in sources:
        return sources[path]
    stem = str(pathlib.PurePosixPath(path).with_suffix(""))
    for ext in (".cpp", ".proto"):
        if stem + ext in sources:
            return sources[stem + ext]
    folder = str(pathlib.PurePosixPath(path).parent)
    in_folder = [lib for src, lib in sources.items()
                 if str(pathlib.PurePosixPath(src).parent) == folder and not src.endswith(".h")]
    return in_folder[0] if in_folder else None


def main():
    links, sources = read_graph()
    wrong = []
    for f in sorted(DAEMON.rglob("*")):
        if f.suffix not in (".h", ".cpp") or f.parent == DAEMON:
            continue
        rel = f.relative_to(DAEMON).as_posix()
        lib = owner(rel, sources)
        if lib is None:
            continue
        allowed = usable(links, lib) | {lib}
        for inc in INCLUDE.findall(f.read_text()):
            if not (DAEMON / inc).exists():
                continue  # drivegate/..., generated files, system headers in quotes
            target = owner(inc, sources)
            if target is not None and target not in allowed:
                wrong.append(f"daemon/{rel} ({lib}) includes {inc} ({target}), which {lib} "
                             "does not link")
    for w in wrong:
        print(w)
    if not wrong:
        print(f"{len(links)} libraries: every include under daemon/ follows the links")
    return 1 if wrong else 0


if __name__ == "__main__":
    sys.exit(main())
