#!/usr/bin/env python3
"""Holds the code to its layer chart. The link graph in the CMakeLists.txt files under daemon/,
codecs/, adapters/ and cli/ is the one statement of the layers; this reads it, it does not repeat
it, and rejects:

  - an include that goes up or sideways: a file under daemon/, codecs/, adapters/ (their tests
    aside) or cli/ may include only headers of its own library and of the libraries that library
    links, directly or through others; an adapter no header under daemon/ at all (a plugin knows
    the daemon through include/drivegate, and shares only codecs/ with it);
  - a southbound library that reaches a northbound server: nothing the bus, its transports or the
    gateway link, directly or through others, may be the Modbus, HTTP or MQTT side (or what sits
    on them), which sit above the gateway;
  - a source file listed in two libraries (it would be compiled, and its globals made, twice).

A header belongs to the library that lists it among its sources (how an interface library names
its headers), else to the one that compiles the source of the same name, else to the first
library defined in its folder; include/drivegate/ is drivegate_api's. Run by ctest
(Layers.IncludesFollowTheLinks) on this tree, and (Layers.CheckRejects*) on a small tree of one
violation of each kind, tests/layers/violations, given as the argument; prints each violation,
and exits 1 if there is one.
"""
import pathlib
import re
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
# Where the code lives, each also a root its headers are included from ("config/config.h").
TREES = ("daemon", "codecs", "adapters", "cli")
INCLUDE_ROOTS = ("daemon", "codecs", "adapters", "include")
# The northbound side: daemon/ folders whose libraries serve clients (and what wires them).
NORTH_FOLDERS = ("modbus", "http", "mqtt", "status", "app")
# Libraries in those folders that hold no server: pure protocol, or an interface, which a layer
# below may use.
NORTH_PURE = {
    "dg_sparkplug": "Sparkplug B's topics and payloads: pure, no I/O",
    "dg_modbus_api": "what the Modbus server asks of a backend: one header",
}
# The southbound side: the line and the devices on it.
SOUTH_FOLDERS = ("transport", "bus", "gateway")

CALL = re.compile(
    r"\b(add_library|add_executable|target_sources|target_link_libraries|drivegate_add_adapter)"
    r"\s*\(([^)]*)\)", re.S)
INCLUDE = re.compile(r'^\s*#\s*include\s+"([A-Za-z0-9_./-]+)"', re.M)
KEYWORDS = {"STATIC", "SHARED", "MODULE", "OBJECT", "INTERFACE", "PUBLIC", "PRIVATE"}
SOURCE = (".cpp", ".h", ".proto")


def cmake_files():
    for tree in TREES:
        for cmake in sorted((ROOT / tree).rglob("CMakeLists.txt")):
            if "tests" not in cmake.relative_to(ROOT).parts:
                yield cmake


def read_graph():
    """{target: {dependency: visibility}}, {source path relative to ROOT: target}, [errors],
    {target: the folder of its first source}."""
    links = {"drivegate_api": {}}
    sources, errors, folders = {}, [], {"drivegate_api": "include/drivegate"}

    def add_source(target, folder, src):
        if not src.endswith(SOURCE) or "$" in src:
            return
        path = (folder / src).as_posix()
        folders.setdefault(target, pathlib.PurePosixPath(path).parent.as_posix())
        if path in sources and sources[path] != target:
            errors.append(f"{path} is listed in {sources[path]} and in {target}: a source belongs "
                          "to one library")
            return
        sources[path] = target

    for cmake in cmake_files():
        folder = cmake.parent.relative_to(ROOT)
        text = re.sub(r"#[^\n]*", "", cmake.read_text())
        for kind, args in CALL.findall(text):
            words = [w.strip('"') for w in args.split()]
            if kind == "drivegate_add_adapter":
                adapter_id, rest = words[0], words[1:]
                lib = "dg_" + adapter_id.replace("-", "_")
                if "LIBRARY" in rest:
                    lib = rest[rest.index("LIBRARY") + 1]
                plugin = "drivegate-" + adapter_id
                links.setdefault(lib, {})["drivegate_api"] = "PUBLIC"
                links.setdefault(plugin, {})[lib] = "PRIVATE"
                target = lib
                for w in rest:
                    if w in ("SOURCES", "LIBRARY"):
                        target = lib
                    elif w == "PLUGIN":
                        target = plugin
                    else:
                        add_source(target, folder, w)
                continue
            name, rest = words[0], [w for w in words[1:] if w not in KEYWORDS]
            deps = links.setdefault(name, {})
            if kind in ("add_library", "add_executable", "target_sources"):
                for src in rest:
                    add_source(name, folder, src)
                continue
            visibility = "PUBLIC"
            for w in words[1:]:
                if w in ("PUBLIC", "PRIVATE", "INTERFACE"):
                    visibility = w
                elif w.startswith(("dg_", "drivegate_api", "drivegate-")):
                    deps[w] = visibility
    return links, sources, errors, folders


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


def reach(links, lib):
    """Every library `lib` links into its program, whatever the visibility: {library: path}."""
    paths = {lib: [lib]}
    todo = [lib]
    while todo:
        cur = todo.pop()
        for dep in links.get(cur, {}):
            if dep not in paths:
                paths[dep] = paths[cur] + [dep]
                todo.append(dep)
    del paths[lib]
    return paths


def owner(path, sources):
    """The library a file (path relative to ROOT) belongs to, or None (not built)."""
    if path.startswith("include/drivegate/"):
        return "drivegate_api"
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


def resolve(including, inc):
    """The file an include names, relative to ROOT, as the compiler finds it: beside the file
    that includes it, else under one of the include roots; None for anything else (system
    headers in quotes, generated files)."""
    for base in [including.parent] + [ROOT / r for r in INCLUDE_ROOTS]:
        candidate = base / inc
        if candidate.is_file():
            return candidate.resolve().relative_to(ROOT).as_posix()
    return None


def code_files():
    for tree in TREES:
        for f in sorted((ROOT / tree).rglob("*")):
            rel = f.relative_to(ROOT)
            if f.suffix in (".h", ".cpp") and "tests" not in rel.parts:
                yield f, rel.as_posix()


def wrong_includes(links, sources):
    wrong = []
    for f, rel in code_files():
        lib = owner(rel, sources)
        if lib is None:
            continue
        allowed = usable(links, lib) | {lib}
        for inc in INCLUDE.findall(f.read_text()):
            target_path = resolve(f, inc)
            if target_path is None:
                continue
            if rel.startswith("adapters/") and target_path.startswith("daemon/"):
                wrong.append(f"{rel} ({lib}) includes {inc}, a daemon header: an adapter knows "
                             "the daemon only through include/drivegate (and codecs/)")
                continue
            target = owner(target_path, sources)
            if target is not None and target not in allowed:
                wrong.append(f"{rel} ({lib}) includes {inc} ({target}), which {lib} does not "
                             "link")
    return wrong


def south_reaching_north(links, folders):
    def in_folders(lib, names):
        return any(folders.get(lib, "") == "daemon/" + n for n in names)

    north = {lib for lib in links if in_folders(lib, NORTH_FOLDERS) and lib not in NORTH_PURE}
    south = {lib for lib in links if in_folders(lib, SOUTH_FOLDERS)}
    wrong = []
    for lib in sorted(south):
        for dep, path in sorted(reach(links, lib).items()):
            if dep in north:
                wrong.append(f"{lib} (southbound) reaches {dep} (northbound): "
                             f"{' -> '.join(path)}")
    return wrong


def main():
    global ROOT
    if len(sys.argv) > 1:
        ROOT = pathlib.Path(sys.argv[1]).resolve()
    links, sources, errors, folders = read_graph()
    wrong = errors + south_reaching_north(links, folders) + wrong_includes(links, sources)
    for w in wrong:
        print(w)
    if not wrong:
        print(f"{len(links)} targets under {', '.join(TREES)}: every include follows the links, "
              "no southbound library reaches a northbound one, no source is in two libraries")
    return 1 if wrong else 0


if __name__ == "__main__":
    sys.exit(main())
